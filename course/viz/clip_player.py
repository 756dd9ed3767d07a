"""The clip player (ipywidgets): a motion played in the kernel, paced to the pictures it can
send, with other clips, IK targets and joint-angle curves beside it."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import ipywidgets as widgets
import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .figures import JointAngleFigure
from .panel import Control, fixed_height, on_value, readout_box, slider_style
from .scene import SkeletonScene


class BVHPlayer(Control):
    """Play a clip: play/pause, frame slider, speed, loop, camera. FK runs once for the whole
    clip; a frame change is a point update. The root's path is drawn on the floor; ``curves``
    (label -> ``(F,)`` angles in radians, e.g. a knee's flexion) are plotted under the view
    with a cursor at the current frame. ``others`` (label -> ``(F, J, 3)`` joint positions of
    the same skeleton, e.g. a student's FK of the clip) are drawn beside it, frame by frame,
    and ``name`` labels the clip's own skeleton. ``targets`` (``(F, 3)`` or ``(F, K, 3)``,
    e.g. the IK targets a clip was solved for) are drawn as target markers at each frame.

    Playback runs in the kernel, one picture at a time: the next frame is drawn only once the
    last picture has been sent, and frames are skipped to keep the clip's speed at the rate
    pictures are delivered (:class:`~course.viz.playback.PlaybackPacer`, at most
    ``display_fps`` a second); the readout says which ("showing every 4th frame — 30 of 120
    fps"). Pause stops it at once. ``clock`` and ``call_later(delay, fn)`` replace the
    monotonic clock and the kernel's event loop (tests drive playback with fakes).
    """

    def __init__(self, motion: Any, *, camera: str = "follow", display_fps: float = 30.0,
                 curves: Mapping[str, ArrayLike] | None = None,
                 others: Mapping[str, ArrayLike] | None = None, name: str | None = None,
                 targets: ArrayLike | None = None,
                 clock: Callable[[], float] | None = None,
                 call_later: Callable[[float, Callable[[], None]], Any] | None = None) -> None:
        import time

        from .backend import call_later as kernel_call_later
        from .playback import PlaybackPacer

        self.motion = motion
        self.positions, self.orientations = motion.forward_kinematics()
        n = self.positions.shape[0]
        self.others = {label: _clip_positions(label, p, self.positions.shape)
                       for label, p in (others or {}).items()}
        self.targets = None if targets is None else _clip_targets(targets, n)
        self.pacer = PlaybackPacer(1.0 / motion.frame_time, max_pictures_per_s=display_fps)
        self._clock = clock or time.monotonic
        self._call_later = call_later or kernel_call_later
        self.frame = 0
        self._run = 0  # which press of play the pending picture belongs to
        self.play = fixed_height(widgets.ToggleButton(value=False, description="play", icon="play",
                                                tooltip="play / pause",
                                                layout=widgets.Layout(width="96px")))
        self.play.add_class("course-play")
        self.sliders = {
            "frame": widgets.IntSlider(value=0, min=0, max=n - 1, description="frame",
                                       **slider_style("d")),
            "speed": widgets.Dropdown(options=[0.25, 0.5, 1.0, 2.0], value=1.0,
                                      description="speed", layout=widgets.Layout(width="160px")),
            "loop": widgets.Checkbox(value=True, description="loop"),
            "camera": widgets.Dropdown(options=["follow", "iso", "front", "side", "top"],
                                       value=camera, description="camera",
                                       layout=widgets.Layout(width="200px")),
        }
        self.readout = readout_box(1)
        # with curves under it the view is lower: the player fits a 1366x768 window
        self.scene = SkeletonScene(window_size=(720, 380 if curves else 480), camera="iso")
        self.name = name or motion.name or "motion"
        # framed on all the clips (the follow camera: about the first one's root)
        everything = np.concatenate([self.positions, *self.others.values(),
                                     *([] if self.targets is None else [self.targets])], axis=1)
        self.scene.add_skeleton(motion.skeleton.parents, self.positions[0], name=self.name,
                                frame_points=everything)
        for label, clip in self.others.items():
            self.scene.add_skeleton(motion.skeleton.parents, clip[0], name=label)
        self.scene.set_camera(camera)
        floor = float(self.positions[..., 1].min())
        path = self.positions[:, 0] * [1.0, 0.0, 1.0] + [0.0, floor, 0.0]
        self.scene.add_trail(capacity=n)
        self.scene.set_trail(path)
        self.curves = self.curves_image = None
        if curves:
            angles = np.column_stack([np.asarray(c, dtype=np.float64).reshape(n)
                                      for c in curves.values()])
            self.curves = JointAngleFigure(angles, motion.frame_time, list(curves),
                                           figsize=(7.2, 1.8))
            self.curves_image = widgets.Image(format="png", width=720)
        # playback sets the slider to the frame it shows: that is no new frame to draw
        on_value(self.sliders["frame"],
                  lambda c: None if c["new"] == self.frame else self.show_frame(c["new"]))
        on_value(self.sliders["speed"], lambda c: setattr(self.pacer, "speed", c["new"]))
        on_value(self.sliders["camera"], lambda c: self.scene.set_camera(c["new"], render=True))
        on_value(self.play, lambda c: self._play_toggled(c["new"]))
        row = widgets.HBox([self.play, self.sliders["frame"], self.sliders["speed"],
                            self.sliders["loop"], self.sliders["camera"]],
                           layout=widgets.Layout(flex_flow="row wrap", align_items="center"))
        self.widget = widgets.VBox([self.scene.widget(), row, self.readout,
                                    *([self.curves_image] if self.curves_image else [])])
        self.show_frame(0)

    @property
    def playing(self) -> bool:
        return bool(self.play.value)

    def _play_toggled(self, playing: bool) -> None:
        self.play.description = self.play.icon = "pause" if playing else "play"
        if not playing:
            self._show_readout()  # no skip to report while paused
            return
        if self.frame >= self.positions.shape[0] - 1 and not self.sliders["loop"].value:
            self.show_frame(0)  # played to the end before: start again
        self._run += 1  # a pause and play while a picture was pending: one chain, not two
        run = self._run
        self._call_later(0.0, lambda: self._tick(run))

    def _tick(self, run: int) -> None:
        """Show the next frame (the pause button is read here, so a pause stops at once)."""
        if not self.playing or run != self._run:
            return
        frame = self.pacer.next_frame(self.frame, self.positions.shape[0],
                                      self.sliders["loop"].value)
        if frame is None:  # the end of a clip that does not loop
            self.play.value = False
            return
        asked = self._clock()
        self.show_frame(frame)
        self.sliders["frame"].value = frame
        self._when_sent(asked, run)

    def _when_sent(self, asked: float, run: int) -> None:
        """Wait (without blocking) until the picture has left the kernel, then measure its
        cost and ask for the next one in time to keep the clip's speed."""
        elapsed = self._clock() - asked
        # (a view that never answers is not waited for forever)
        if self.scene.pictures_in_flight() and elapsed < 1.0 and self.playing:
            self._call_later(0.002, lambda: self._when_sent(asked, run))
            return
        self.pacer.delivered(elapsed)
        self._call_later(max(0.0, self.pacer.interval - elapsed), lambda: self._tick(run))

    def show_frame(self, frame: int) -> None:
        self.frame = int(frame)
        for label, clip in self.others.items():  # one render, with the last
            self.scene.set_pose(clip[self.frame], name=label, render=False)
        if self.targets is not None:
            self.scene.set_targets(self.targets[self.frame], render=False)
        self.scene.set_pose(self.positions[self.frame], name=self.name)
        self._show_readout()
        if self.curves is not None and self.curves_image is not None:
            self.curves.set_frame(self.frame)
            self.curves_image.value = self.curves.png()

    def _show_readout(self) -> None:
        playing = f" &middot; {self.pacer.describe()}" if self.playing else ""
        self.readout.value = (f"frame {self.frame} / {self.positions.shape[0] - 1}, "
                              f"t = {self.frame * self.motion.frame_time:.3f} s{playing}")


def _clip_positions(label: str, positions: ArrayLike, shape: tuple[int, ...]) -> Array:
    """``positions`` as a float array of ``shape`` (F, J, 3), or an error naming ``label``."""
    p = np.asarray(positions, dtype=np.float64)
    if p.shape != shape:
        raise ValueError(f"others[{label!r}] must have the clip's shape {shape} (frames, "
                         f"joints, 3), got {p.shape}")
    return _finite_frames(f"others[{label!r}]", p)


def _finite_frames(name: str, frames: Array) -> Array:
    """``frames`` (F, ...) as they are, or an error naming the first frame not finite."""
    if not np.isfinite(frames).all():
        frame = int(np.argwhere(~np.isfinite(frames))[0, 0])
        raise ValueError(f"{name} is not finite at frame {frame}")
    return frames


def _clip_targets(targets: ArrayLike, n_frames: int) -> Array:
    """``targets`` as ``(F, K, 3)`` floats (``(F, 3)``: one per frame), or an error."""
    t = np.asarray(targets, dtype=np.float64)
    if t.ndim == 2:
        t = t[:, None]
    if t.ndim != 3 or t.shape[0] != n_frames or t.shape[2] != 3:
        raise ValueError(f"targets must have shape ({n_frames}, 3) or ({n_frames}, K, 3) "
                         f"(one row per frame of the clip), got {np.shape(targets)}")
    return _finite_frames("targets", t)


def bvh_player(motion: Any, *, camera: str = "follow",
               curves: Mapping[str, ArrayLike] | None = None, **kwargs: Any) -> BVHPlayer:
    """Play a :class:`course.motion.Motion`: see :class:`BVHPlayer`."""
    return BVHPlayer(motion, camera=camera, curves=curves, **kwargs)
