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

import contextlib
import io
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import Array
from ._backend import (
    _headless,
    configure_environment,
    jupyter_backend,
    off_screen,
    on_gl_thread,
    png_bytes,
)

configure_environment()

import pyvista as pv  # noqa: E402  (after the environment is set: VTK reads it on import)
from vtkmodules.vtkFiltersCore import vtkGlyph3D, vtkTubeFilter  # noqa: E402
from vtkmodules.vtkRenderingCore import vtkGlyph3DMapper, vtkPolyDataMapper  # noqa: E402

#: (bone colour, joint colour) per skeleton, in the order skeletons are added.
PALETTE: tuple[tuple[str, str], ...] = (
    ("#3d7dca", "#ffb000"),  # blue bones, amber joints: the student's / main skeleton
    ("#8f9aa6", "#4a5561"),  # greys: the reference / before
    ("#2bb673", "#e5484d"),  # green bones, red joints: after IK
    ("#8e6bd8", "#f08c3a"),
)
#: (bone colour, joint colour) of a faint pose drawn for comparison (before IK, the capture).
GHOST = ("#aab4bf", "#8793a0")
#: joint and bone radii of a faint (``opacity < 1``) pose, relative to a solid one's
FAINT_SIZE = 0.8
TARGET_COLOR = "#e5484d"
# a target's sphere, translucent, about twice a joint's: it shows around a hand's finger joints
TARGET_RADIUS = 0.05
POLE_COLOR = "#8e3bd1"  # violet, as the pole's diamond in the 2D figures (chain_plots.ACCENT)
TRAIL_COLOR = "#d1347a"
AXIS_COLORS = np.array([[230, 57, 70], [42, 170, 82], [44, 110, 230]], dtype=np.uint8)
BACKGROUND = ("#f4f6fa", "#c9d3e3")  # bottom, top: a soft sky
FLOOR_COLORS = ("#e9ecef", "#d5dae0")
CAMERA_PRESETS = ("iso", "front", "side", "top", "follow")


def _as_positions(positions: ArrayLike, n_joints: int, name: str = "positions") -> Array:
    p = np.asarray(positions, dtype=np.float64)
    if p.shape != (n_joints, 3):
        raise ValueError(f"{name} must have shape ({n_joints}, 3), got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return p


def _as_parents(parents: ArrayLike) -> NDArray[np.intp]:
    par = np.asarray(parents, dtype=np.intp).reshape(-1)
    later = np.arange(1, par.size)
    if par.size == 0 or par[0] != -1 or np.any(par[1:] < 0) or np.any(par[1:] >= later):
        raise ValueError(
            "parents must list joints parent-before-child with parents[0] == -1 "
            f"(parents[j] < j for j > 0), got {par.tolist()}"
        )
    return par


def _segments(pairs: NDArray[np.intp]) -> NDArray[np.intp]:
    """VTK line connectivity ``[2, a, b, 2, c, d, ...]`` for index pairs ``(S, 2)``."""
    return np.column_stack([np.full(len(pairs), 2), pairs]).ravel()


def _tube_actor(lines: pv.PolyData, radius: float, sides: int = 18) -> tuple[pv.Actor, Any]:
    """An actor drawing ``lines`` as shaded tubes; the tube filter re-runs when points change."""
    tube = vtkTubeFilter()
    tube.SetInputData(lines)
    tube.SetRadius(radius)
    tube.SetNumberOfSides(sides)
    tube.CappingOn()
    mapper = vtkPolyDataMapper()
    mapper.SetInputConnection(tube.GetOutputPort())
    mapper.ScalarVisibilityOff()
    actor = pv.Actor(mapper=mapper)
    return actor, tube


def _sphere_actor(points: pv.PolyData, radius: float, *, browser: bool = False) -> pv.Actor:
    """Spheres at every point of ``points``: glyphed on the GPU where VTK renders; for a view
    rendered in the browser (vtk.js knows no glyph mapper) as one small mesh, re-glyphed on
    the CPU when the points move (a few hundred points per joint)."""
    if browser:
        glyphs = vtkGlyph3D()
        glyphs.SetInputData(points)
        glyphs.SetSourceData(pv.Sphere(radius=radius, theta_resolution=14, phi_resolution=10))
        glyphs.ScalingOff()
        glyphs.OrientOff()
        mapper = vtkPolyDataMapper()
        mapper.SetInputConnection(glyphs.GetOutputPort())
        mapper.ScalarVisibilityOff()
        return pv.Actor(mapper=mapper)
    mapper = vtkGlyph3DMapper()
    mapper.SetInputData(points)
    mapper.SetSourceData(pv.Sphere(radius=radius, theta_resolution=28, phi_resolution=20))
    mapper.ScalingOff()
    mapper.OrientOff()
    mapper.ScalarVisibilityOff()
    return pv.Actor(mapper=mapper)


def _shade(actor: pv.Actor, color: str, *, specular: float = 0.35, opacity: float = 1.0) -> None:
    prop = actor.prop
    prop.color = color
    prop.opacity = opacity
    prop.ambient = 0.18
    prop.diffuse = 0.85
    prop.specular = specular
    prop.specular_power = 30.0
    prop.interpolation = "phong"


def _new_plotter(window_size: Sequence[int]) -> pv.Plotter:
    """An off-screen-aware plotter whose every render runs on the GL thread: pyvista also
    renders from inside ``add_actor``, camera setters and ``show``, not only when we ask."""
    plotter = pv.Plotter(off_screen=off_screen(), window_size=list(window_size),
                         lighting="light_kit")
    render = plotter.render
    plotter.render = lambda: on_gl_thread(render)  # type: ignore[method-assign]
    plotter.set_background(BACKGROUND[0], top=BACKGROUND[1])
    _smooth_edges(plotter)
    return plotter


def _smooth_edges(plotter: pv.Plotter) -> None:
    """MSAA where a GPU draws (a display exists): free there. Headless, VTK draws on the CPU
    (llvmpipe), where MSAA costs 5-8x per frame, so interaction stays aliased and only saved
    screenshots are smoothed."""
    if _headless():
        plotter.disable_anti_aliasing()  # pyvista's theme asks for 4 samples by default
    else:
        plotter.enable_anti_aliasing("msaa")


@dataclass
class SkeletonActors:
    """One skeleton in a scene: its meshes (updated in place) and its actors."""

    name: str
    parents: NDArray[np.intp]
    bone_color: str
    joint_color: str
    points: pv.PolyData  # joints (J points), glyphed with spheres
    bones: pv.PolyData  # the same J points, one line per (parent, child) edge
    triads: pv.PolyData | None  # 6 points per joint: origin/tip for x, y, z
    axis_length: float
    actors: list[pv.Actor] = field(default_factory=list)

    @property
    def positions(self) -> Array:
        """The joint positions currently drawn, ``(J, 3)`` (a copy)."""
        return np.array(self.points.points, dtype=np.float64)


class SkeletonScene:
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
        self.backend = jupyter_backend()
        self.plotter = _new_plotter(window_size)
        self._in_browser = self.backend == "client"
        self._browser_views: list[Any] = []  # the vtk.js views showing this scene
        self._live_servers: list[Any] = []  # the trame servers of live views
        self._drawn = BrowserDraws()  # pictures the vtk.js views have not drawn yet
        self._camera_moved = False
        self._legend: Any = None  # an HTML legend above a view rendered in the browser
        self.skeletons: dict[str, SkeletonActors] = {}
        self._ground_wanted = ground
        self._ground_actor: pv.Actor | None = None
        self._scale = 1.0
        self._center = np.zeros(3)
        self._radius = 1.0
        self._fit_points: Array | None = None  # framed by projection (else by a sphere)
        self._envelope: Array | None = None  # a clip's poses about their root (follow camera)
        self._sphere = False  # framing a sphere of reach
        self._camera = camera
        self._follow: tuple[str, Array] | None = None  # (skeleton, root position at last move)
        self._targets: pv.PolyData | None = None
        self._pole: pv.PolyData | None = None
        self._trail: pv.PolyData | None = None
        self._trail_count = 0
        self._widget: Any = None
        self._handle: Any = None  # the draggable target sphere (interactive views)

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
        par = _as_parents(parents)
        n = par.size
        pos = _as_positions(positions, n)
        name = name or ("skeleton" if not self.skeletons else f"skeleton {len(self.skeletons) + 1}")
        if name in self.skeletons:
            raise ValueError(f"name {name!r} is already used in this scene")
        used = {sk.bone_color for sk in self.skeletons.values()}
        bone_color, joint_color = color or next(
            (c for c in PALETTE if c[0] not in used), PALETTE[len(self.skeletons) % len(PALETTE)])
        if not self.skeletons:
            clip = None if frame_points is None else np.asarray(frame_points, np.float64)
            if clip is not None and clip.ndim == 3:
                # whole frames (a stride over all points could skip a joint in every frame)
                clip = clip[:: max(1, clip.shape[0] * clip.shape[1] // 4000)]
                # about each frame's root, on the floor
                self._envelope = (clip - clip[:, :1] * [1.0, 0.0, 1.0]).reshape(-1, 3)
            pts = pos if clip is None else clip.reshape(-1, 3)
            if reach is not None:  # the sphere's six extremes
                extremes = pos[0] + reach * np.concatenate([np.eye(3), -np.eye(3)])
                pts = np.concatenate([pts, extremes])
            self._frame(pts, pos, par, headroom=frame_points is None and reach is None,
                        sphere=reach is not None)
        s = self._scale
        points = pv.PolyData(pos.copy())
        bones = pv.PolyData()
        bones.SetPoints(points.GetPoints())  # the same vtkPoints: one write moves both
        edges = np.column_stack([par[1:], np.arange(1, n)])
        bones.lines = _segments(edges)
        # a faint pose is drawn thinner: where a solid pose coincides with it (IK left a joint
        # in place) the solid one hides it whole, instead of the two fighting over the depth
        thin = FAINT_SIZE if opacity < 1.0 else 1.0
        joints_actor = _sphere_actor(points, radius=0.022 * s * thin, browser=self._in_browser)
        bones_actor, _ = _tube_actor(bones, radius=0.011 * s * thin)
        _shade(joints_actor, joint_color, opacity=opacity)
        _shade(bones_actor, bone_color, specular=0.25, opacity=opacity)
        actors = [bones_actor, joints_actor]
        triads = None
        axis_length = 0.09 * s
        if axes:
            triads = pv.PolyData(np.zeros((6 * n, 3)))
            triads.lines = _segments(np.arange(6 * n).reshape(-1, 2))
            triads.point_data["rgb"] = np.tile(np.repeat(AXIS_COLORS, 2, axis=0), (n, 1))
            triad_actor, _ = _tube_actor(triads, radius=0.0045 * s, sides=10)
            mapper = triad_actor.mapper
            mapper.ScalarVisibilityOn()
            mapper.SetColorModeToDirectScalars()
            mapper.SetScalarModeToUsePointFieldData()
            mapper.SelectColorArray("rgb")
            actors.append(triad_actor)
        for actor in actors:
            self.plotter.add_actor(actor, reset_camera=False, pickable=False)
        skel = SkeletonActors(name, par, bone_color, joint_color, points, bones, triads,
                              axis_length, actors)
        self.skeletons[name] = skel
        if triads is not None:
            self._set_triads(skel, pos, orientations)
        if len(self.skeletons) == 1 and self._camera == "follow":  # now it has a root to follow
            self.set_camera("follow")
        self._update_legend()
        return skel

    def _frame(self, points: Array, pose: Array, parents: NDArray[np.intp],
               headroom: bool, sphere: bool) -> None:
        """Size the glyphs from ``pose``; place the floor and camera to cover ``points``
        (with ``headroom``, also a pose whose limbs swing out further; with ``sphere``, the
        bounding sphere, seen the same from every side)."""
        pts = points.reshape(-1, 3)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        bone = np.linalg.norm(pose[1:] - pose[parents[1:]], axis=1)
        self._scale = float(max(np.ptp(pose, axis=0).max(), 2.5 * bone.max(initial=0.0), 1e-6))
        self._center = (lo + hi) / 2
        self._radius = float(max(np.linalg.norm(pts - self._center, axis=1).max(),
                                 (0.65 if headroom else 0.5) * self._scale))
        # a clip is framed by what each view sees of it (subsampled): a walk seen from the
        # front is one person, not a 20 m sphere
        self._sphere = sphere
        self._fit_points = None if sphere else pts[:: max(1, len(pts) // 4000)]
        if headroom:
            self._fit_points = None
        if self._ground_wanted:
            self._add_ground(lo, hi)
        self.set_camera(self._camera)

    def _add_ground(self, lo: Array, hi: Array) -> None:
        """A checkered floor under the points, tiles of a round size, y = lowest point."""
        span = 1.6 * max(hi[0] - lo[0], hi[2] - lo[2]) + 2.0 * self._scale  # a wide view too
        tile = 10.0 ** np.floor(np.log10(self._scale / 4))  # 1, 10, 100 ... per tile
        tile *= 5 if span / (5 * tile) > 8 else 1
        n = int(np.ceil(span / tile)) + 1
        center = np.round(self._center / tile) * tile
        plane = pv.Plane(
            center=(center[0], lo[1] - 0.022 * self._scale, center[2]),
            direction=(0, 1, 0), i_size=n * tile, j_size=n * tile,
            i_resolution=n, j_resolution=n,
        )
        i, j = np.divmod(np.arange(plane.n_cells), n)
        plane.cell_data["tile"] = ((i + j) % 2).astype(float)
        self._ground_actor = self.plotter.add_mesh(
            plane, scalars="tile", cmap=list(FLOOR_COLORS), show_scalar_bar=False,
            ambient=0.35, diffuse=0.7, specular=0.0, pickable=False, reset_camera=False,
        )

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
        self.plotter.remove_legend(render=False)
        self.plotter.add_legend(
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
        pos = _as_positions(positions, skel.parents.size)
        skel.points.points[:] = pos  # bones share these vtkPoints
        skel.points.GetPoints().Modified()
        skel.points.Modified()
        skel.bones.Modified()
        if skel.triads is not None:
            self._set_triads(skel, pos, orientations)
        if self._follow is not None and self._follow[0] == skel.name:
            self._follow_root(pos[0])
        if render:
            self.render()

    def _set_triads(self, skel: SkeletonActors, pos: Array, orientations: ArrayLike | None) -> None:
        if orientations is None:
            raise ValueError(f"orientations (J, 4) are needed to draw the axes of {skel.name!r}")
        from course.rotations import matrix_from_quat

        R = matrix_from_quat(np.asarray(orientations, dtype=np.float64))
        if R.shape != (pos.shape[0], 3, 3):
            raise ValueError(f"orientations must have shape ({pos.shape[0]}, 4)")
        tips = pos[:, None, :] + skel.axis_length * np.swapaxes(R, 1, 2)  # columns = local axes
        pts = skel.triads.points.reshape(-1, 3, 2, 3)
        pts[:, :, 0] = pos[:, None, :]
        pts[:, :, 1] = tips
        skel.triads.Modified()

    def set_targets(self, targets: ArrayLike, *, render: bool = True) -> None:
        """Show target markers at ``targets (K, 3)``; the marker mesh is made once per K."""
        t = np.asarray(targets, dtype=np.float64).reshape(-1, 3)
        if not np.all(np.isfinite(t)):
            raise ValueError("targets contains NaN or infinite values")
        if self._targets is None or self._targets.n_points != len(t):
            if self._targets is not None:
                self.plotter.remove_actor(self._targets_actor, render=False)
            self._targets = pv.PolyData(t.copy())
            self._targets_actor = _sphere_actor(self._targets, radius=TARGET_RADIUS * self._scale,
                                                browser=self._in_browser)
            _shade(self._targets_actor, TARGET_COLOR, opacity=0.45)
            self.plotter.add_actor(self._targets_actor, reset_camera=False, pickable=False)
        else:
            self._targets.points[:] = t
            self._targets.Modified()
        if render:
            self.render()

    def set_pole(self, position: ArrayLike, *, render: bool = True) -> None:
        """Show the pole (the point a middle joint bends towards) at ``position (3,)``: a
        violet sphere, so it is not taken for a target, named in the legend."""
        p = _as_positions(np.reshape(position, (1, 3)), 1, "position")
        if self._pole is None:
            self._pole = pv.PolyData(p.copy())
            actor = _sphere_actor(self._pole, radius=TARGET_RADIUS * self._scale,
                                  browser=self._in_browser)
            _shade(actor, POLE_COLOR, opacity=0.6)
            self.plotter.add_actor(actor, reset_camera=False, pickable=False)
            self._update_legend()
        else:
            self._pole.points[:] = p
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

    def add_target_handle(self, position: ArrayLike, on_drag: Callable[[Array], None]) -> Any:
        """A sphere at ``position (3,)`` that the student drags with the mouse in an interactive
        view (trame; a static image has no mouse): ``on_drag(p)`` gets each new centre
        ``p (3,)`` while it moves. Returns the VTK widget (see :meth:`move_target_handle`)."""
        p = _as_positions(np.reshape(position, (1, 3)), 1, "position")[0]
        self._handle = self.plotter.add_sphere_widget(
            lambda center: on_drag(np.asarray(center, dtype=np.float64)), center=tuple(p),
            radius=0.045 * self._scale, color=TARGET_COLOR, selected_color="#ff8a8e",
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
        if capacity < 2:
            raise ValueError(f"capacity must be at least 2, got {capacity}")
        self._trail = pv.PolyData(np.zeros((capacity, 3)))
        self._trail.lines = np.concatenate([[capacity], np.arange(capacity)])
        actor = self.plotter.add_mesh(
            self._trail, color=TRAIL_COLOR, line_width=4, render_lines_as_tubes=True,
            reset_camera=False, pickable=False,
        )
        actor.visibility = False
        self._trail_actor = actor
        self._trail_count = 0

    def push_trail(self, point: ArrayLike) -> None:
        """Append a point to the trail (the oldest drops out when full); unused slots repeat
        the newest point, so the polyline keeps its size and nothing is reallocated."""
        if self._trail is None:
            raise ValueError("call add_trail() before push_trail()")
        pts = self._trail.points
        p = np.asarray(point, dtype=np.float64).reshape(3)
        if self._trail_count < len(pts):
            pts[self._trail_count:] = p
            self._trail_count += 1
        else:
            pts[:-1] = pts[1:]
            pts[-1] = p
        self._trail.Modified()
        self._trail_actor.visibility = self._trail_count > 1

    def set_trail(self, points: ArrayLike) -> None:
        """Replace the trail by ``points (N, 3)`` (the newest ``capacity`` of them) at once."""
        if self._trail is None:
            raise ValueError("call add_trail() before set_trail()")
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)[-self._trail.n_points:]
        if len(p) == 0:
            self.clear_trail()
            return
        pts = self._trail.points
        pts[:len(p)] = p
        pts[len(p):] = p[-1]
        self._trail_count = len(p)
        self._trail.Modified()
        self._trail_actor.visibility = len(p) > 1

    def clear_trail(self) -> None:
        self._trail_count = 0
        if self._trail is not None:
            self._trail_actor.visibility = False

    # -- camera ------------------------------------------------------------------------------

    def set_camera(self, preset: str = "iso", *, render: bool = False) -> None:
        """Frame the scene from a preset direction: iso, front, side, top or follow."""
        if preset not in CAMERA_PRESETS:
            raise ValueError(f"preset must be one of {CAMERA_PRESETS}, got {preset!r}")
        direction, up = {
            "iso": ((0.55, 0.38, 1.0), (0, 1, 0)),
            "follow": ((0.55, 0.38, 1.0), (0, 1, 0)),
            "front": ((0.0, 0.12, 1.0), (0, 1, 0)),
            "side": ((1.0, 0.12, 0.0), (0, 1, 0)),
            "top": ((0.0, 1.0, 0.0), (0, 0, -1)),
        }[preset]
        d = np.asarray(direction) / np.linalg.norm(direction)
        camera = self.plotter.camera
        camera.view_angle = 30.0
        # a sphere of reach, with a margin; a lone pose's headroom is margin enough
        distance = self._radius * (1.15 / np.sin(np.radians(15.0)) if self._sphere
                                   else 1.05 / np.tan(np.radians(15.0)))
        focal = self._center
        if self._fit_points is not None:
            focal, distance = self._fit_view(d, np.asarray(up, dtype=np.float64))
        if preset == "follow" and self.skeletons:
            root = self.skeleton().positions[0]
            self._follow = (self.skeleton().name, root.copy())
            if self._envelope is not None:  # the clip's largest pose, where the root is now
                focal, distance = self._fit_view(d, np.asarray(up, dtype=np.float64),
                                                 self._envelope + root * [1.0, 0.0, 1.0])
            else:
                focal = np.array([root[0], self._center[1], root[2]])
                distance = 1.15 * 0.6 * self._scale / np.tan(np.radians(15.0))
        else:
            self._follow = None
        camera.focal_point = tuple(focal)
        camera.position = tuple(focal + distance * d)
        camera.up = up
        self.plotter.renderer.camera_set = True  # else pyvista resets it at the first render
        self.plotter.renderer.ResetCameraClippingRange()
        self._camera = preset
        self._camera_moved = True
        if render:
            self.render()

    def _fit_view(self, d: Array, up: Array, points: Array | None = None
                  ) -> tuple[Array, float]:
        """Focal point and distance along ``d`` at which every framing point (or every one of
        ``points (N, 3)``), with its joint sphere, is in view (perspective, 30 degrees
        vertically, the window's aspect, a 10% margin)."""
        right = np.cross(up, d)
        right /= np.linalg.norm(right)
        true_up = np.cross(d, right)
        rel = (self._fit_points if points is None else points) - self._center
        x, y, z = rel @ right, rel @ true_up, rel @ d  # z: towards the camera
        focal = self._center + right * (x.max() + x.min()) / 2 + true_up * (y.max() + y.min()) / 2
        pad = 0.03 * self._scale  # a joint sphere's radius and a little more
        x = np.abs(x - (x.max() + x.min()) / 2) + pad
        y = np.abs(y - (y.max() + y.min()) / 2) + pad
        w, h = self.plotter.window_size
        tan_v = np.tan(np.radians(15.0)) / 1.1
        tan_h = tan_v * w / h
        return focal, float(max((z + pad + y / tan_v).max(), (z + pad + x / tan_h).max(), 1e-6))

    def _follow_root(self, root: Array) -> None:
        name, last = self._follow
        delta = np.array([root[0] - last[0], 0.0, root[2] - last[2]])
        camera = self.plotter.camera
        camera.focal_point = tuple(np.add(camera.focal_point, delta))
        camera.position = tuple(np.add(camera.position, delta))
        self.plotter.renderer.ResetCameraClippingRange()
        self._follow = (name, root.copy())
        self._camera_moved = True

    # -- output ------------------------------------------------------------------------------

    def render(self) -> None:
        """Draw the current state (and push it to the notebook view, if one is shown)."""
        if not self._in_browser:  # vtk.js sets its own clipping range
            self.plotter.renderer.ResetCameraClippingRange()
        self.plotter.render()
        if self._camera_moved and self._browser_views:  # vtk.js keeps its camera otherwise
            for view in self._browser_views:
                view.push_camera()
            self._camera_moved = False
        if self._widget is not None and self.backend == "static":
            self._widget.value = png_bytes(self.image())

    def image(self) -> NDArray[np.uint8]:
        """The rendered frame as an ``(H, W, 3)`` uint8 array (row 0 at the top)."""
        return on_gl_thread(self._capture, False)

    def screenshot(self, path: str | Path | None = None) -> NDArray[np.uint8]:
        """Render and return the frame ``(H, W, 3)``; also write it as PNG to ``path``
        (a saved picture is always anti-aliased, even where interaction is not)."""
        img = on_gl_thread(self._capture, path is not None)
        if path is not None:
            Path(path).parent.mkdir(parents=True, exist_ok=True)
            Path(path).write_bytes(png_bytes(img, compress_level=6))
        return img

    def _capture(self, smooth: bool) -> NDArray[np.uint8]:
        # a view rendered in the browser suppresses VTK's own rendering: lift that for a picture
        suppressed, self.plotter.suppress_rendering = self.plotter.suppress_rendering, False
        # the depth range of what is drawn now: one set before the actors were added spans
        # 0.01 to 1000, too coarse a depth buffer to tell a joint from a ghost's just behind it
        if not self._in_browser:  # (vtk.js sets its own)
            self.plotter.renderer.ResetCameraClippingRange()
        try:
            smooth = smooth and not self.plotter.render_window.GetMultiSamples()
            if smooth:
                self.plotter.enable_anti_aliasing("msaa")
            self.plotter.render()
            img = self.plotter.screenshot(None, return_img=True)
            if smooth:
                self.plotter.disable_anti_aliasing()
                self.plotter.render()
        finally:
            self.plotter.suppress_rendering = suppressed
        return img

    def project(self, points: ArrayLike) -> Array:
        """Pixel coordinates ``(N, 2)`` as (column, row), row 0 at the top, of world points
        ``(N, 3)`` in the rendered image: the camera's composite projection
        ``x_clip = P V [p; 1]``, then the viewport transform."""
        w, h = self.plotter.window_size
        ren = self.plotter.renderer
        m = ren.GetActiveCamera().GetCompositeProjectionTransformMatrix(w / h, -1.0, 1.0)
        M = np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        clip = np.column_stack([p, np.ones(len(p))]) @ M.T
        ndc = clip[:, :2] / clip[:, 3:4]
        return np.column_stack([(ndc[:, 0] + 1) / 2 * w, h - (ndc[:, 1] + 1) / 2 * h])

    def widget(self) -> Any:
        """The view for a notebook layout: an ``ipywidgets.Image`` refreshed on every render
        (static backend) or the interactive trame iframe."""
        if self._widget is None:
            if self.backend == "static":
                import ipywidgets as widgets

                w, h = self.plotter.window_size
                # as wide as the window, narrower when the notebook is (aspect kept)
                self._widget = widgets.Image(format="png", width=w, height=h, layout=widgets.Layout(
                    max_width="100%", height="auto", min_width="320px", flex="0 1 auto"))
                self.render()
            else:
                self._widget = on_gl_thread(self._trame_view)
            self._widget.add_class("course-view")  # found by the browser tests
            self._widget.add_class(f"course-view-{self.backend}")  # what they expect it to draw
            if self._in_browser and len(self.legend_entries()) > 1:  # (a FrameScene: never)
                import ipywidgets as widgets

                self._legend = widgets.HTML(self._legend_html(),
                                            layout=widgets.Layout(height="22px"))
                view = self._widget
                self._widget = widgets.VBox([self._legend, view], layout=widgets.Layout(
                    width=view.layout.width, min_width=view.layout.min_width, flex="0 1 auto"))
        return self._widget

    def _trame_view(self) -> Any:
        """The interactive view; trame-vtklocal's note of where it found its (unused) wasm
        bundle is kept out of the student's output."""
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            if not self._in_browser:  # as in _capture
                self.plotter.renderer.ResetCameraClippingRange()
            self.plotter.render()
            # the toolbar collapsed to one button in the corner: it covers nothing
            view = self.plotter.show(
                jupyter_backend=self.backend, return_viewer=True, auto_close=False,
                jupyter_kwargs={"collapse_menu": True},
            )
        print("".join(line for line in out.getvalue().splitlines(keepends=True)
                      if not line.startswith("Using wasm_dir:")), end="")
        server = getattr(getattr(view, "viewer", None), "server", None)
        if server is not None:
            self._live_servers.append(server)
        viewer = getattr(view, "viewer", None)
        for local_view in getattr(viewer, "views", ()):
            if _send_changes_only(local_view, self._drawn):
                self._browser_views.append(local_view)
                # the vtk.js view says when it has drawn a change (playback waits for that)
                local_view.after_scene_loaded = self._drawn.drawn
        if self._browser_views and getattr(viewer, "layout", None) is not None:
            viewer.layout.flush_content()  # before the page loads: the event is in its template
        # the iframe is as wide as its box (keeping its aspect): the window's width, narrower
        # when the notebook is, never nothing
        view.layout.width = f"{self.plotter.window_size[0]}px"
        view.layout.min_width = "320px"
        view.layout.flex = "0 1 auto"
        return view

    def pictures_in_flight(self) -> int:
        """Pictures of this scene's live views not yet shown: messages on trame's websocket
        not yet handed to the network, and pictures the browser's vtk.js view has not drawn
        (:class:`BrowserDraws`). The last picture is on screen once this is 0. Always 0 for
        a static image, which travels with its widget's own message."""
        return self._drawn.pending() + sum(
            getattr(getattr(getattr(s, "context", None), "network_monitor", None), "pending", 0)
            for s in self._live_servers)

    def show(self) -> None:
        """Display the view: in a notebook as :meth:`widget`, else in a window (blocking)."""
        from ._backend import in_jupyter_kernel

        if in_jupyter_kernel():
            from IPython.display import display

            display(self.widget())
        else:
            self.plotter.show(auto_close=False)

    def close(self) -> None:
        on_gl_thread(self.plotter.close)


class BrowserDraws:
    """Changes sent to a browser-rendered (vtk.js) view and not yet drawn there.

    The view answers every change it has applied (its ``afterSceneLoaded`` event, a message
    back to the kernel). So the kernel sends a change only once the last one is drawn, and
    while the browser draws it keeps only the newest (:meth:`send_or_wait`): a drag faster
    than the browser draws shows its latest state, never a backlog; a player waits for the
    picture on the student's screen, not only on the network, and its frame skip says what is
    seen. Until a first answer arrives nothing is waited for (a view that never answers), and
    a change unanswered after ``patience`` seconds is forgotten (a closed tab, a lost message).
    """

    def __init__(self, *, patience: float = 1.0, clock: Callable[[], float] | None = None,
                 call_later: Callable[[float, Callable[[], None]], Any] | None = None) -> None:
        import collections
        import time

        self.patience = float(patience)
        self.clock = clock or time.monotonic
        self.call_later = call_later or _event_loop_call_later  # the kernel's loop
        self._sent: collections.deque[float] = collections.deque()
        self._waiting: Callable[[], None] | None = None  # the newest change held back
        self.answers = False  # the browser has answered at least once
        self.count = 0  # changes drawn, as the browser said

    def pending(self) -> int:
        """Changes sent and not yet drawn (0 while the browser has never answered)."""
        now = self.clock()
        while self._sent and now - self._sent[0] > self.patience:
            self._sent.popleft()
        return len(self._sent) if self.answers else 0

    def send_or_wait(self, send: Callable[[], None]) -> None:
        """Call ``send`` (which sends the scene's changes) now if the browser has drawn all it
        was sent, else once it has (only the newest ``send`` is kept)."""
        if not self.pending():
            self._send(send)
            return
        if self._waiting is None:  # a browser that stops answering is waited for no longer
            self.call_later(self.patience, self._send_waiting)
        self._waiting = send

    def drawn(self, *_event: Any) -> None:
        """The browser has applied a change and draws it (the oldest one sent)."""
        self.answers = True
        self.count += 1
        if self._sent:
            self._sent.popleft()
        if not self.pending():
            self._send_waiting()

    def _send(self, send: Callable[[], None]) -> None:
        self._sent.append(self.clock())
        send()

    def _send_waiting(self) -> None:
        send, self._waiting = self._waiting, None
        if send is not None:
            self._send(send)


def _event_loop_call_later(delay: float, fn: Callable[[], None]) -> None:
    import asyncio

    asyncio.get_event_loop().call_later(delay, fn)


def _send_changes_only(view: Any, draws: BrowserDraws | None = None) -> bool:
    """Make a browser-rendered (vtk.js) view send only what changed on each render.

    trame's ``VtkLocalView.update`` serializes the scene twice per render: the changes
    (published at once) and the whole state (kept for a page that reloads), which the browser
    then applies a second time. Here a render publishes the changes only, paced by the
    browser's draws (``draws``, see :class:`BrowserDraws`); the whole state is refreshed once
    the view has been still for a second. Until a page has shown the scene (its first answer)
    every render keeps the whole state: a page loads that state once, when it opens, and
    takes only changes afterwards, so a state older than the page would stay on it. Views
    of another kind, or of a trame version without these internals, are left as they are
    (returns False).
    """
    render_window = getattr(view, "_VtkLocalView__view", None)
    helper = getattr(view, "_helper", None)
    if render_window is None or helper is None or not hasattr(view, "_widgets"):
        return False
    draws = draws or BrowserDraws()
    full_update = view.update
    last = [0.0, False]  # time of the last change, whether a refresh is scheduled

    def refresh() -> None:  # one timer per quiet second, not one per render
        wait = last[0] + 1.0 - draws.clock()
        if wait > 0:
            draws.call_later(wait, refresh)
            return
        last[1] = False
        full_update()

    def update(widgets: Any = None, orientation_axis: int = 0, **_kwargs: Any) -> None:
        def send() -> None:  # the scene as it is when sent: the newest state
            protocol = view.server.protocol
            if not protocol:
                return
            delta = helper.scene(render_window, new_state=False,
                                 widgets=view._widgets if widgets is None else widgets,
                                 orientation_axis=orientation_axis)
            protocol.publish("trame.vtk.delta", delta)
            last[0] = draws.clock()
            if not last[1]:
                last[1] = True
                draws.call_later(1.0, refresh)

        if not draws.answers:  # no page has shown the scene yet: it will load the whole of it
            full_update(widgets=widgets, orientation_axis=orientation_axis)
            return
        draws.send_or_wait(send)

    view.update = update
    return True


def show_skeletons(
    parents: ArrayLike,
    poses: Sequence[ArrayLike] | ArrayLike,
    names: Sequence[str] | None = None,
    **kwargs: Any,
) -> SkeletonScene:
    """One scene with several poses of the same skeleton (e.g. reference vs. student),
    in distinct colours with a legend. ``poses``: (S, J, 3) or a list of (J, 3)."""
    arr = [np.asarray(p, dtype=np.float64) for p in poses]
    names = list(names) if names is not None else [f"pose {i + 1}" for i in range(len(arr))]
    if len(names) != len(arr):
        raise ValueError(f"names has {len(names)} entries for {len(arr)} poses")
    scene = SkeletonScene(**kwargs)
    for pose, name in zip(arr, names, strict=True):
        scene.add_skeleton(parents, pose, name=name, frame_points=np.stack(arr))
    return scene


class FrameScene:
    """A rotated coordinate frame (x red, y green, z blue arrows) beside the faint world frame;
    :meth:`set_rotations` moves each frame by setting its actors' transform (nothing rebuilt).

    The view is a parallel projection, so equal lengths look equal in every frame (a shorter
    arrow is a shorter axis, not a farther one). The frames stand in a row across the screen,
    each caption centred under its own frame, below every place its arrows can point.

    Parameters
    ----------
    n_frames : how many frames to show side by side (e.g. 3 for LERP / NLERP / SLERP).
    labels : a caption under each frame (wrapped to the frame's width).
    """

    #: world units between neighbouring frames, and the radius every arrow (turned any way,
    #: its tip included) and the world frame's axes (1.15 long) stay inside
    SPACING, REACH = 2.6, 1.2
    FONT_SIZE, MARGIN = 18, 8  # caption size, and pixels kept clear at the window's edges

    def __init__(
        self,
        n_frames: int = 1,
        labels: Sequence[str] | None = None,
        *,
        window_size: tuple[int, int] | None = None,
    ) -> None:
        if labels is not None and len(labels) != n_frames:
            raise ValueError(f"labels must have {n_frames} entries, got {len(labels)}")
        # the captions are VTK text, which vtk.js does not draw: rendered in the kernel
        self.backend = "server" if jupyter_backend() == "client" else jupyter_backend()
        self._in_browser = False
        self._browser_views: list[Any] = []
        self._live_servers: list[Any] = []
        self._drawn = BrowserDraws()
        self._camera_moved = False
        size = window_size or (max(420, 300 * n_frames), 380)
        self.plotter = _new_plotter(size)
        # looking from the front, a little right and above; the frames in a row along the
        # screen's right (horizontal), so none is lower or farther than another
        d = np.array([0.45, 0.35, 1.0]) / np.linalg.norm([0.45, 0.35, 1.0])
        right = np.cross([0.0, 1.0, 0.0], d)
        right /= np.linalg.norm(right)
        up = np.cross(d, right)
        self.offsets = [self.SPACING * (i - (n_frames - 1) / 2) * right for i in range(n_frames)]
        scale, captions, caption_px = self._layout(size, n_frames, labels)
        self.pixels_per_unit = scale
        self._arrows: list[list[pv.Actor]] = []
        self.label_actors: list[Any] = []
        arrow = [pv.Arrow(start=(0, 0, 0), direction=np.eye(3)[a], tip_length=0.22,
                          tip_radius=0.07, shaft_radius=0.028) for a in range(3)]
        gap = 6.0 / scale  # between the lowest reach of the arrows and the caption's top
        for i, off in enumerate(self.offsets):
            for a in range(3):  # the world frame, faint and thin
                ghost = pv.Line(off, off + 1.15 * np.eye(3)[a])
                self.plotter.add_mesh(ghost, color=tuple(AXIS_COLORS[a] / 255), opacity=0.35,
                                      line_width=2, reset_camera=False)
            actors = []
            for a in range(3):
                actor = self.plotter.add_mesh(arrow[a], color=tuple(AXIS_COLORS[a] / 255),
                                              smooth_shading=True, specular=0.4,
                                              reset_camera=False)
                actors.append(actor)
            self._arrows.append(actors)
            if captions:
                self.label_actors.append(self.plotter.add_point_labels(
                    [off - (self.REACH + gap) * up], [captions[i]], font_size=self.FONT_SIZE,
                    shape=None, show_points=False, text_color="#2b3440", always_visible=True,
                    justification_horizontal="center", justification_vertical="top",
                    reset_camera=False))
        self.rotations = np.tile(np.eye(3), (n_frames, 1, 1))
        # the row of frames and the captions under it, centred in the window: the frames'
        # centre row is above the window's middle by half the captions' height
        camera = self.plotter.camera
        camera.parallel_projection = True
        camera.parallel_scale = size[1] / (2 * scale)
        focal = -(caption_px + 6.0) / 2 / scale * up
        camera.focal_point = tuple(focal)
        camera.position = tuple(focal + 4 * self.SPACING * max(n_frames, 2) * d)
        camera.up = tuple(up)
        self.plotter.renderer.camera_set = True
        self._widget: Any = None

    @classmethod
    def _layout(cls, size: tuple[int, int], n_frames: int, labels: Sequence[str] | None
                ) -> tuple[float, list[str], float]:
        """Pixels per world unit that fit the row of frames and the captions under it in
        ``size``; the captions wrapped to a frame's width; their height in pixels."""
        import textwrap

        w, h = size
        line = 1.25 * cls.FONT_SIZE
        captions: list[str] = []
        caption_px = 0.0
        for _ in range(2):  # the scale depends on the captions' lines, their width on the scale
            scale = min((w - 2 * cls.MARGIN) / (cls.SPACING * (n_frames - 1) + 2 * cls.REACH),
                        (h - 2 * cls.MARGIN - 6.0 - caption_px) / (2 * cls.REACH))
            if labels is None:
                break
            column = min(cls.SPACING * scale, w - 2 * cls.MARGIN) - 8  # a gap between captions
            chars = max(6, int(column / (0.55 * cls.FONT_SIZE)))  # bold sans: ~0.55 em a letter
            captions = ["\n".join(textwrap.wrap(text, chars)) or " " for text in labels]
            caption_px = line * max(c.count("\n") + 1 for c in captions)
        return float(scale), captions, caption_px

    def set_rotations(self, matrices: ArrayLike, *, render: bool = True) -> None:
        """Set each frame's linear map ``(n_frames, 3, 3)`` (a rotation, or a scaled one to
        show a non-unit quaternion); the arrows are transformed, not rebuilt."""
        R = np.asarray(matrices, dtype=np.float64).reshape(-1, 3, 3)
        if len(R) != len(self._arrows):
            raise ValueError(f"matrices must have shape ({len(self._arrows)}, 3, 3)")
        self.rotations = R.copy()
        for actors, off, Ri in zip(self._arrows, self.offsets, R, strict=True):
            T = np.eye(4)
            T[:3, :3] = Ri
            T[:3, 3] = off
            for actor in actors:
                actor.user_matrix = T
        if render:
            self.render()

    render = SkeletonScene.render
    image = SkeletonScene.image
    screenshot = SkeletonScene.screenshot
    _capture = SkeletonScene._capture
    project = SkeletonScene.project
    widget = SkeletonScene.widget
    _trame_view = SkeletonScene._trame_view
    pictures_in_flight = SkeletonScene.pictures_in_flight
    show = SkeletonScene.show
    close = SkeletonScene.close
