"""3D skeleton views (pyvista), updated in place.

A :class:`SkeletonScene` holds one or more skeletons, each drawn from a few VTK meshes whose
point arrays are overwritten on every change: a point set glyphed with spheres on the GPU
(joints), a line set run through a tube filter (bones), a line set of axis triads, target
markers and an end-effector trail. A slider event therefore costs a copy of ``(J, 3)`` floats
and one render; nothing is rebuilt.

The core takes plain arrays (``parents``, ``positions (J, 3)``, optional ``orientations
(J, 4)``), so it draws anything: a hand-made chain, a :class:`course.skeleton.Skeleton` pose,
a BVH frame. y is up.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import Array
from .backend import configure_environment
from .framing import CAMERA_PRESETS, Framing
from .live_view import LiveView, shade
from .meshes import (
    FLOOR_COLORS,
    Trail,
    as_parents,
    as_positions,
    floor_plane,
    overwrite,
    sphere_actor,
)
from .skeleton_actors import SkeletonActors

if TYPE_CHECKING:
    import ipywidgets as widgets

configure_environment()

import pyvista as pv  # noqa: E402  (after the environment is set: VTK reads it on import)
from vtkmodules.vtkInteractionWidgets import vtkSphereWidget  # noqa: E402

#: (bone colour, joint colour) per skeleton, in the order skeletons are added.
PALETTE: tuple[tuple[str, str], ...] = (
    ("#3d7dca", "#ffb000"),  # blue bones, amber joints: the student's / main skeleton
    ("#8f9aa6", "#4a5561"),  # greys: the reference / before
    ("#2bb673", "#e5484d"),  # green bones, red joints: after IK
    ("#8e6bd8", "#f08c3a"),
)
#: (bone colour, joint colour) of a faint pose drawn for comparison (before IK, the capture).
GHOST = ("#aab4bf", "#8793a0")
TARGET_COLOR = "#e5484d"
# a target's sphere, translucent, about twice a joint's: it shows around a hand's finger joints
TARGET_RADIUS = 0.05
POLE_COLOR = "#8e3bd1"  # violet, as the pole's diamond in the 2D figures (chain_plots.ACCENT)
TRAIL_COLOR = "#d1347a"


class SkeletonScene(LiveView):
    """A pyvista scene of skeletons, targets and trails, updated in place.

    Parameters
    ----------
    window_size : (width, height) in pixels.
    ground : draw a checkered floor in the plane ``y = ground height`` (y is up).
    camera : one of ``"iso"``, ``"front"`` (looking down -z), ``"side"`` (down -x), ``"top"``
        (down -y), ``"follow"`` (iso, then moving with the root).

    Examples
    --------
    >>> scene = SkeletonScene()
    >>> scene.add_skeleton(parents, positions, name="student")   # doctest: +SKIP
    >>> scene.set_pose(new_positions)                            # doctest: +SKIP
    >>> scene.screenshot("pose.png")                             # doctest: +SKIP
    """

    def __init__(
        self,
        *,
        window_size: tuple[int, int] = (720, 540),
        ground: bool = True,
        camera: str = "iso",
    ) -> None:
        if camera not in CAMERA_PRESETS:
            raise ValueError(f"camera must be one of {CAMERA_PRESETS}, got {camera!r}")
        super().__init__(window_size)
        self.skeletons: dict[str, SkeletonActors] = {}
        self.framing = Framing()  # measured from the first skeleton
        self.trail: Trail | None = None  # see add_trail
        self._legend: widgets.HTML | None = None  # HTML above a view rendered in the browser
        self._ground_wanted = ground
        self.floor_height: float | None = None  # the drawn floor's y, once a skeleton framed it
        self._camera = camera
        self._follow: tuple[str, Array] | None = None  # (skeleton, root position at last move)
        self._targets: pv.PolyData | None = None
        self._targets_actor: pv.Actor | None = None
        self._pole: pv.PolyData | None = None
        self._handle: vtkSphereWidget | None = None  # the draggable target sphere

    # -- building (once) -------------------------------------------------------------------

    def add_skeleton(
        self,
        parents: ArrayLike,
        positions: ArrayLike,
        orientations: ArrayLike | None = None,
        *,
        name: str | None = None,
        color: tuple[str, str] | None = None,
        axes: bool = False,
        opacity: float = 1.0,
        frame_points: ArrayLike | None = None,
        reach: float | None = None,
    ) -> SkeletonActors:
        """Add a skeleton drawn as spheres (joints) and tubes (bones).

        Parameters
        ----------
        parents : (J,) parent indices, ``parents[0] == -1``, parent before child.
        positions : (J, 3) global joint positions ``p_j``.
        orientations : (J, 4) global orientations ``Q_j`` (w, x, y, z); needed for ``axes``.
        name : label in the legend (default ``"skeleton"``, ``"skeleton 2"``, ...).
        color : (bone colour, joint colour); default: the first entry of :data:`PALETTE` that
            no skeleton of the scene uses yet (a :data:`GHOST` beside it leaves blue first).
        axes : draw each joint's local frame (x red, y green, z blue).
        opacity : below 1, a faint pose for comparison (drawn a little thinner, see
            :data:`FAINT_SIZE`).
        frame_points : (..., 3) points the camera and floor must cover (e.g. a whole clip);
            default: this pose. Only the first skeleton sets the framing. A clip's frames
            ``(F, N, 3)`` whose point 0 is the root: the ``follow`` camera frames their
            largest extent about the root (every pose fills the view as it walks).
        reach : frame the whole sphere of this radius about the root as well (a chain that
            can turn anywhere: sliders never take it out of view).
        """
        par = as_parents(parents)
        pos = as_positions(positions, par.size)
        name = name or ("skeleton" if not self.skeletons else f"skeleton {len(self.skeletons) + 1}")
        if name in self.skeletons:
            raise ValueError(f"name {name!r} is already used in this scene")
        used = {sk.bone_color for sk in self.skeletons.values()}
        colors = color or next(
            (c for c in PALETTE if c[0] not in used), PALETTE[len(self.skeletons) % len(PALETTE)])
        if not self.skeletons:
            self._frame(pos, par, frame_points, reach)
        skel = SkeletonActors.build(name, par, pos, colors, scale=self.framing.scale,
                                    opacity=opacity, axes=axes, browser=self._in_browser)
        for actor in skel.actors:
            self.plotter.add_actor(actor, reset_camera=False, pickable=False)
        self.skeletons[name] = skel
        if skel.triads is not None:
            skel.move(pos, orientations)
        if len(self.skeletons) == 1 and self._camera == "follow":  # now it has a root to follow
            self.set_camera("follow")
        self._update_legend()
        return skel


    def _frame(self, pose: Array, parents: NDArray[np.intp], frame_points: ArrayLike | None,
               reach: float | None) -> None:
        """Measure the framing from the first skeleton (see :meth:`add_skeleton`); place the
        floor and the camera."""
        clip = None if frame_points is None else np.asarray(frame_points, np.float64)
        envelope = None
        if clip is not None and clip.ndim == 3:
            # whole frames (a stride over all points could skip a joint in every frame)
            clip = clip[:: max(1, clip.shape[0] * clip.shape[1] // 4000)]
            # about each frame's root, on the floor
            envelope = (clip - clip[:, :1] * [1.0, 0.0, 1.0]).reshape(-1, 3)
        pts = pose if clip is None else clip.reshape(-1, 3)
        if reach is not None:  # the sphere's six extremes
            pts = np.concatenate([pts, pose[0] + reach * np.concatenate([np.eye(3), -np.eye(3)])])
        self.framing = Framing.of(pts, pose, parents, sphere=reach is not None, envelope=envelope,
                                  headroom=frame_points is None and reach is None)
        if self._ground_wanted:
            plane = floor_plane(pts.min(axis=0), pts.max(axis=0), self.framing.center,
                                self.framing.scale)
            self.plotter.add_mesh(
                plane, scalars="tile", cmap=list(FLOOR_COLORS), show_scalar_bar=False,
                ambient=0.35, diffuse=0.7, specular=0.0, pickable=False, reset_camera=False)
            self.floor_height = float(plane.bounds[2])
        self.set_camera(self._camera)

    def legend_entries(self) -> list[tuple[str, str]]:
        """(name, bone colour) of each skeleton, as the legend shows them; with a pole shown
        (:meth:`set_pole`), also the target's and the pole's marker colours."""
        entries = [(s.name, s.bone_color) for s in self.skeletons.values()]
        if self._pole is not None:
            entries += [("target", TARGET_COLOR), ("pole", POLE_COLOR)]
        return entries

    def _legend_html(self) -> str:
        return "".join(
            f"<span style='margin-right:14px;white-space:nowrap'><span style='display:inline-block;"
            f"width:10px;height:10px;border-radius:5px;background:{color};margin-right:5px'>"
            f"</span>{name}</span>" for name, color in self.legend_entries())

    def _update_legend(self) -> None:
        if len(self.legend_entries()) < 2:
            return
        if self._in_browser:  # vtk.js draws no 2D actors: the legend is HTML above the view
            if self._legend is not None:
                self._legend.value = self._legend_html()
            return
        entries = self.legend_entries()
        self.plotter.renderer.remove_legend(render=False)
        self.plotter.renderer.add_legend(
            [list(entry) for entry in entries],
            bcolor="white", border=False, face="circle", loc="upper right",
            size=(0.15, 0.06 * len(entries)),  # pyvista pads wider boxes off-screen
        )

    # -- updating (per event, in place) ------------------------------------------------------

    def skeleton(self, name: str | None = None) -> SkeletonActors:
        """The skeleton called ``name`` (default: the first one added)."""
        if not self.skeletons:
            raise ValueError("the scene has no skeleton yet: call add_skeleton first")
        if name is None:
            return next(iter(self.skeletons.values()))
        if name not in self.skeletons:
            raise ValueError(f"name {name!r} is not in this scene ({list(self.skeletons)})")
        return self.skeletons[name]

    @property
    def joint_positions(self) -> Array:
        """The first skeleton's drawn joint positions ``(J, 3)``."""
        return self.skeleton().positions

    def set_pose(
        self,
        positions: ArrayLike,
        orientations: ArrayLike | None = None,
        *,
        name: str | None = None,
        render: bool = True,
    ) -> None:
        """Move a skeleton: overwrite its points (and triads); no mesh is rebuilt."""
        skel = self.skeleton(name)
        pos = skel.move(positions, orientations)
        if self._follow is not None and self._follow[0] == skel.name:
            self._follow_root(*self._follow, pos[0])
        if render:
            self.render()

    def _add_marker(self, points: pv.PolyData, color: str, opacity: float) -> pv.Actor:
        """Translucent spheres, a target's size, at ``points``."""
        actor = sphere_actor(points, radius=TARGET_RADIUS * self.framing.scale,
                             browser=self._in_browser)
        shade(actor, color, opacity=opacity)
        self.plotter.add_actor(actor, reset_camera=False, pickable=False)
        return actor

    def set_targets(self, targets: ArrayLike, *, render: bool = True) -> None:
        """Show target markers at ``targets (K, 3)``; the marker mesh is made once per K."""
        t = np.asarray(targets, dtype=np.float64).reshape(-1, 3)
        if not np.all(np.isfinite(t)):
            raise ValueError("targets contains NaN or infinite values")
        if self._targets is None or self._targets.n_points != len(t):
            if self._targets_actor is not None:
                self.plotter.remove_actor(self._targets_actor, render=False)
            self._targets = pv.PolyData(t.copy())
            self._targets_actor = self._add_marker(self._targets, TARGET_COLOR, 0.45)
        else:
            overwrite(self._targets.points, t)
            self._targets.Modified()
        if render:
            self.render()

    def set_pole(self, position: ArrayLike, *, render: bool = True) -> None:
        """Show the pole (the point a middle joint bends towards) at ``position (3,)``: a
        violet sphere, so it is not taken for a target, named in the legend."""
        p = as_positions(np.reshape(position, (1, 3)), 1, "position")
        if self._pole is None:
            self._pole = pv.PolyData(p.copy())
            self._add_marker(self._pole, POLE_COLOR, 0.6)
            self._update_legend()
        else:
            overwrite(self._pole.points, p)
            self._pole.Modified()
        if render:
            self.render()

    @property
    def pole_position(self) -> Array | None:
        """The drawn pole ``(3,)``, or None."""
        return None if self._pole is None else np.array(self._pole.points[0])

    @property
    def draggable(self) -> bool:
        """True when the view sends the mouse to the kernel (server-rendered trame), so a
        target handle can be dragged; an image or a browser-rendered view cannot."""
        return self.backend in ("trame", "server")

    def add_target_handle(self, position: ArrayLike, on_drag: Callable[[Array], None]
                          ) -> vtkSphereWidget:
        """A sphere at ``position (3,)`` that the student drags with the mouse in an interactive
        view (trame; a static image has no mouse): ``on_drag(p)`` gets each new centre
        ``p (3,)`` while it moves. Returns the VTK widget (see :meth:`move_target_handle`)."""
        p = as_positions(np.reshape(position, (1, 3)), 1, "position")[0]
        self._handle = self.plotter.widgets.add_sphere_widget(
            lambda center: on_drag(np.asarray(center, dtype=np.float64)), center=tuple(p),
            radius=0.045 * self.framing.scale, color=TARGET_COLOR, selected_color="#ff8a8e",
            interaction_event="always", test_callback=False,  # made where it is: no move
        )
        return self._handle

    def move_target_handle(self, position: ArrayLike) -> None:
        """Put the drag handle (if any) at ``position (3,)``, e.g. after a slider moved it."""
        if self._handle is not None:
            self._handle.SetCenter(*np.asarray(position, dtype=np.float64).reshape(3))

    @property
    def target_positions(self) -> Array:
        """The drawn target markers ``(K, 3)`` (empty when none)."""
        return np.empty((0, 3)) if self._targets is None else np.array(self._targets.points)

    def add_trail(self, capacity: int = 240) -> None:
        """Prepare an end-effector trail of up to ``capacity`` points (a fixed-size polyline)."""
        self.trail = Trail(self.plotter, capacity, TRAIL_COLOR)

    def _existing_trail(self, call: str) -> Trail:
        """The trail, which ``call`` needs (a ValueError before :meth:`add_trail`)."""
        if self.trail is None:
            raise ValueError(f"call add_trail() before {call}()")
        return self.trail

    def push_trail(self, point: ArrayLike) -> None:
        """Append a point to the trail (the oldest drops out when full); unused slots repeat
        the newest point, so the polyline keeps its size and nothing is reallocated."""
        self._existing_trail("push_trail").push(point)

    def set_trail(self, points: ArrayLike) -> None:
        """Replace the trail by ``points (N, 3)`` (the newest ``capacity`` of them) at once."""
        self._existing_trail("set_trail").set(points)

    def clear_trail(self) -> None:
        if self.trail is not None:
            self.trail.clear()

    # -- camera ------------------------------------------------------------------------------

    def set_camera(self, preset: str = "iso", *, render: bool = False) -> None:
        """Frame the scene from a preset direction: iso, front, side, top or follow."""
        if preset not in CAMERA_PRESETS:
            raise ValueError(f"preset must be one of {CAMERA_PRESETS}, got {preset!r}")
        root = None
        if preset == "follow" and self.skeletons:
            root = self.skeleton().positions[0]
            self._follow = (self.skeleton().name, root.copy())
        else:
            self._follow = None
        self.plotter.camera.view_angle = 30.0
        self._look_at(*self.framing.aim(preset, self.plotter.window_size, root))
        self.plotter.renderer.ResetCameraClippingRange()
        self._camera = preset
        self._camera_moved = True
        if render:
            self.render()

    def _follow_root(self, name: str, last: Array, root: Array) -> None:
        delta = np.array([root[0] - last[0], 0.0, root[2] - last[2]])
        camera = self.plotter.camera
        camera.focal_point = tuple(np.add(camera.focal_point, delta))
        camera.position = tuple(np.add(camera.position, delta))
        self.plotter.renderer.ResetCameraClippingRange()
        self._follow = (name, root.copy())
        self._camera_moved = True

    # -- output ------------------------------------------------------------------------------

    def _framed(self, view: widgets.DOMWidget) -> widgets.DOMWidget:
        """vtk.js draws no 2D actors: the legend of a view rendered in the browser is HTML
        above it.

        The box of the two takes over the view's size and the view fills its width (never
        more than its window's): a layout that narrows the box (a panel beside it, a notebook
        beside the file browser) narrows the view with it, its aspect kept, instead of leaving
        it at its window's width, sticking out of the box and cut by it."""
        if not (self._in_browser and len(self.legend_entries()) > 1):
            return view
        import ipywidgets as widgets

        self._legend = widgets.HTML(self._legend_html(), layout=widgets.Layout(height="22px"))
        box = widgets.VBox([self._legend, view], layout=widgets.Layout(
            width=view.layout.width, min_width=view.layout.min_width, flex="0 1 auto"))
        view.layout.max_width = view.layout.width
        view.layout.width = "100%"
        return box


def show_skeletons(
    parents: ArrayLike,
    poses: Sequence[ArrayLike] | ArrayLike,
    names: Sequence[str] | None = None,
    **kwargs: Any,
) -> SkeletonScene:
    """One scene with several poses of the same skeleton (e.g. reference vs. student),
    in distinct colours with a legend. ``poses``: (S, J, 3) or a list of (J, 3)."""
    stack = np.asarray(poses, dtype=np.float64)
    names = list(names) if names is not None else [f"pose {i + 1}" for i in range(len(stack))]
    if len(names) != len(stack):
        raise ValueError(f"names has {len(names)} entries for {len(stack)} poses")
    scene = SkeletonScene(**kwargs)
    for pose, name in zip(stack, names, strict=True):
        scene.add_skeleton(parents, pose, name=name, frame_points=stack)
    return scene
