"""Rotation views (ipywidgets): Euler angles with their matrix, quaternion and gimbal rings,
and LERP / NLERP / SLERP between two rotations side by side."""

from __future__ import annotations

from typing import Any

import ipywidgets as widgets
import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .figures import GimbalFigure, SlerpArcFigure
from .frame_scene import FrameScene
from .panel import (
    Control,
    angle_slider,
    matrix_html,
    on_value,
    readout_box,
    side_by_side,
    slider_style,
    vec,
)


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
        self.sliders = {f"angle{k}": angle_slider(f"angle {k + 1}", v)
                        for k, v in enumerate(a_deg)}
        self.readout = readout_box(9)  # the matrix rows are taller than a line of text
        self.warning = readout_box(4)  # reserved: the lock warning never moves the views
        self.scene = FrameScene(1, window_size=(380, 340))
        self.gimbal = GimbalFigure(order, np.radians(a_deg))
        self.gimbal_image = widgets.Image(format="png", width=340)
        controls = widgets.VBox([self.order, *self.sliders.values(), self.warning, self.readout],
                                layout=widgets.Layout(width="350px"))
        self.widget = side_by_side(controls, self.scene.widget(), self.gimbal_image)
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
            f"<b>{kind}{product}</b>{matrix_html(self.matrix)}"
            f"<b>q</b> = (w, x, y, z) = {vec(self.quaternion)}<br>"
            f"<b>axis</b> = {vec(axis)}, <b>angle</b> = {np.degrees(angle):.1f}&deg;"
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
            **{f"start{k}": angle_slider(f"start {c}", v) for k, (c, v) in
               enumerate(zip("XYZ", np.ravel(start), strict=True))},
            **{f"end{k}": angle_slider(f"end {c}", v) for k, (c, v) in
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
        self.widget = widgets.VBox([self.scene.widget(), side_by_side(
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
            f"<tr><td style='padding:1px 10px 1px 0'><b>{k}</b></td>{cell}{vec(v)}</td>"
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
