"""LQR balance 线性二次调节平衡 of the standing character, live in 3D, its cost on sliders.

:class:`LQRBalanceSimulator` stands the MuJoCo character under
:class:`~course.physics.lqr_balance.LQRBalance` on the machinery of every live view of the
course: a :class:`~course.viz.live_simulator.LiveSimulator` (play/pause ticking in the browser,
one step, reset, the readout) beside a :class:`~course.viz.scene.SkeletonScene`. Each run is
:func:`~course.physics.lqr_balance.lqr_stand`'s, a frame of 1/60 s per step: from the design's
equilibrium, for :attr:`LQRBalanceSimulator.duration` seconds, with the push sliders' push on
the root (size in N for ``push_duration`` s from ``push_start`` s, direction about the
vertical: 0 forward, 90 degrees to the left), stopped when the COM falls below 60 % of its
height or the run diverges. On the floor are the COM's projection, the capture point
:math:`\\xi = c + \\dot c/\\omega_0` and the line between them
(:mod:`course.viz.ground_markers`): the character stands while the ring stays over its feet;
the push is an arrow into the root while it acts.

The sliders are :math:`\\log_{10}` of the cost's weights (:class:`~course.physics.lqr_balance.
Weights`): per group of ``Q`` (the COM over the support, the balance joints, the other
joints, the feet, the velocities) and ``R``. On release the gain is designed again
(:func:`~course.physics.lqr_balance.reweigh`: the DARE alone, a few tenths of a second, the
equilibrium and linearisation kept) and the run starts again and plays; the stance (two feet,
one leg) needs a whole :func:`~course.physics.lqr_balance.design` (about 4 s) the first time
it is chosen, computed beside the kernel while the last gain plays on. "push" runs again with
the push sliders' push. The readout says whether it stood or when it fell, beside the largest
pushes measured in ``docs/control.md``.

As in every view of :mod:`course.viz`, widget events run on the GL thread and setting a
widget's value from code does what moving it does, so tests and notebooks drive it too.
MuJoCo and scipy are imported when a gain is designed, pyvista with :mod:`course.viz.scene`.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from typing import Any

import ipywidgets as widgets
import numpy as np

from .._typing import Array
from .backend import in_background, latest_on_gl_thread
from .ground_markers import COLORS, GroundMarkers, color_key, y_up
from .live_simulator import LiveSimulator, log_slider
from .scene import SkeletonScene

WINDOW = (640, 420)  # px: the 3D view, as notebook 14's
#: the stance menu: label -> ``stance`` of :func:`~course.physics.lqr_balance.design`
STANCES: dict[str, int | None] = {"two feet": None, "left foot": 0, "right foot": 1}
#: the weight sliders: field of :class:`~course.physics.lqr_balance.Weights`, label, range
WEIGHT_SLIDERS = (("balance", "Q COM", 10.0, 1e5), ("balance_joint", "Q legs+spine", 0.03, 300.0),
                  ("other_joint", "Q other", 0.003, 30.0), ("feet", "Q feet", 100.0, 1e7),
                  ("velocity", "Q velocity", 0.3, 3000.0), ("torque", "R", 0.01, 100.0))
#: the largest pushes measured (N, for 0.1 s on the root; docs/control.md) by stance and push
#: direction (degrees): notebook 14's ``com`` controller and LQR with the default weights
MEASURED = {"com": {0: 121.9, 180: 159.4, 90: 668.8},
            "two feet": {0: 128.1, 180: 131.2, 90: 162.5},
            "left foot": {0: 96.9, 180: 128.1, 90: 84.4, -90: 50.0},
            "right foot": {0: 96.9, 180: 128.1, -90: 71.9, 90: 65.6}}
GROUND_IN_VIEW = 0.5  # m of floor about the feet the camera keeps in view
KEY = color_key([(COLORS["com"], "COM"), (COLORS["capture"], "capture point ξ"),
                 (COLORS["push"], "push")])  # the readout's last line


class LQRBalanceSimulator(LiveSimulator[SkeletonScene]):
    """The character standing under LQR, played live while it simulates (module docstring).

    Parameters
    ----------
    character : :class:`~course.physics.model.Character` with two feet (the CMU one).
    design : the :class:`~course.physics.lqr_balance.LQRDesign` to start from (its stance and
        weights set the sliders); default ``design(character)``, two feet (about 4 s).
    push, push_direction : the push sliders' start: newtons, and degrees about the vertical
        (0 forward, 90 to the left, -90 to the right, 180 back).
    push_start, push_duration : when the push begins and how long it lasts (s).
    duration : simulated seconds per run.
    playback : simulated seconds per real second that play aims for (1.0: real time).
    max_frames_per_tick : the most frames (1/60 s each) one tick of play simulates.
    interval : ms between two ticks of play.
    window_size : (width, height) of the 3D view in pixels.

    Attributes
    ----------
    design : the gain in use (:class:`~course.physics.lqr_balance.LQRDesign`).
    design_time : wall seconds the last design took.
    sim : this run's :class:`~course.physics.simulation.Simulation`.
    pushed : this run's :class:`~course.physics.simulation.Push`, or None.
    markers : the COM, capture point and push drawn (:class:`~course.viz.ground_markers.
        GroundMarkers`).
    ground_height : MuJoCo's floor, y-up m.
    """

    frame_time = 1.0 / 60.0  # s: one step of play, as lqr_stand's frame
    torque_limit = 400.0  # N m, as lqr_stand's

    def __init__(self, character: Any, design: Any | None = None, *, push: float = 100.0,
                 push_direction: float = 0.0, push_start: float = 0.25,
                 push_duration: float = 0.1, duration: float = 3.0, playback: float = 1.0,
                 max_frames_per_tick: int = 10, interval: int = 50,
                 window_size: tuple[int, int] = WINDOW) -> None:
        from course.physics import lqr_balance
        from course.physics.model import motion_from_qpos

        for name, value in (("push_duration", push_duration), ("duration", duration)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name}: a positive time in s, got {value!r}")
        self.character = character
        self.push_start, self.push_duration = float(push_start), float(push_duration)
        self.duration = float(duration)
        self.n_frames = lqr_balance.lqr_frames(self.duration, self.frame_time)
        start = time.perf_counter()
        self.design = lqr_balance.design(character) if design is None else design
        self.design_time = time.perf_counter() - start
        self._gain_line = gain_line(self.design, self.design_time)
        self._designs = {self.design.stance: self.design}  # equilibrium and (A, B) per stance
        self._designing: set[int | None] = set()  # stances whose design runs beside the kernel
        self._design_note = ""  # the readout's first line while one runs, or why it failed
        pose = motion_from_qpos(character, self.design.equilibrium.qpos[None],
                                self.frame_time).forward_kinematics()[0][0]
        scene = SkeletonScene(window_size=window_size, camera="iso")
        r = GROUND_IN_VIEW / character.scale
        corners = np.array([[pose[0, 0] + sx, pose[:, 1].min(), pose[0, 2] + sz]
                            for sx in (-r, r) for sz in (-r, r)])
        scene.add_skeleton(character.skeleton.parents, pose, name="LQR",
                           frame_points=np.concatenate([pose, corners]))
        #: MuJoCo's floor, y-up m (the capture point's height reference)
        self.ground_height = float(y_up(character.model.geom("floor").pos)[1])
        assert scene.floor_height is not None  # the scene draws its floor
        self.markers = GroundMarkers(scene, ground_height=scene.floor_height,
                                     meters=character.scale)
        w = self.design.weights
        sliders: dict[str, widgets.Widget] = {
            key: log_slider(label, getattr(w, key), lo, hi, ".3g")
            for key, label, lo, hi in WEIGHT_SLIDERS}
        stance = next(k for k, v in STANCES.items() if v == self.design.stance)
        sliders["stance"] = widgets.Dropdown(options=list(STANCES), value=stance,
                                             description="stance",
                                             style={"description_width": "90px"},
                                             layout=widgets.Layout(width="240px"))
        style = {"style": {"description_width": "90px"}, "continuous_update": False,
                 "layout": widgets.Layout(width="360px")}
        sliders["push"] = widgets.FloatSlider(value=push, min=0.0, max=400.0, step=5.0,
                                              description="push (N)", readout_format=".0f",
                                              **style)
        style["layout"] = widgets.Layout(width="360px")  # widgets must not share a Layout
        sliders["push_direction"] = widgets.FloatSlider(
            value=push_direction, min=-180.0, max=180.0, step=15.0, description="push dir (°)",
            readout_format=".0f", **style)
        for key, *_ in WEIGHT_SLIDERS:
            sliders[key].observe(latest_on_gl_thread(lambda _c: self.redesign()), names="value")
        sliders["stance"].observe(latest_on_gl_thread(lambda _c: self.redesign()),
                                  names="value")
        for key in ("push", "push_direction"):
            sliders[key].observe(latest_on_gl_thread(lambda _c: self._show()), names="value")
        self.push_button = widgets.Button(description="push", icon="hand-o-right")
        self.push_button.on_click(latest_on_gl_thread(lambda _b: self.rerun()))
        super().__init__(scene, sliders, buttons=[self.push_button], speed=playback,
                         max_steps_per_tick=max_frames_per_tick, interval=interval,
                         window_size=window_size)

    # -- what the sliders set ------------------------------------------------------------------

    def weights(self) -> Any:
        """The :class:`~course.physics.lqr_balance.Weights` of the sliders (the starting
        design's ``scale`` kept)."""
        return dataclasses.replace(self.design.weights, **{
            key: float(self.sliders[key].value) for key, *_ in WEIGHT_SLIDERS})

    @property
    def stance(self) -> int | None:
        """The stance menu's foot (``design``'s ``stance``): None for both."""
        return STANCES[self.sliders["stance"].value]

    def push_force(self) -> Array:
        """The push sliders' force (3,), N, y up: the size along the direction about the
        vertical (0 forward along +z, 90 degrees to the left, +x)."""
        a = math.radians(float(self.sliders["push_direction"].value))
        return float(self.sliders["push"].value) * np.array([math.sin(a), 0.0, math.cos(a)])

    def redesign(self, asked: float | None = None) -> None:
        """The gain of the sliders' weights and stance (timed from ``asked``, default now:
        :attr:`design_time`), then a run from the start, playing. A stance not designed before
        needs its equilibrium and linearisation first (about 4 s): in a kernel they are
        computed beside it, the last gain playing on meanwhile, and the stance's gain follows
        once they are done."""
        from course.physics import lqr_balance

        stance, label = self.stance, self.sliders["stance"].value
        start = time.perf_counter() if asked is None else asked
        if stance not in self._designs:
            if stance not in self._designing:  # one design per stance, however often asked
                self._designing.add(stance)
                self._design_note = (f"<i>designing for {label}: equilibrium and "
                                     f"linearisation, about 4 s &hellip; (the last gain plays "
                                     f"meanwhile)</i>")
                self._show()
                in_background(lambda: lqr_balance.design(self.character, stance=stance),
                              lambda d: self._designed(stance, d, start),
                              lambda err: self._design_failed(stance, label, err))
            return
        self.design = lqr_balance.reweigh(self.character, self._designs[stance], self.weights())
        self.design_time = time.perf_counter() - start
        self._gain_line = gain_line(self.design, self.design_time)
        self.rerun()

    @property
    def designing(self) -> bool:
        """Whether a stance's equilibrium and linearisation are being computed."""
        return bool(self._designing)

    def _designed(self, stance: int | None, design: Any, start: float) -> None:
        self._designing.discard(stance)
        self._designs[stance] = design
        self._design_note = ""
        if self.stance == stance:  # still the stance asked for: its gain, timed from the ask
            self.redesign(asked=start)

    def _design_failed(self, stance: int | None, label: str, err: Exception) -> None:
        self._designing.discard(stance)  # chosen again, it is tried again
        self._design_note = (f"<span style='color:#a4161a'>the design for {label} failed: "
                             f"{type(err).__name__}: {err}</span>")
        self._show()

    def rerun(self) -> None:
        """Start the run again (with the push sliders' push) and play it."""
        self.reset()
        self.play.playing = True

    # -- simulating ------------------------------------------------------------------------------

    @property
    def step_time(self) -> float:
        """One step of play is a frame of :attr:`frame_time`."""
        return self.frame_time

    def reset(self) -> None:
        """A new run from the design's equilibrium, the push sliders' push to come."""
        from course.physics.lqr_balance import LQRBalance, lqr_simulation
        from course.physics.simulation import Push

        force = self.push_force()
        push = (Push(self.character.skeleton.names[0], force, self.push_start,
                     self.push_duration) if np.any(force) else None)
        self.pushed = push
        self.sim = lqr_simulation(self.character, self.design, push=push,
                                  torque_limit=self.torque_limit, frame_time=self.frame_time,
                                  stop_when_diverged=True)
        self.controller = LQRBalance(self.design)
        self.controller.reset(self.sim)
        self.wall_time = 0.0
        self._draw()
        self._show()

    @property
    def stopped(self) -> bool:
        """Whether the run has ended: fallen, diverged, or :attr:`duration` simulated."""
        return self.sim.reason is not None or self.sim.frame >= self.n_frames - 1

    def advance(self, n: int = 1) -> None:
        """Simulate ``n`` frames (fewer if the run ends) and draw the last once."""
        start = time.perf_counter()
        for _ in range(int(n)):
            if self.stopped:
                break
            self.sim.step(self.controller)
        self.wall_time += time.perf_counter() - start
        if self.stopped:
            self.play.playing = False
        self._draw()
        self._show()

    def finish(self) -> None:
        """Simulate the rest of the run at once (from code and tests) and draw its end."""
        self.advance(self.n_frames)

    @property
    def fall_time(self) -> float | None:
        """When the run fell or diverged (s), or None."""
        sim = self.sim
        if sim.reason == "diverged":
            return sim.time
        return sim.fall_time

    @property
    def pushing(self) -> bool:
        """Whether this run's push acts in the frame simulated next."""
        return self.pushed is not None and self.pushed.active(self.sim.time, self.frame_time)

    def _draw(self) -> None:
        from course.physics.model import motion_from_qpos

        motion = motion_from_qpos(self.character, self.sim.data.qpos[None], self.frame_time)
        pose = motion.forward_kinematics()[0][0]
        push = self.pushed if self.pushing else None
        self.markers.follow(self.character, self.sim.model, self.sim.data, self.ground_height,
                            None if push is None else pose[0],
                            None if push is None else push.force)
        self.scene.set_pose(pose, render=False)

    def _measured(self) -> str:
        """The largest pushes of docs/control.md in the push sliders' direction, if any."""
        direction = round(float(self.sliders["push_direction"].value))
        stance = self.sliders["stance"].value
        lqr = MEASURED[stance].get(direction)
        if lqr is None:
            return "measured (docs/control.md) forward, back and sideways only"
        text = f"measured here, default weights: LQR {lqr:.0f} N ({lqr * 0.1:.1f} N s)"
        com = MEASURED["com"].get(direction)
        if stance == "two feet" and com is not None:
            text += f"; notebook 14's com controller {com:.0f} N ({com * 0.1:.1f} N s)"
        return text

    def _show(self) -> None:
        sim, t = self.sim, self.sim.time
        fell = self.fall_time
        if sim.reason == "diverged":
            state = f"<b style='color:#e5484d'>fell at {fell:.2f} s</b> (diverged)"
        elif fell is not None:
            state = f"<b style='color:#e5484d'>fell at {fell:.2f} s</b>"
        elif self.stopped:
            state = f"<b style='color:#2bb673'>stood {t:.1f} s</b>"
        else:
            state = f"t = {t:.2f} s of {self.duration:g} s: standing"
        if self.stopped and self.wall_time > 0:
            state += f" (simulated in {self.wall_time:.2f} s)"
        size = float(np.linalg.norm(self.push_force()))
        push = (f"push: {size:.0f} N for {self.push_duration:g} s at {self.push_start:g} s "
                f"= {size * self.push_duration:.1f} N s" if size > 0 else "push: none")
        lines = [self._design_note] if self._design_note else []
        lines += [state, push, self._measured(), self._gain_line,
                 f"play: {self.speed:g}× real time, {self.steps_per_tick} frames of 1/60 s "
                 f"a tick", KEY]
        self.readout.value = "<br>".join(lines)
        self.scene.render()


def gain_line(design: Any, seconds: float) -> str:
    """The readout's line on a design: its time, its largest gain and how fast the closed loop
    ``A − BK`` settles. Its spectral radius is 1 on the floor's neutral modes (the body slid or
    turned on the floor stays so: nothing in the cost pulls it back), which alone would read as
    "not stable"; the slowest other mode is the one that says how fast a push dies away."""
    magnitudes = np.sort(np.abs(np.linalg.eigvals(design.A - design.B @ design.K)))[::-1]
    neutral = int(np.sum(np.abs(magnitudes - 1.0) < 1e-5))  # 1 but for finite differences
    rest = magnitudes[neutral:]
    settle = (f"; ρ(A − BK) = 1 on {neutral} neutral modes (sliding, turning on the floor), "
              f"|λ| ≤ {rest[0]:.5f} on the others" if neutral and rest.size else
              f"; ρ(A − BK) = {magnitudes[0]:.5f}")
    return f"gain designed in {seconds:.2f} s: max |K| {np.abs(design.K).max():.0f}{settle}"


def lqr_balance_simulator(character: Any, design: Any | None = None,
                          **kwargs: Any) -> LQRBalanceSimulator:
    """A :class:`LQRBalanceSimulator` of ``character`` (``design``: the gain to start from,
    default the two-foot one), ready to play (``kwargs`` go to it)."""
    return LQRBalanceSimulator(character, design, **kwargs)


__all__: Sequence[str] = ("LQRBalanceSimulator", "MEASURED", "STANCES", "lqr_balance_simulator")
