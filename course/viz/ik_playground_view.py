"""The IK playground (ipywidgets): drag a target, pick a method, replay the solve iteration by
iteration beside its residual curve."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import ipywidgets as widgets
import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .backend import soon
from .figures import ConvergenceFigure
from .panel import (
    Control,
    ancestors,
    clipped_to_sliders,
    facing_camera,
    hinge_plane_normal,
    ik_methods,
    iterations,
    on_value,
    readout_box,
    set_sliders,
    side_by_side,
    slider_style,
    snapped,
    target_drag_pad,
)
from .scene import GHOST, SkeletonScene


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

        methods = tuple(methods or ik_methods())
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
        normal = hinge_plane_normal(skeleton, ancestors(skeleton, self.effector), start_rot)
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
        self.scene = SkeletonScene(window_size=(640, 500), camera=facing_camera(normal) or "iso")
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
        self.drag = None if self.handle is not None else target_drag_pad(
            self.scene, center, reach, goal, self._dragged, size=96, normal=normal)
        for k, name in enumerate("xyz"):
            on_value(self.sliders[name], lambda c, k=k: self._slider_moved(k, c["new"]))
        for name in ("method", "tol", "max_iter"):
            on_value(self.sliders[name], lambda _c: self.solve(plot_later=True))
        on_value(self.sliders["iteration"], lambda c: self.show_iteration(c["new"]))
        sliders = list(self.sliders.values())
        left = widgets.VBox([*_beside_pad(sliders[:3], self.drag), *sliders[3:], self.readout,
                             self.convergence_image])
        self.widget = side_by_side(left, self.scene.widget())
        self.solve()

    @property
    def target(self) -> Array:
        """The target ``(3,)`` the solve aims at."""
        return np.array(self._goal, dtype=np.float64)  # a copy

    def _slider_moved(self, k: int, value: float) -> None:
        """Target slider ``k`` moved to ``value``: move the target there and solve (not for
        the browser's rounding of a value to the slider's steps, see
        :func:`~course.viz.panel.snapped`)."""
        if self._dragging or snapped(self.sliders["xyz"[k]], self._goal[k], value):
            return
        self._goal[k] = value
        self.scene.move_target_handle(self.target)  # in the picture the solve draws
        self.solve(plot_later=True)
        if self.drag is not None:  # after the 3D picture has gone out, not before it
            self.drag.show(self.target)

    def _dragged(self, position: Array) -> None:
        """The handle was dragged to ``position``: the sliders follow, then one solve (a
        callback that did not move it, e.g. a click, changes nothing)."""
        position = clipped_to_sliders(self.sliders, position)
        if np.allclose(position, self._goal):
            return
        self._goal = position
        self._dragging = True
        try:
            set_sliders(self.sliders, position)
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
        title = f"{self.sliders['method'].value}: {iterations(residuals.size - 1)}"
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
            f"<b>{iterations(int(r.iterations))}</b><br>residual at iteration {k}: "
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
