"""A simulated character 仿真角色 beside its captured clip, drawn while it is simulated.

:class:`SimulationView` shows, in one :class:`~course.viz.scene.SkeletonScene`, the clip
(faint, a :data:`~course.viz.scene.GHOST`) and the character that
:func:`course.physics.character.track` simulates to follow it, side by side. Sliders set
``kp``, ``kd``, the step ``h`` and a push; a change re-runs a short simulation. The
simulation runs on a worker thread and hands over each clip frame as it is simulated
(``track(..., on_frame=...)``); the kernel's loop draws the newest one at most
``display_fps`` times a second, so the picture moves while the simulation runs and the
notebook never blocks. ``blocking=True`` simulates in the caller's thread and draws each
frame as it arrives (for code and tests: no running kernel loop needed).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

import ipywidgets as widgets
import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .panel import Control, fixed_height, on_value, readout_box, slider_style
from .scene import GHOST, SkeletonScene

#: sub-steps per clip frame the step menu offers, kept where the step is 1/2400 .. 1/60 s:
#: only steps that divide the frame (the simulation refuses any other), e.g. 1/120 .. 1/2400 s
#: for a 120 fps clip, 1/60 .. 1/1200 s for a 60 fps one
SUBSTEPS = (1, 2, 4, 5, 10, 20)
STEP_RANGE = (1 / 2400, 1 / 60)  # s
WINDOW = (640, 420)  # px: the 3D view


def steps(frame_time: float) -> list[float]:
    """The steps (s) the menu offers for a clip of ``frame_time`` s a frame: ``frame_time / n``
    for ``n`` in :data:`SUBSTEPS`, within :data:`STEP_RANGE`, coarsest first."""
    lo, hi = STEP_RANGE[0] * (1 - 1e-9), STEP_RANGE[1] * (1 + 1e-9)
    return [frame_time / n for n in SUBSTEPS if lo <= frame_time / n <= hi]


def step_label(h: float) -> str:
    """``h`` as a student reads it, "1/600 s" (a CMU frame of 0.008333 s makes 1/600.002)."""
    return f"1/{1 / h:.4g} s"


class _Stopped(Exception):
    """Raised inside ``on_frame`` to end a simulation whose settings changed."""


class SimulationView(Control):
    """Simulate ``character`` tracking ``clip`` and draw it beside the clip while it runs.

    Parameters
    ----------
    character : :class:`~course.physics.character.Character`
    clip : :class:`~course.motion.Motion`, the clip to follow (``n_frames`` of it are run).
    kp, kd : the starting gains (N m/rad, N m s/rad).
    h : the starting step (s), one of :func:`steps` of the clip; default the one nearest
        1/600 s.
    push : starting push (N), applied sideways to the root for ``push_duration`` s from
        ``push_start`` s (0: none).
    hold_root, stable_pd : as in :func:`~course.physics.character.track`.
    n_frames : clip frames to simulate per run (short: a slider change re-runs it).
    offset : (3,) where the simulated character is drawn relative to the clip (clip units);
        default half its height sideways (+z), so the two stand side by side.
    blocking : simulate in the caller's thread (see the module's docstring).
    call_later : ``call_later(delay, fn)`` of the kernel's loop (tests pass a fake).
    """

    def __init__(self, character: Any, clip: Any, *, kp: float = 1000.0, kd: float = 6.3,
                 h: float | None = None, push: float = 0.0, push_start: float = 0.3,
                 push_duration: float = 0.1, hold_root: bool = False, stable_pd: bool = False,
                 n_frames: int = 120, offset: ArrayLike | None = None,
                 torque_limit: float = float("inf"), display_fps: float = 30.0,
                 blocking: bool = False,
                 call_later: Callable[[float, Callable[[], None]], Any] | None = None) -> None:
        offered = steps(clip.frame_time)
        if not offered:
            raise ValueError(f"clip: a frame of {clip.frame_time:.6g} s has no step of "
                             f"1/2400 .. 1/60 s dividing it in {SUBSTEPS} sub-steps")
        asked = 1 / 600 if h is None else h
        step = min(offered, key=lambda s: abs(s - asked))  # the menu's own value
        if h is not None and not math.isclose(h, step, rel_tol=1e-9):
            raise ValueError(f"h: one of {', '.join(map(step_label, offered))} "
                             f"(steps that divide the clip's frame of {clip.frame_time:.6g} s), "
                             f"got {h!r}")
        if not 2 <= int(n_frames):
            raise ValueError(f"n_frames: at least 2, got {n_frames!r}")
        from .backend import call_later as kernel_call_later

        self.character = character
        self.clip = clip[: min(int(n_frames), clip.n_frames)]
        self.clip_positions, _ = self.clip.forward_kinematics()
        height = float(np.ptp(self.clip_positions[0, :, 1]))
        self.offset = (np.array([0.0, 0.0, 0.5 * height]) if offset is None
                       else np.asarray(offset, dtype=np.float64).reshape(3))
        self.push_start, self.push_duration = float(push_start), float(push_duration)
        self.torque_limit = float(torque_limit)
        self.blocking = blocking
        self.interval = 1.0 / display_fps
        self._call_later = call_later or kernel_call_later
        self._lock = threading.Lock()
        self._run = 0  # which simulation the frames belong to
        self._latest: tuple[int, int, Array] | None = None  # (run, frame, positions)
        self._thread: threading.Thread | None = None
        self._last_draw = -np.inf
        self.frames_drawn = 0
        self.result: Any = None
        self.error: str | None = None

        self.sliders = {
            "kp": widgets.FloatLogSlider(value=kp, base=10, min=1, max=5, step=0.05,
                                         description="kp", **slider_style(".3g")),
            "kd": widgets.FloatSlider(value=kd, min=0.0, max=100.0, step=0.1,
                                      description="kd", **slider_style(".1f")),
            "h": widgets.Dropdown(options=[(step_label(s), s) for s in offered],
                                  value=step,
                                  description="h", layout=widgets.Layout(width="200px")),
            "push": widgets.FloatSlider(value=push, min=0.0, max=1000.0, step=10.0,
                                        description="push (N)", **slider_style(".0f")),
            "hold_root": widgets.Checkbox(value=hold_root, description="hold the root"),
            "stable_pd": widgets.Checkbox(value=stable_pd, description="stable PD"),
        }
        for s in self.sliders.values():
            s.continuous_update = False  # one run per release, not one per pixel dragged
        self.readout = readout_box(2)
        parents = clip.skeleton.parents
        self.scene = SkeletonScene(window_size=WINDOW, camera="iso")
        p0 = self.clip_positions[0]
        frame = np.concatenate([self.clip_positions, self.clip_positions + self.offset], axis=1)
        self.scene.add_skeleton(parents, p0, name="captured", color=GHOST, frame_points=frame)
        self.scene.add_skeleton(parents, p0 + self.offset, name="simulated")
        self.scene.set_camera("iso")
        for s in self.sliders.values():
            on_value(s, lambda _c: self.simulate())
        self.button = fixed_height(widgets.Button(description="simulate again", icon="play",
                                            layout=widgets.Layout(width="160px")))
        self.button.on_click(lambda _b: self.simulate())
        # the controls beside the view, as notebook 13's: the whole fits a 1366x768 window
        width = "360px"
        panel = widgets.VBox([*self.sliders.values(), self.button, self.readout],
                             layout=widgets.Layout(flex="0 0 auto", width=width,
                                                   min_width=width, margin="0 12px 0 0"))
        view = self.scene.widget()
        w = f"{WINDOW[0]}px"
        view.layout.width, view.layout.min_width, view.layout.flex = w, w, "0 0 auto"
        self.widget = widgets.HBox([panel, view], layout=widgets.Layout(
            align_items="flex-start", flex_flow="row wrap"))

    # -- simulating ----------------------------------------------------------------------------

    def settings(self) -> dict[str, Any]:
        """The keyword arguments of :func:`~course.physics.character.track` the sliders set."""
        from course.physics.character import Push

        force = float(self.sliders["push"].value)
        push = (Push(self.clip.skeleton.names[0], (0.0, 0.0, force), self.push_start,
                     self.push_duration) if force > 0 else None)
        return {"kp": float(self.sliders["kp"].value), "kd": float(self.sliders["kd"].value),
                "h": float(self.sliders["h"].value), "push": push,
                "hold_root": bool(self.sliders["hold_root"].value),
                "stable_pd": bool(self.sliders["stable_pd"].value),
                "torque_limit": self.torque_limit}

    def simulate(self) -> None:
        """Run the simulation with the sliders' settings (a run still going is stopped)."""
        with self._lock:
            self._run += 1
            run = self._run
            self._latest = None
        self.result, self.error = None, None
        self.frames_drawn = 0
        self.readout.value = f"simulating {self.clip.n_frames} frames &hellip;"
        if self.blocking:
            self._simulate(run)
            self._finish(run)
            return
        self._thread = threading.Thread(target=self._simulate, args=(run,), daemon=True)
        self._thread.start()
        self._call_later(0.0, lambda: self._draw_latest(run))

    def wait(self, timeout: float = 60.0) -> None:
        """Block until the current run's simulation has ended (from code and tests)."""
        if self._thread is not None:
            self._thread.join(timeout)

    def _simulate(self, run: int) -> None:
        from course.physics.character import track

        def on_frame(i: int, frame: Any) -> None:
            if run != self._run:
                raise _Stopped
            positions, _ = frame.forward_kinematics()
            with self._lock:
                self._latest = (run, i, positions[0])
            if self.blocking and time.monotonic() - self._last_draw >= self.interval:
                self._draw_latest(run, again=False)

        try:
            result = track(self.character, self.clip, on_frame=on_frame, **self.settings())
        except _Stopped:
            return
        except Exception as exc:  # shown in the readout: a view must not die silently
            self.error = f"{type(exc).__name__}: {exc}"
            return
        if run == self._run:
            self.result = result

    def _draw_latest(self, run: int, again: bool = True) -> None:
        """Draw the newest simulated frame of ``run`` (and, from the loop, come back)."""
        if run != self._run:
            return
        with self._lock:
            latest, self._latest = self._latest, None
        if latest is not None and latest[0] == run:
            _, i, positions = latest
            self._show(i, positions)
        if not again:
            return
        done = self._thread is None or not self._thread.is_alive()
        if done:
            self._finish(run)
        else:
            self._call_later(self.interval, lambda: self._draw_latest(run))

    def _show(self, i: int, positions: Array) -> None:
        self.scene.set_pose(self.clip_positions[i], name="captured", render=False)
        self.scene.set_pose(positions + self.offset, name="simulated")
        self._last_draw = time.monotonic()
        self.frames_drawn += 1
        self.readout.value = (f"frame {i} / {self.clip.n_frames - 1}, "
                              f"t = {i * self.clip.frame_time:.2f} s (simulating)")

    def _finish(self, run: int) -> None:
        if run != self._run:
            return
        if self.result is None:
            self.readout.value = f"the simulation stopped: {self.error or 'settings changed'}"
            return
        r = self.result
        last = r.motion.n_frames - 1
        positions, _ = r.motion[last:].forward_kinematics()
        self._show(last, positions[0])
        state = ("numerically unstable" if r.unstable else
                 f"fell at {r.fall_time:.2f} s" if r.fell else "stayed up")
        self.readout.value = (f"{r.sim_time:.2f} s simulated in {r.wall_time:.2f} s "
                              f"(h = {step_label(r.h)}): {state}; tracking error mean "
                              f"{np.nanmean(r.error_cm):.1f} cm")


def simulation_view(character: Any, clip: Any, *, simulate: bool = True,
                    **kwargs: Any) -> SimulationView:
    """A :class:`SimulationView` of ``character`` following ``clip``, its first run started."""
    view = SimulationView(character, clip, **kwargs)
    if simulate:
        view.simulate()
    return view


__all__: Sequence[str] = ("SUBSTEPS", "SimulationView", "simulation_view", "step_label",
                            "steps")
