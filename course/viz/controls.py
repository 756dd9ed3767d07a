"""Interactive controls (ipywidgets): drag a slider, the skeleton, the numbers and the plot answer.

Every control is an object that displays itself in a notebook and also works from code:
``.sliders`` (name -> widget), ``.readout`` (an HTML widget with the numbers), ``.scene``
(the 3D view; e.g. ``.scene.joint_positions``) and ``.widget`` (the whole layout). Setting a
slider's ``.value`` from code runs the same update as dragging it, so tests and notebooks can
drive them. Per event the math (FK, IK) runs once on small arrays and the views are updated in
place; clip playback is paced on the kernel's event loop (one picture at a time, see
:mod:`course.viz.playback`), so no cell ever blocks.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import ipywidgets as widgets
import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .backend import latest_on_gl_thread, soon
from .figures import ConvergenceFigure, GimbalFigure, JointAngleFigure, SlerpArcFigure
from .frame_scene import FrameScene
from .panel import fixed_height, on_value, readout_box, slider_style
from .scene import GHOST, SkeletonScene


def _angle_slider(description: str, value: float = 0.0, limit: float = 180.0
                  ) -> widgets.FloatSlider:
    """A slider in degrees (what students read); the math converts to radians."""
    return widgets.FloatSlider(value=value, min=-limit, max=limit, step=1.0,
                               description=description, **slider_style())


def _set_sliders(sliders: dict[str, widgets.Widget], position: Array) -> None:
    """Put ``position (3,)`` into the x/y/z sliders, clipped to their ranges."""
    for k, c in enumerate("xyz"):
        s = sliders[c]
        s.value = float(np.clip(position[k], s.min, s.max))


def _clipped(sliders: dict[str, widgets.Widget], position: Array) -> Array:
    """``position (3,)`` clipped to the ranges of the x/y/z sliders."""
    lo = np.array([sliders[c].min for c in "xyz"])
    hi = np.array([sliders[c].max for c in "xyz"])
    out: Array = np.clip(np.asarray(position, dtype=np.float64), lo, hi)
    return out


def _snapped(slider: widgets.Widget, old: float, new: float) -> bool:
    """The browser moved ``old`` onto the slider's step grid (``min + n step``, the nearest
    point): it does so when it shows a value that lies between two steps, and sends the
    snapped value back. That is the same value to the student, not a move of theirs."""
    step = slider.step
    if not step:
        return False
    n = (new - slider.min) / step
    return bool(abs(new - old) <= step / 2 * (1 + 1e-9) and abs(n - round(n)) < 1e-6)


def _side_by_side(*children: widgets.Widget) -> widgets.HBox:
    """A row of panels that keep their width (the sliders and their numbers stay readable)
    beside views that shrink to fit a narrow notebook (see ``SkeletonScene.widget``); what
    does not fit wraps to the next line instead of leaving the output."""
    for child in children:
        if child.layout.min_width is None:  # a panel: fixed
            child.layout.flex = "0 0 auto"
            child.layout.margin = "0 12px 0 0"
    return widgets.HBox(list(children), layout=widgets.Layout(
        align_items="flex-start", flex_flow="row wrap", width="100%"))


def _number(x: float, fmt: str = "+.3f") -> str:
    """``x`` in ``fmt``, and never ``-0.000`` (a tiny negative number, rounded)."""
    text = format(float(x), fmt)
    return format(0.0, fmt) if float(text) == 0 else text


def _matrix_html(R: Array) -> str:
    rows = "".join(
        "<tr>" + "".join(f"<td style='padding:0 8px;text-align:right'>{_number(v)}</td>"
                         for v in r)
        + "</tr>" for r in R
    )
    return f"<table style='font-family:monospace'>{rows}</table>"


def _iterations(n: int) -> str:
    """``"1 iteration"``, ``"12 iterations"``."""
    return f"{n} iteration{'' if n == 1 else 's'}"


def _vec(v: ArrayLike, fmt: str = "+.3f") -> str:
    return "(" + ", ".join(_number(x, fmt) for x in np.ravel(v)) + ")"


class Control:
    """Common shape of every control: a layout, its sliders, a readout and a scene."""

    widget: widgets.Widget
    sliders: dict[str, widgets.Widget]
    readout: widgets.HTML

    def _ipython_display_(self) -> None:
        from IPython.display import display

        display(self.widget)

    @classmethod
    def _widgets(cls, w: widgets.Widget) -> list[widgets.Widget]:
        return [w, *(x for c in getattr(w, "children", ()) for x in cls._widgets(c))]

    def close(self) -> None:
        """Close the widgets and free the render window."""
        for w in self._widgets(self.widget):
            w.close()
        scene = getattr(self, "scene", None)
        if scene is not None:
            scene.close()


# -- rotations ---------------------------------------------------------------------------------


class RotationExplorer(Control):
    """Three Euler angle sliders and an order: the matrix, quaternion and axis-angle live, the
    rotated frame in 3D, the gimbal rings, and a warning near gimbal lock."""

    LOCK_WARNING_DEG = 2.0

    def __init__(self, order: str = "XYZ", angles: ArrayLike = (0.0, 0.0, 0.0),
                 degrees: bool = False) -> None:
        from course.rotations import EULER_ORDERS

        if order not in EULER_ORDERS:
            raise ValueError(f"order must be one of the 24 Euler orders, got {order!r}")
        a = np.asarray(angles, dtype=np.float64).reshape(3)
        a_deg = a if degrees else np.degrees(a)
        self.order = widgets.Dropdown(options=list(EULER_ORDERS), value=order,
                                      description="order", layout=widgets.Layout(width="200px"))
        self.sliders = {f"angle{k}": _angle_slider(f"angle {k + 1}", v)
                        for k, v in enumerate(a_deg)}
        self.readout = readout_box(9)  # the matrix rows are taller than a line of text
        self.warning = readout_box(4)  # reserved: the lock warning never moves the views
        self.scene = FrameScene(1, window_size=(380, 340))
        self.gimbal = GimbalFigure(order, np.radians(a_deg))
        self.gimbal_image = widgets.Image(format="png", width=340)
        controls = widgets.VBox([self.order, *self.sliders.values(), self.warning, self.readout],
                                layout=widgets.Layout(width="350px"))
        self.widget = _side_by_side(controls, self.scene.widget(), self.gimbal_image)
        for w in (self.order, *self.sliders.values()):
            on_value(w, self._changed)
        self._changed()

    @property
    def angles(self) -> Array:
        """The three angles in radians, in the order's sequence."""
        return np.radians([s.value for s in self.sliders.values()])

    def _changed(self, _change: Any = None) -> None:
        from course.rotations import (
            axis_angle_from_quat,
            gimbal_lock_distance,
            matrix_from_euler,
            quat_from_euler,
        )

        order, a = self.order.value, self.angles
        for k, s in enumerate(self.sliders.values()):
            s.description = f"{order[k]} (#{k + 1})"
        self.matrix = matrix_from_euler(a, order)
        self.quaternion = quat_from_euler(a, order)
        axis, angle = axis_angle_from_quat(self.quaternion)
        distance = float(np.degrees(gimbal_lock_distance(a, order)))
        self.gimbal_lock = distance < self.LOCK_WARNING_DEG
        kind = "intrinsic: R = " if order.isupper() else "extrinsic: R = "
        product = " ".join(f"R<sub>{c}</sub>" for c in (order if order.isupper() else order[::-1]))
        self.readout.value = (
            f"<b>{kind}{product}</b>{_matrix_html(self.matrix)}"
            f"<b>q</b> = (w, x, y, z) = {_vec(self.quaternion)}<br>"
            f"<b>axis</b> = {_vec(axis)}, <b>angle</b> = {np.degrees(angle):.1f}&deg;"
        )
        self.warning.value = (
            "<div style='background:#fde8e8;color:#a4161a;padding:4px 8px;border-radius:4px'>"
            f"&#9888; <b>Gimbal lock</b>: the middle angle is {distance:.1f}&deg; from lock; "
            f"the {order[0]} and {order[2]} rings are aligned and one degree of freedom is "
            "lost.</div>" if self.gimbal_lock else ""
        )
        self.scene.set_rotations(self.matrix[None])
        self.gimbal.update(a, order)
        self.gimbal_image.value = self.gimbal.png()


def rotation_explorer(order: str = "XYZ", angles: ArrayLike = (0.0, 0.0, 0.0),
                      degrees: bool = False) -> RotationExplorer:
    """Explore Euler angles: see :class:`RotationExplorer`."""
    return RotationExplorer(order, angles, degrees)


class SlerpExplorer(Control):
    """Two rotations (Euler "XYZ" sliders) and t: LERP, NLERP and SLERP side by side.

    LERP's quaternion ``(1-t) q0 + t q1`` is not unit; its frame is drawn as the map
    ``v -> q v q*``, which scales by ``|q|^2`` (the frame shrinks mid-way). NLERP normalises
    (right rotation, uneven speed); SLERP moves at constant angular speed.
    """

    def __init__(self, start: ArrayLike = (0.0, 0.0, 0.0), end: ArrayLike = (20.0, 150.0, 60.0),
                 t: float = 0.25) -> None:
        self.sliders = {
            **{f"start{k}": _angle_slider(f"start {c}", v) for k, (c, v) in
               enumerate(zip("XYZ", np.ravel(start), strict=True))},
            **{f"end{k}": _angle_slider(f"end {c}", v) for k, (c, v) in
               enumerate(zip("XYZ", np.ravel(end), strict=True))},
            "t": widgets.FloatSlider(value=t, min=0.0, max=1.0, step=0.01, description="t",
                                     **slider_style(".2f")),
        }
        # room for the table: a row per method, readable columns
        self.readout = readout_box(6, "470px")
        self.scene = FrameScene(3, labels=["LERP", "NLERP", "SLERP"], window_size=(780, 300))
        self.q0, self.q1 = self._ends()
        self.arc = SlerpArcFigure(self.q0, self.q1, t=t)
        self.arc_image = widgets.Image(format="png", width=300)
        # sliders, table and arc in one row under the view: the whole explorer fits a
        # 1366x768 window (a narrower notebook wraps the arc under them)
        self.widget = widgets.VBox([self.scene.widget(), _side_by_side(
            widgets.VBox(list(self.sliders.values())), self.readout, self.arc_image)])
        for name, s in self.sliders.items():
            on_value(s, self._changed_t if name == "t" else self._changed_ends)
        self._show()

    def _ends(self) -> tuple[Array, Array]:
        from course.rotations import quat_from_euler

        ang = np.radians([s.value for s in self.sliders.values()][:6]).reshape(2, 3)
        return tuple(quat_from_euler(ang, "XYZ"))

    def _changed_ends(self, _change: Any = None) -> None:
        self.q0, self.q1 = self._ends()
        self.arc.set_rotations(self.q0, self.q1)  # drawn at the arc's t, the slider's
        self._show()

    def _changed_t(self, _change: Any = None) -> None:
        self.arc.set_t(self.sliders["t"].value)
        self._show()

    def _show(self) -> None:
        """The arc's picture, the three frames and the table, for the current ends and t."""
        from course.rotations import lerp, matrix_from_quat, nlerp, quat_angle, slerp

        t = self.sliders["t"].value
        self.arc_image.value = self.arc.png()
        q1 = self.q1 if np.dot(self.q0, self.q1) >= 0 else -self.q1  # same hemisphere as q0
        q = {"LERP": lerp(self.q0, q1, t), "NLERP": nlerp(self.q0, q1, t),
             "SLERP": slerp(self.q0, q1, t)}
        self.quaternions = q
        norms = {k: float(np.linalg.norm(v)) for k, v in q.items()}
        # v -> q v q* = |q|^2 R(q/|q|) v
        self.scene.set_rotations(
            [norms[k] ** 2 * matrix_from_quat(v / norms[k]) for k, v in q.items()]
        )
        total = float(np.degrees(quat_angle(self.q0, q1)))
        cell = "<td style='padding:1px 10px;text-align:right;white-space:nowrap'>"
        rows = "".join(
            f"<tr><td style='padding:1px 10px 1px 0'><b>{k}</b></td>{cell}{_vec(v)}</td>"
            f"{cell}{norms[k]:.3f}</td>"
            f"{cell}{np.degrees(quat_angle(self.q0, v / norms[k])):.1f}&deg;</td></tr>"
            for k, v in q.items()
        )
        head = "<th style='padding:1px 10px;text-align:right'>"
        self.readout.value = (
            "<table style='font-family:monospace;border-collapse:collapse'><tr><th></th>"
            f"{head}q(t) = (w, x, y, z)</th>{head}|q|</th>{head}angle from q0</th></tr>"
            f"{rows}</table>t &middot; total angle = {t * total:.1f}&deg; (SLERP matches it)"
        )


def slerp_explorer(start: ArrayLike = (0.0, 0.0, 0.0), end: ArrayLike = (20.0, 150.0, 60.0),
                   t: float = 0.25) -> SlerpExplorer:
    """Compare LERP / NLERP / SLERP: see :class:`SlerpExplorer` (angles in degrees). It opens
    at ``t = 0.25``: at 0.5, by symmetry, NLERP and SLERP agree."""
    return SlerpExplorer(start, end, t)


# -- forward kinematics --------------------------------------------------------------------------


def _dof_axes(skeleton: Any, j: int) -> Array:
    """The rotation axes of joint j's sliders, ``(dof, 3)``, composed in order (intrinsic):
    a hinge has its axis, a universal joint its two axes, a ball joint z, y, x (BVH's
    ``Zrotation Yrotation Xrotation``); End Sites none."""
    types = getattr(skeleton, "joint_types", None)
    jt = types[j] if types is not None else None
    if jt is not None and getattr(jt, "dof", 3) == 0:
        return np.zeros((0, 3))
    if jt is not None and getattr(jt, "axis", None) is not None:
        return np.asarray(jt.axis, dtype=np.float64).reshape(1, 3)
    if jt is not None and getattr(jt, "axes", None) is not None:
        return np.asarray(jt.axes, dtype=np.float64).reshape(-1, 3)
    if skeleton.names[j].endswith("_end") and not skeleton.children(j):
        return np.zeros((0, 3))
    return np.eye(3)[[2, 1, 0]]


class FKExplorer(Control):
    """One slider per degree of freedom, grouped by joint, on top of a base pose:
    ``R_j = R_j^0 R(a_1, th_1) R(a_2, th_2) ...``, then ``Q_j = Q_parent R_j``,
    ``p_j = p_parent + Q_parent l_j``. A reset returns to the base pose."""

    def __init__(self, skeleton: Any, local_rotations: ArrayLike | None = None,
                 root_position: ArrayLike | None = None, *, axes: bool = True,
                 limit: float = 180.0) -> None:
        from course.rotations import quat_identity

        self.skeleton = skeleton
        n = skeleton.n_joints
        self.base = (np.tile(quat_identity(), (n, 1)) if local_rotations is None
                     else np.array(local_rotations, dtype=np.float64).reshape(n, 4))
        self.root_position = (np.zeros(3) if root_position is None
                              else np.asarray(root_position, dtype=np.float64).reshape(3))
        self.local_rotations = self.base.copy()
        self._quiet = False
        self.axes = {j: _dof_axes(skeleton, j) for j in range(n)}
        self.sliders: dict[str, widgets.FloatSlider] = {}
        groups, titles = [], []
        for j, ax in self.axes.items():
            if len(ax) == 0:
                continue
            row = []
            for k, a in enumerate(ax):
                label = "xyz"[int(np.argmax(np.abs(a)))] if np.count_nonzero(a) == 1 else f"a{k}"
                s = _angle_slider(label, 0.0, limit)
                on_value(s, lambda _c, j=j: self._changed(j))
                self.sliders[f"{skeleton.names[j]}.{k}"] = s
                row.append(s)
            groups.append(widgets.VBox(row))
            titles.append(skeleton.names[j])
        self.accordion = widgets.Accordion(children=groups, titles=tuple(titles),
                                           selected_index=0 if groups else None)
        self.reset_button = fixed_height(widgets.Button(description="reset", icon="undo"))
        self.reset_button.on_click(latest_on_gl_thread(lambda _b: self.reset()))
        self.readout = readout_box(4)  # R_j, Q_j, p_j: lines with subscripts are taller
        self.positions, self.orientations = skeleton.forward_kinematics(
            self.local_rotations, self.root_position)
        # frame the whole reach (the pose can turn anywhere), not just this pose
        reach = float(np.linalg.norm(self.positions - self.positions[0], axis=1).max())
        # a planar arm is seen face on, as in the lecture's drawings
        normal = _hinge_plane_normal(skeleton, range(n), self.orientations)
        self.scene = SkeletonScene(window_size=(640, 520), camera=_facing(normal) or "iso")
        self.scene.add_skeleton(skeleton.parents, self.positions, self.orientations,
                                name="pose", axes=axes, frame_points=self.positions, reach=reach)
        # the readout above the joint list, which scrolls: it stays in sight while posing
        self.accordion.layout = widgets.Layout(max_height="400px", overflow="auto",
                                               flex="0 1 auto")
        left = widgets.VBox([self.reset_button, self.readout, self.accordion],
                            layout=widgets.Layout(width="400px"))
        self.widget = _side_by_side(left, self.scene.widget())
        self._joint = next(iter(j for j, a in self.axes.items() if len(a)), 0)
        self._show_readout()

    def _delta(self, j: int) -> Array:
        from course.rotations import quat_from_axis_angle, quat_identity, quat_mul

        q = quat_identity()
        name = self.skeleton.names[j]
        for k, a in enumerate(self.axes[j]):
            theta = np.radians(self.sliders[f"{name}.{k}"].value)
            q = quat_mul(q, quat_from_axis_angle(a, theta))
        return q

    def _changed(self, j: int) -> None:
        from course.rotations import quat_mul

        if self._quiet:
            return
        self.local_rotations[j] = quat_mul(self.base[j], self._delta(j))
        self._joint = j
        self.update()

    def update(self) -> None:
        """FK for the current sliders, then move the scene in place."""
        self.positions, self.orientations = self.skeleton.forward_kinematics(
            self.local_rotations, self.root_position)
        self.scene.set_pose(self.positions, self.orientations)
        self._show_readout()

    def _show_readout(self) -> None:
        j = self._joint
        name = self.skeleton.names[j]
        self.readout.value = (
            f"<b>{name}</b>: R<sub>j</sub> = {_vec(self.local_rotations[j])}<br>"
            f"Q<sub>j</sub> = {_vec(self.orientations[j])}<br>"
            f"p<sub>j</sub> = {_vec(self.positions[j], '+.2f')}"
        )

    def reset(self) -> None:
        """All sliders back to 0: the base pose (one FK and one render, not one per slider)."""
        self._quiet = True
        try:
            for s in self.sliders.values():
                s.value = 0.0
        finally:
            self._quiet = False
        self.local_rotations = self.base.copy()
        self.update()


def fk_explorer(skeleton: Any, local_rotations: ArrayLike | None = None,
                root_position: ArrayLike | None = None, *, axes: bool = True) -> FKExplorer:
    """Pose a skeleton joint by joint: see :class:`FKExplorer`."""
    return FKExplorer(skeleton, local_rotations, root_position, axes=axes)


# -- motion ------------------------------------------------------------------------------------


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


# -- inverse kinematics ------------------------------------------------------------------------


def _ik_methods() -> tuple[str, ...]:
    """The methods course.ik.solve offers: its registry, :mod:`course.ik.methods`."""
    from course.ik.methods import METHODS

    return METHODS


def _drag_pad(scene: SkeletonScene, center: ArrayLike, half: float | None, position: ArrayLike,
              on_drag: Any, size: int = 180, normal: Array | None = None,
              box: ArrayLike | None = None) -> Any:
    """A pad that drags the target in the plane the view's camera faces, or across
    ``normal`` (views that take no mouse: browser-rendered, static), see
    :mod:`course.viz.drag_pad`."""
    from .drag_pad import ViewPlaneDrag

    return ViewPlaneDrag(scene.plotter.camera, center, half, position, on_drag, size=size,
                         normal=normal, box=box)


def _hinge_plane_normal(skeleton: Any, joints: Sequence[int], orientations: Array
                        ) -> Array | None:
    """The world axis ``n`` of the hinges among ``joints`` when they all turn about it (a
    planar arm: what they move stays in planes across ``n``), else None (a ball or universal
    joint among them, hinges about two axes, no hinge). ``orientations``: the global
    orientations ``Q_j (J, 4)`` of the pose; a hinge's world axis is ``Q_j a_j``."""
    from course.rotations import quat_rotate

    axes = []
    for j in joints:
        a = _dof_axes(skeleton, j)
        if len(a) > 1:
            return None
        if len(a):
            axes.append(quat_rotate(orientations[j], a[0] / np.linalg.norm(a[0])))
    if not axes or any(np.linalg.norm(np.cross(a, axes[0])) > 1e-9 for a in axes):
        return None
    n: Array = axes[0]
    return n


def _ancestors(skeleton: Any, j: int) -> list[int]:
    """The joints above ``j``, from its parent to the root (those that move it)."""
    out = []
    while (j := int(skeleton.parents[j])) >= 0:
        out.append(j)
    return out


def _facing(normal: Array | None) -> str | None:
    """The camera preset that looks along ``normal`` (a world axis), if one does."""
    if normal is None:
        return None
    for preset, axis in (("front", 2), ("side", 0), ("top", 1)):
        if abs(normal[axis]) > 1 - 1e-9:
            return preset
    return None


def _pad_row(drag: Any, text: str = "drag the target in the view's plane:"
             ) -> list[widgets.Widget]:
    """The pad with a caption, for a control panel (nothing where the view takes the mouse)."""
    if drag is None:
        return []
    caption = widgets.HTML(text,
                           layout=widgets.Layout(margin="4px 0 2px 84px"))
    drag.pad.layout = widgets.Layout(margin="0 0 6px 84px", flex="0 0 auto")
    return [caption, drag.pad]


def _beside_pad(target_sliders: list[widgets.Widget], drag: Any) -> list[widgets.Widget]:
    """The x, y, z sliders with a small pad to their right, so that the panel grows by a
    line, not by the pad's height (the playground fits a 1366x768 window)."""
    if drag is None:
        return target_sliders
    caption = widgets.HTML("drag:", layout=widgets.Layout(margin="0 0 2px 0"))
    drag.pad.layout = widgets.Layout(flex="0 0 auto")
    # room on the right: a dot at the pad's edge (a target at full reach) stays clickable
    pad = widgets.VBox([caption, drag.pad], layout=widgets.Layout(margin="0 12px 4px 8px",
                                                                  overflow="visible"))
    return [widgets.HBox([widgets.VBox(target_sliders), pad],
                         layout=widgets.Layout(align_items="center"))]


class IKPlayground(Control):
    """Drag a target, pick a method, and watch IK solve it; an iteration slider replays the
    recorded solve, and the residual and iteration count update live.

    The solve runs once per event with ``record=True``; replaying iterations only moves points.
    ``methods`` are offered in the menu, which opens on ``method`` (default: the first listed,
    the one the notebook teaches).
    """

    def __init__(self, skeleton: Any, methods: Sequence[str] | None = None, *,
                 end_effector: int | str | None = None, target: ArrayLike | None = None,
                 local_rotations: ArrayLike | None = None, root_position: ArrayLike | None = None,
                 method: str | None = None, tol: float = 1e-4, max_iter: int = 100) -> None:
        from course.rotations import quat_identity

        methods = tuple(methods or _ik_methods())
        method = methods[0] if method is None else method  # the one the notebook teaches
        if method not in methods:
            raise ValueError(f"method must be one of {methods}, got {method!r}")
        self.skeleton = skeleton
        n = skeleton.n_joints
        self.effector = (n - 1 if end_effector is None else
                         skeleton.index(end_effector) if isinstance(end_effector, str)
                         else int(end_effector))
        self.start = (np.tile(quat_identity(), (n, 1)) if local_rotations is None
                      else np.array(local_rotations, dtype=np.float64).reshape(n, 4))
        self.root_position = (np.zeros(3) if root_position is None
                              else np.asarray(root_position, dtype=np.float64).reshape(3))
        start_pos, start_rot = skeleton.forward_kinematics(self.start, self.root_position)
        reach = float(np.linalg.norm(skeleton.offsets[1:], axis=1).sum())
        # a planar arm is seen face on, and its target dragged in its plane
        normal = _hinge_plane_normal(skeleton, _ancestors(skeleton, self.effector), start_rot)
        goal = (start_pos[self.effector] + np.array([-0.3, 0.4, 0.0]) * reach * 0.5
                if target is None else np.asarray(target, dtype=np.float64).reshape(3))
        center = start_pos[0]
        self.sliders = {
            **{c: widgets.FloatSlider(value=goal[k], min=center[k] - reach, max=center[k] + reach,
                                      step=reach / 200, description=f"target {c}",
                                      **slider_style(".2f"))
               for k, c in enumerate("xyz")},
            "method": widgets.Dropdown(options=list(methods), value=method,
                                       description="method", layout=widgets.Layout(width="260px")),
            "tol": widgets.FloatLogSlider(value=tol, base=10, min=-8, max=-1, step=0.5,
                                          description="tolerance",
                                          **slider_style(".0e")),
            "max_iter": widgets.IntSlider(value=max_iter, min=1, max=500, description="max iter",
                                          **slider_style("d")),
            "iteration": widgets.IntSlider(value=0, min=0, max=0, description="iteration",
                                           **slider_style("d")),
        }
        # the target (the sliders show it, rounded to their steps by the browser)
        self._goal: Array = np.array([self.sliders[c].value for c in "xyz"], dtype=np.float64)
        self.readout = readout_box(5, "360px")  # a long method name wraps the first line
        self.scene = SkeletonScene(window_size=(640, 500), camera=_facing(normal) or "iso")
        # framed: the chain's reach and the first target (which may lie beyond it)
        self.scene.add_skeleton(skeleton.parents, start_pos, name="start", color=GHOST,
                                opacity=0.55, frame_points=np.vstack([start_pos, goal]),
                                reach=reach)
        self.scene.add_skeleton(skeleton.parents, start_pos, name="solution")
        self.scene.add_trail(capacity=512)
        self.convergence = ConvergenceFigure(figsize=(4.6, 2.6))  # fits 1366x768 with the rest
        self.convergence_image = widgets.Image(format="png", width=420)
        self._solving = False
        self._dragging = False
        # where the view takes the mouse (trame), the target is also a sphere to drag;
        # elsewhere a pad drags it in the plane the camera faces
        self.handle = (self.scene.add_target_handle(goal, self._dragged)
                       if self.scene.draggable else None)
        self.drag = None if self.handle is not None else _drag_pad(
            self.scene, center, reach, goal, self._dragged, size=96, normal=normal)
        for k, name in enumerate("xyz"):
            on_value(self.sliders[name], lambda c, k=k: self._slider_moved(k, c["new"]))
        for name in ("method", "tol", "max_iter"):
            on_value(self.sliders[name], lambda _c: self.solve(plot_later=True))
        on_value(self.sliders["iteration"], lambda c: self.show_iteration(c["new"]))
        sliders = list(self.sliders.values())
        left = widgets.VBox([*_beside_pad(sliders[:3], self.drag), *sliders[3:], self.readout,
                             self.convergence_image])
        self.widget = _side_by_side(left, self.scene.widget())
        self.solve()

    @property
    def target(self) -> Array:
        """The target ``(3,)`` the solve aims at."""
        return np.array(self._goal, dtype=np.float64)  # a copy

    def _slider_moved(self, k: int, value: float) -> None:
        """Target slider ``k`` moved to ``value``: move the target there and solve (not for
        the browser's rounding of a value to the slider's steps, see :func:`_snapped`)."""
        if self._dragging or _snapped(self.sliders["xyz"[k]], self._goal[k], value):
            return
        self._goal[k] = value
        self.scene.move_target_handle(self.target)
        if self.drag is not None:
            self.drag.show(self.target)
        self.solve(plot_later=True)

    def _dragged(self, position: Array) -> None:
        """The handle was dragged to ``position``: the sliders follow, then one solve (a
        callback that did not move it, e.g. a click, changes nothing)."""
        position = _clipped(self.sliders, position)
        if np.allclose(position, self._goal):
            return
        self._goal = position
        self._dragging = True
        try:
            _set_sliders(self.sliders, position)
        finally:
            self._dragging = False
        self.solve(plot_later=True)

    def solve(self, *, plot_later: bool = False) -> None:
        """Solve IK from the start pose to the current target, recording every iterate (the
        residual plot once the kernel has sent the 3D picture, with ``plot_later``)."""
        import course.ik

        name = self.skeleton.names[self.effector]
        try:
            self.result = course.ik.solve(
                self.skeleton, self.start, self.root_position, {name: self.target},
                method=self.sliders["method"].value, tol=self.sliders["tol"].value,
                max_iter=self.sliders["max_iter"].value, record=True,
            )
        except ValueError as err:  # e.g. two_link on a longer chain: say why, keep the view
            self.readout.value = f"<span style='color:#a4161a'>{err}</span>"
            return
        assert self.result.frames is not None  # record=True keeps them
        self.frames = np.array([f["positions"] for f in self.result.frames], dtype=np.float64)
        self.scene.set_targets(self.target[None], render=False)
        it = self.sliders["iteration"]
        last = len(self.frames) - 1
        self._solving = True  # one render per event: not one more from the slider's observer
        try:
            it.max = max(last, 0)
            it.value = it.max
        finally:
            self._solving = False
        self.scene.set_trail(self.frames[:, self.effector])
        self.show_iteration(it.value)  # the 3D view first: it is what the student drags
        if plot_later:  # a student's move: the 3D picture goes out first, the PNG after it
            soon(self._plot_convergence)
        else:
            self._plot_convergence()

    def _plot_convergence(self) -> None:
        """Blit the new residual curve into the figure made once."""
        residuals = np.asarray(self.result.residuals, dtype=np.float64)
        title = f"{self.sliders['method'].value}: {_iterations(residuals.size - 1)}"
        self.convergence.update(residuals, self.sliders["tol"].value, title)
        self.convergence_image.value = self.convergence.png()

    def show_iteration(self, k: int) -> None:
        """Show the k-th recorded pose of the last solve."""
        if self._solving:
            return
        k = int(np.clip(k, 0, len(self.frames) - 1))
        pose = self.frames[k] if len(self.frames) else self.result.positions
        self.scene.set_pose(pose, name="solution")
        r = self.result
        residual = np.asarray(r.residuals, dtype=np.float64)
        state = "converged" if r.converged else f"not converged ({r.reason})"
        self.readout.value = (
            f"<b>{self.sliders['method'].value}</b>: {state} in "
            f"<b>{_iterations(int(r.iterations))}</b><br>residual at iteration {k}: "
            f"<b>{residual[min(k, residual.size - 1)]:.2e}</b> "
            f"(final {residual[-1]:.2e})"
            + _start_note(r)
        )


def _start_note(result: Any) -> str:
    """A readout line when the solve did not start from the start pose (IKResult.start)."""
    if result.start != "reach":
        return ""
    if result.reason == "unreachable":
        return "<br>out of reach: the chain is stretched towards the target"
    return "<br>started bent evenly: the target is near full reach"


def ik_playground(skeleton: Any, methods: Sequence[str] | None = None, **kwargs: Any
                  ) -> IKPlayground:
    """Play with IK on a chain or skeleton: see :class:`IKPlayground`."""
    return IKPlayground(skeleton, methods, **kwargs)


class FullBodyIK(Control):
    """IK on one frame of a clip: choose the root joint (the one that stays put), the end
    effectors and their targets; the captured pose (grey) stays beside the solution.

    The panel (``PANEL_WIDTH``) and the view (``VIEW_BASIS`` wide, growing to its window's
    width) fit side by side in ``PANEL_WIDTH + 12 + VIEW_BASIS`` pixels: a notebook beside
    JupyterLab's file browser at 1366 px keeps the pad and the view on screen together.
    When a solve fails, the view keeps the last solved pose, dimmed, and the readout says so.
    """

    PANEL_WIDTH = 360  # px: the sliders (340) and the readout
    PAD_SIZE = 120  # px: the drag pad, under the sliders
    VIEW_BASIS = 520  # px: the view's width before it grows (up to its 640 px window)
    STALE_OPACITY = 0.3  # the IK skeleton while it shows a pose that is not the setting's

    def __init__(self, motion: Any, frame: int = 0, *, root: str | None = None,
                 effectors: Sequence[str] | None = None, method: str | None = None) -> None:
        sk = motion.skeleton
        self.skeleton = sk
        self.local = np.array(motion.local_rotations[frame])
        self.root_position = np.array(motion.root_positions[frame])
        self.positions, _ = sk.forward_kinematics(self.local, self.root_position)
        names = list(sk.names)
        leaves = [n for j, n in enumerate(names) if not sk.children(j)]
        effectors = list(effectors or [n for n in leaves if "Hand" in n or "Foot" in n][:2]
                         or leaves[:1])
        # every target starts on its joint: the first picture is the captured pose
        self.targets = {e: self.positions[sk.index(e)].copy() for e in names}
        start = self.targets[effectors[0]] - self.root_position
        height = float(np.ptp(self.positions[:, 1]))
        # targets move within a box around the captured pose; the view frames that box, so
        # no target and no pose pulled towards one leaves the picture
        margin = 0.3 * height
        box = np.stack([self.positions.min(axis=0) - margin, self.positions.max(axis=0) + margin])
        box[0, 1] = self.positions[:, 1].min()  # not under the floor
        lo, hi = box - self.root_position
        methods = _ik_methods()
        self.sliders = {
            "root": widgets.Dropdown(options=names, value=root or names[0], description="root"),
            # any joint can be pulled (a hand, an elbow); the tips are offered first
            "effectors": widgets.SelectMultiple(
                options=leaves + [n for n in names if n not in leaves],
                value=tuple(effectors), description="effectors", rows=5),
            "edit": widgets.Dropdown(options=list(effectors), description="edit target"),
            "method": widgets.Dropdown(options=list(methods),
                                       value=method or ("dls" if "dls" in methods else methods[0]),
                                       description="method"),
            **{c: widgets.FloatSlider(value=start[k], min=lo[k], max=hi[k],
                                      step=height / 200, description=f"target {c}",
                                      **slider_style(".1f")) for k, c in enumerate("xyz")},
        }
        self.readout = readout_box(4, f"{self.PANEL_WIDTH}px")
        self.stale = False
        self.scene = SkeletonScene(window_size=(640, 520))
        corners = np.stack(np.meshgrid(*box.T, indexing="ij"), axis=-1).reshape(-1, 3)
        self.scene.add_skeleton(sk.parents, self.positions, name="captured", color=GHOST,
                                opacity=0.6, frame_points=np.concatenate([self.positions,
                                                                          corners]))
        self.scene.add_skeleton(sk.parents, self.positions, name="IK")
        self._editing = False
        self.handle = (self.scene.add_target_handle(self.targets[effectors[0]], self._dragged)
                       if self.scene.draggable else None)
        # the pad is the face of the sliders' box that the camera sees most (x-y or z-y): its
        # corners are two sliders' limits, its middle their middles; the third keeps its value
        camera = self.scene.plotter.camera
        toward = np.abs(np.subtract(camera.position, camera.focal_point))
        self.drag = None if self.handle is not None else _drag_pad(
            self.scene, box.mean(axis=0), None, self.targets[effectors[0]], self._dragged,
            size=self.PAD_SIZE, normal=np.eye(3)[0 if toward[0] > toward[2] else 2],
            box=np.ptp(box, axis=0) / 2)
        on_value(self.sliders["effectors"], lambda _c: self._effectors_changed())
        on_value(self.sliders["edit"], lambda _c: self._load_target())
        for k in ("root", "method"):
            on_value(self.sliders[k], lambda _c: self.solve())
        for axis, c in enumerate("xyz"):
            on_value(self.sliders[c], lambda ch, axis=axis: self._target_moved(axis, ch["new"]))
        # the x/y/z sliders are offsets from the captured root joint (not world coordinates)
        origin = widgets.HTML(f"target, from the captured <b>{sk.names[0]}</b>:",
                              layout=widgets.Layout(margin="2px 0 0 8px"))
        controls = list(self.sliders.values())
        width = f"{self.PANEL_WIDTH}px"
        pad = _pad_row(self.drag, self._pad_caption())
        self.panel = widgets.VBox([*controls[:4], origin, *controls[4:], *pad, self.readout],
                                  layout=widgets.Layout(width=width, min_width=width))
        view = self.scene.widget()
        # it starts at VIEW_BASIS on the panel's line and grows to the window's width; never
        # wider than the notebook, never under 320 px (then it wraps below the panel)
        view.layout.flex = f"1 1 {self.VIEW_BASIS}px"
        view.layout.width = None
        view.layout.max_width = f"min(100%, {self.scene.plotter.window_size[0]}px)"
        self.widget = _side_by_side(self.panel, view)
        self.panel.layout.flex = "0 0 auto"
        self.panel.layout.margin = "0 12px 0 0"
        self._load_target()

    def _effectors_changed(self) -> None:
        chosen = list(self.sliders["effectors"].value)
        self.sliders["edit"].options = chosen
        self._load_target()

    def _load_target(self) -> None:
        """Put the edited effector's target into the x/y/z sliders (relative to the
        captured root), then solve once."""
        name = self.sliders["edit"].value
        self._editing = True
        if name is not None:
            rel = self.targets[name] - self.root_position
            for k, c in enumerate("xyz"):
                self.sliders[c].value = float(rel[k])
            self._show_target(self.targets[name])
        self._editing = False
        self.solve()

    def _target_moved(self, k: int, value: float) -> None:
        """Target slider ``k`` moved to ``value`` (from the root): move the edited target and
        solve (not for the browser's rounding to the slider's steps, see :func:`_snapped`)."""
        name = self.sliders["edit"].value
        if self._editing or name is None:
            return
        old = self.targets[name][k] - self.root_position[k]
        if _snapped(self.sliders["xyz"[k]], old, value):
            return
        self.targets[name][k] = self.root_position[k] + value
        self._show_target(self.targets[name])
        self.solve()

    def _show_target(self, position: Array) -> None:
        """The drag handle or the pad's dot follows a target set otherwise."""
        self.scene.move_target_handle(position)
        if self.drag is not None:
            self.drag.show(position)

    def _dragged(self, position: Array) -> None:
        """The handle was dragged: the edited effector's target (and its sliders) follow."""
        name = self.sliders["edit"].value
        if name is None:
            return
        position = self.root_position + _clipped(self.sliders, position - self.root_position)
        if np.allclose(position, self.targets[name]):
            return
        self.targets[name] = position
        self._editing = True
        try:
            _set_sliders(self.sliders, position - self.root_position)
        finally:
            self._editing = False
        self.solve()

    def solve(self) -> None:
        import course.ik

        chosen = list(self.sliders["effectors"].value)
        targets = {e: self.targets[e] for e in chosen}
        try:
            self.result = course.ik.solve(
                self.skeleton, self.local, self.root_position, targets,
                method=self.sliders["method"].value, root=self.sliders["root"].value,
            )
        except ValueError as err:  # e.g. an effector on the root's side: say why
            self._mark_stale(True)
            self.readout.value = (
                f"<span style='color:#a4161a'>{err}</span><br><i style='color:#6b7480'>the "
                "view shows the last solved pose (dimmed), not this setting</i>")
            return
        self._mark_stale(False, render=False)
        self.scene.set_targets(np.array(list(targets.values())) if targets
                               else np.empty((0, 3)), render=False)
        self.scene.set_pose(self.result.positions, name="IK")
        r = self.result
        residual = np.asarray(r.residuals, dtype=np.float64)
        self.readout.value = (
            f"root <b>{self.sliders['root'].value}</b>, {len(chosen)} effector(s): "
            f"{'converged' if r.converged else f'not converged ({r.reason})'}, "
            f"{_iterations(int(r.iterations))}, residual {residual[-1]:.2e}"
        )


    def _pad_caption(self) -> str:
        """Which sliders the pad moves, e.g. "drag target x → and y ↑ (z: its slider)"."""
        if self.drag is None:
            return ""
        right, up, depth = (int(np.argmax(np.abs(a))) for a in
                            (self.drag.right, self.drag.up, self.drag.depth_axis))
        sign = "" if self.drag.right[right] > 0 else "−"
        return (f"drag target {sign}{'xyz'[right]} → and {'xyz'[up]} ↑ "
                f"({'xyz'[depth]}: its slider):")

    def _mark_stale(self, stale: bool, *, render: bool = True) -> None:
        """Dim the IK skeleton while it shows a pose the current setting did not solve."""
        if stale == self.stale:
            return
        self.stale = stale
        for actor in self.scene.skeleton("IK").actors:
            actor.prop.opacity = self.STALE_OPACITY if stale else 1.0
        if render:
            self.scene.render()


def full_body_ik(motion: Any, frame: int = 0, **kwargs: Any) -> FullBodyIK:
    """Full-body IK on a frame of a clip: see :class:`FullBodyIK`."""
    return FullBodyIK(motion, frame, **kwargs)
