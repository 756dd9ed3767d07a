"""The VTK pieces a skeleton scene is drawn from: checked inputs, tubes, spheres, a floor.

Each actor draws a mesh through a filter or glyph mapper that re-runs when the mesh's points
change, so a scene moves by overwriting points, never by rebuilding actors.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import Array
from .backend import configure_environment

configure_environment()

import pyvista as pv  # noqa: E402  (after the environment is set: VTK reads it on import)
from vtkmodules.vtkFiltersCore import vtkGlyph3D, vtkTubeFilter  # noqa: E402
from vtkmodules.vtkRenderingCore import vtkGlyph3DMapper, vtkPolyDataMapper  # noqa: E402

FLOOR_COLORS = ("#e9ecef", "#d5dae0")


def as_positions(positions: ArrayLike, n_joints: int, name: str = "positions") -> Array:
    """``positions`` as a finite ``(n_joints, 3)`` float array (else a ValueError naming it)."""
    p = np.asarray(positions, dtype=np.float64)
    if p.shape != (n_joints, 3):
        raise ValueError(f"{name} must have shape ({n_joints}, 3), got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return p


def as_parents(parents: ArrayLike) -> NDArray[np.intp]:
    """``parents`` as an index array, parent before child, ``parents[0] == -1``."""
    par = np.asarray(parents, dtype=np.intp).reshape(-1)
    later = np.arange(1, par.size)
    if par.size == 0 or par[0] != -1 or np.any(par[1:] < 0) or np.any(par[1:] >= later):
        raise ValueError(
            "parents must list joints parent-before-child with parents[0] == -1 "
            f"(parents[j] < j for j > 0), got {par.tolist()}"
        )
    return par


def overwrite(array: pv.pyvista_ndarray, values: ArrayLike, rows: slice = slice(None)) -> None:
    """Write ``values`` into ``rows`` of a mesh's array in place, through pyvista's
    ``__setitem__``: it marks the VTK array and its mesh modified."""
    # pyvista annotates the key as an int or an int array only; numpy takes a slice as well
    array[rows] = values  # type: ignore[index]


def move_points(mesh: pv.PolyData, points: ArrayLike) -> None:
    """Overwrite all of ``mesh``'s points in place and mark them and the mesh modified, so
    that every filter and mapper downstream re-runs at the next render."""
    overwrite(mesh.points, points)
    mesh.GetPoints().Modified()
    mesh.Modified()


def segments(pairs: NDArray[np.intp]) -> NDArray[np.intp]:
    """VTK line connectivity ``[2, a, b, 2, c, d, ...]`` for index pairs ``(S, 2)``."""
    return np.column_stack([np.full(len(pairs), 2), pairs]).ravel()


#: (theta, phi) resolution of a joint's or target's sphere where VTK glyphs it on the GPU, and
#: where it is a mesh sent to the browser (vtk.js) on every move: there a joint is 8 to 14 px
#: across, and 12 x 8 (74 points, a vertex on each axis so its bounds are the sphere's within
#: 3 %) shades as round as 14 x 10 (114) while a 38-joint skeleton sends, hashes and uploads
#: 2,812 points per move instead of 4,332
SPHERE_RESOLUTION = {"gpu": (28, 20), "browser": (12, 8)}
#: sides of a bone's tube: where VTK draws, and in the mesh sent to the browser on every move
TUBE_SIDES = {"gpu": 18, "browser": 12}


def tube_actor(lines: pv.PolyData, radius: float, sides: int | None = None, *,
               browser: bool = False) -> pv.Actor:
    """An actor drawing ``lines`` as shaded tubes (``sides`` around, default
    :data:`TUBE_SIDES`); the tube filter re-runs when points change."""
    tube = vtkTubeFilter()
    tube.SetInputData(lines)
    tube.SetRadius(radius)
    tube.SetNumberOfSides(sides or TUBE_SIDES["browser" if browser else "gpu"])
    tube.CappingOn()
    mapper = vtkPolyDataMapper()
    mapper.SetInputConnection(tube.GetOutputPort())
    mapper.ScalarVisibilityOff()
    return pv.Actor(mapper=mapper)


def sphere_actor(points: pv.PolyData, radius: float, *, browser: bool = False) -> pv.Actor:
    """Spheres at every point of ``points``: glyphed on the GPU where VTK renders; for a view
    rendered in the browser (vtk.js knows no glyph mapper) as one small mesh, re-glyphed on
    the CPU when the points move (74 points per joint, see :data:`SPHERE_RESOLUTION`)."""
    if browser:
        theta, phi = SPHERE_RESOLUTION["browser"]
        glyphs = vtkGlyph3D()
        glyphs.SetInputData(points)
        glyphs.SetSourceData(pv.Sphere(radius=radius, theta_resolution=theta,
                                       phi_resolution=phi))
        glyphs.ScalingOff()
        glyphs.OrientOff()
        mapper = vtkPolyDataMapper()
        mapper.SetInputConnection(glyphs.GetOutputPort())
        mapper.ScalarVisibilityOff()
        return pv.Actor(mapper=mapper)
    theta, phi = SPHERE_RESOLUTION["gpu"]
    glyph_mapper = vtkGlyph3DMapper()
    glyph_mapper.SetInputData(points)
    glyph_mapper.SetSourceData(pv.Sphere(radius=radius, theta_resolution=theta,
                                         phi_resolution=phi))
    glyph_mapper.ScalingOff()
    glyph_mapper.OrientOff()
    glyph_mapper.ScalarVisibilityOff()
    return pv.Actor(mapper=glyph_mapper)


def floor_plane(lo: Array, hi: Array, center: Array, scale: float) -> pv.PolyData:
    """A checkered floor under the box ``lo``-``hi`` (y = its lowest point, less a joint's
    radius), tiles of a round size: cell array ``"tile"`` is 0 or 1."""
    span = 1.6 * max(hi[0] - lo[0], hi[2] - lo[2]) + 2.0 * scale  # a wide view too
    tile = 10.0 ** np.floor(np.log10(scale / 4))  # 1, 10, 100 ... per tile
    tile *= 5 if span / (5 * tile) > 8 else 1
    n = int(np.ceil(span / tile)) + 1
    middle = np.round(center / tile) * tile
    plane = pv.Plane(
        center=(middle[0], lo[1] - 0.022 * scale, middle[2]),
        direction=(0, 1, 0), i_size=n * tile, j_size=n * tile,
        i_resolution=n, j_resolution=n,
    )
    i, j = np.divmod(np.arange(plane.n_cells), n)
    plane.cell_data["tile"] = ((i + j) % 2).astype(float)
    return plane


class Trail:
    """A path of up to ``capacity`` points, drawn as one polyline of fixed size: unused slots
    repeat the newest point, so nothing is reallocated as the path grows.

    Parameters
    ----------
    plotter : the plotter to draw in.
    capacity : the most points kept (the oldest drops out when full).
    color : the line's colour.
    """

    def __init__(self, plotter: pv.Plotter, capacity: int, color: str) -> None:
        if capacity < 2:
            raise ValueError(f"capacity must be at least 2, got {capacity}")
        self.mesh = pv.PolyData(np.zeros((capacity, 3)))
        self.mesh.lines = np.concatenate([[capacity], np.arange(capacity)])
        self.actor = plotter.add_mesh(self.mesh, color=color, line_width=4,
                                      render_lines_as_tubes=True, reset_camera=False,
                                      pickable=False)
        self.actor.visibility = False
        self.count = 0  # slots holding points of the path

    @property
    def points(self) -> Array:
        """The polyline's points ``(capacity, 3)`` (the mesh's own array)."""
        return np.asarray(self.mesh.points)

    def push(self, point: ArrayLike) -> None:
        """Append ``point (3,)``."""
        pts = self.mesh.points
        p = np.asarray(point, dtype=np.float64).reshape(3)
        if self.count < len(pts):
            overwrite(pts, p, slice(self.count, None))
            self.count += 1
        else:
            overwrite(pts, pts[1:], slice(None, -1))
            pts[-1] = p
        self.mesh.Modified()
        self.actor.visibility = self.count > 1

    def set(self, points: ArrayLike) -> None:
        """Replace the path by ``points (N, 3)`` (the newest ``capacity`` of them)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)[-self.mesh.n_points:]
        if len(p) == 0:
            self.clear()
            return
        pts = self.mesh.points
        overwrite(pts, p, slice(None, len(p)))
        overwrite(pts, p[-1], slice(len(p), None))
        self.count = len(p)
        self.mesh.Modified()
        self.actor.visibility = len(p) > 1

    def clear(self) -> None:
        """Hide the path; the next point starts a new one."""
        self.count = 0
        self.actor.visibility = False
