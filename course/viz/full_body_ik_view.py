"""Full-body IK (ipywidgets): one frame of a clip, a root joint, end effectors and their
targets; the solution beside the captured pose."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import ipywidgets as widgets
import numpy as np

from .._typing import Array
from .backend import call_later, soon
from .panel import (
    Control,
    clipped_to_sliders,
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


def _pad_row(drag: Any, text: str = "drag the target in the view's plane:"
             ) -> list[widgets.Widget]:
    """The pad with a caption, for a control panel (nothing where the view takes the mouse)."""
    if drag is None:
        return []
    caption = widgets.HTML(text,
                           layout=widgets.Layout(margin="4px 0 2px 84px"))
    drag.pad.layout = widgets.Layout(margin="0 0 6px 84px", flex="0 0 auto")
    return [caption, drag.pad]


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
    # a solve not done after these many iterations shows its pose at once (a few ms of FABRIK
    # on the CMU body), then runs to its end: the view answers a key press without waiting
    # for a solve that crawls near the reach (up to 200 iterations, ~0.4 s)
    PREVIEW_ITERATIONS = 2

    def __init__(self, motion: Any, frame: int = 0, *, root: str | None = None,
                 effectors: Sequence[str] | None = None, method: str | None = None) -> None:
        """The view of ``motion``'s ``frame``: ``root`` stays put (default joint 0), the
        ``effectors`` (default the first two hands or feet) start on their joints, and
        ``method`` names the solver (default DLS where available)."""
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
        methods = ik_methods()
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
        self._result: Any = None  # the current setting's IKResult (see result)
        self._pending: Callable[[], None] | None = None  # the rest of an unfinished solve
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
        self.drag = None if self.handle is not None else target_drag_pad(
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
        self.widget = side_by_side(self.panel, view)
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
        solve (not for the browser's rounding to the slider's steps, see
        :func:`~course.viz.panel.snapped`)."""
        name = self.sliders["edit"].value
        if self._editing or name is None:
            return
        old = self.targets[name][k] - self.root_position[k]
        if snapped(self.sliders["xyz"[k]], old, value):
            return
        self.targets[name][k] = self.root_position[k] + value
        self.scene.move_target_handle(self.targets[name])  # in the picture the solve draws
        self.solve()
        if self.drag is not None:  # after the 3D picture has gone out, not before it
            self.drag.show(self.targets[name])

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
        position = self.root_position + clipped_to_sliders(self.sliders,
                                                           position - self.root_position)
        if np.allclose(position, self.targets[name]):
            return
        self.targets[name] = position
        self._editing = True
        try:
            set_sliders(self.sliders, position - self.root_position)
        finally:
            self._editing = False
        self.solve()

    def solve(self) -> None:
        """Solve for the current setting. A solve still running after ``PREVIEW_ITERATIONS``
        shows that pose at once and finishes once it is on the screen (the same solve run to
        its end, so the final pose is the uninterrupted solve's); a newer setting makes the
        unfinished one moot (latest wins), and reading :attr:`result` finishes it."""
        chosen = list(self.sliders["effectors"].value)
        targets = {e: self.targets[e] for e in chosen}
        self._pending = None
        try:
            first = self._solve(targets, self.PREVIEW_ITERATIONS)
        except ValueError as err:  # e.g. an effector on the root's side: say why
            self._mark_stale(True)
            self.readout.value = (
                f"<span style='color:#a4161a'>{err}</span><br><i style='color:#6b7480'>the "
                "view shows the last solved pose (dimmed), not this setting</i>")
            return
        if first.converged or first.reason != "max_iterations":  # done within the preview
            self._show(first, targets)
            return
        self._show(first, targets, solving=True)

        def finish() -> None:
            self._show(self._solve(targets), targets)

        self._pending = finish
        asked = time.monotonic()
        soon(lambda: self._when_shown(finish, asked))

    def _solve(self, targets: Mapping[str | int, Array], max_iter: int | None = None) -> Any:
        import course.ik

        return course.ik.solve(self.skeleton, self.local, self.root_position, targets,
                               method=self.sliders["method"].value,
                               root=self.sliders["root"].value, max_iter=max_iter)

    def _when_shown(self, pending: Callable[[], None], asked: float) -> None:
        """Finish ``pending`` once the preview is on the student's screen: a browser-drawn
        view fetches the picture's arrays from the kernel, which a solve would hold up (one
        that never answers is waited for 1 s at most)."""
        if pending is not self._pending:
            return
        if self.scene.pictures_in_flight() and time.monotonic() - asked < 1.0:
            call_later(0.002, lambda: self._when_shown(pending, asked))
            return
        self._finish(pending)

    def _finish(self, pending: Callable[[], None] | None = None) -> None:
        """Run the pending solve to its end (only ``pending``, if given: a newer one
        replaced an older)."""
        if self._pending is not None and (pending is None or pending is self._pending):
            finish, self._pending = self._pending, None
            finish()

    @property
    def result(self) -> Any:
        """The :class:`~course.ik.IKResult` of the current setting (finished if pending)."""
        self._finish()
        return self._result

    def _show(self, r: Any, targets: dict[str, Array], *, solving: bool = False) -> None:
        self._result = r
        self._mark_stale(False, render=False)
        self.scene.set_targets(np.array(list(targets.values())) if targets
                               else np.empty((0, 3)), render=False)
        self.scene.set_pose(r.positions, name="IK")
        residual = np.asarray(r.residuals, dtype=np.float64)
        state = (f"solving… ({iterations(int(r.iterations))} so far)" if solving else
                 "converged" if r.converged else f"not converged ({r.reason})")
        self.readout.value = (
            f"root <b>{self.sliders['root'].value}</b>, {len(targets)} effector(s): "
            f"{state}{'' if solving else ', ' + iterations(int(r.iterations))}, "
            f"residual {residual[-1]:.2e}"
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
