"""The forward-kinematics explorer (ipywidgets): one slider per degree of freedom, the pose
and its numbers live."""

from __future__ import annotations

from typing import Any

import ipywidgets as widgets
import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .backend import latest_on_gl_thread
from .panel import (
    Control,
    angle_slider,
    dof_axes,
    facing_camera,
    fixed_height,
    hinge_plane_normal,
    on_value,
    readout_box,
    side_by_side,
    vec,
)
from .scene import SkeletonScene


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
        self.axes = {j: dof_axes(skeleton, j) for j in range(n)}
        self.sliders: dict[str, widgets.FloatSlider] = {}
        groups, titles = [], []
        for j, ax in self.axes.items():
            if len(ax) == 0:
                continue
            row = []
            for k, a in enumerate(ax):
                label = "xyz"[int(np.argmax(np.abs(a)))] if np.count_nonzero(a) == 1 else f"a{k}"
                s = angle_slider(label, 0.0, limit)
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
        normal = hinge_plane_normal(skeleton, range(n), self.orientations)
        self.scene = SkeletonScene(window_size=(640, 520), camera=facing_camera(normal) or "iso")
        self.scene.add_skeleton(skeleton.parents, self.positions, self.orientations,
                                name="pose", axes=axes, frame_points=self.positions, reach=reach)
        # the readout above the joint list, which scrolls: it stays in sight while posing
        self.accordion.layout = widgets.Layout(max_height="400px", overflow="auto",
                                               flex="0 1 auto")
        left = widgets.VBox([self.reset_button, self.readout, self.accordion],
                            layout=widgets.Layout(width="400px"))
        self.widget = side_by_side(left, self.scene.widget())
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
            f"<b>{name}</b>: R<sub>j</sub> = {vec(self.local_rotations[j])}<br>"
            f"Q<sub>j</sub> = {vec(self.orientations[j])}<br>"
            f"p<sub>j</sub> = {vec(self.positions[j], '+.2f')}"
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
