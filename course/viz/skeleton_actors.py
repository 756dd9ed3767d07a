"""One skeleton of a :class:`~course.viz.scene.SkeletonScene`: its meshes and actors.

Joints are a point set glyphed with spheres, bones a line set over the same points run
through a tube filter, and the optional axis triads a line set of 6 points per joint. Moving
the skeleton overwrites these points; nothing is rebuilt.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import Array
from .backend import configure_environment
from .live_view import shade
from .meshes import as_positions, move_points, segments, sphere_actor, tube_actor

configure_environment()

import pyvista as pv  # noqa: E402  (after the environment is set: VTK reads it on import)

AXIS_COLORS = np.array([[230, 57, 70], [42, 170, 82], [44, 110, 230]], dtype=np.uint8)
#: joint and bone radii of a faint (``opacity < 1``) pose, relative to a solid one's
FAINT_SIZE = 0.8


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

    @classmethod
    def build(cls, name: str, parents: NDArray[np.intp], positions: Array,
              colors: tuple[str, str], *, scale: float, opacity: float = 1.0,
              axes: bool = False, browser: bool = False) -> SkeletonActors:
        """The meshes and actors of a skeleton at ``positions (J, 3)``, sized by ``scale``
        (the triads, with ``axes``, are placed by :meth:`move`); ``browser``: for vtk.js."""
        n = parents.size
        bone_color, joint_color = colors
        points = pv.PolyData(positions.copy())
        bones = pv.PolyData()
        bones.SetPoints(points.GetPoints())  # the same vtkPoints: one write moves both
        bones.lines = segments(np.column_stack([parents[1:], np.arange(1, n)]))
        # a faint pose is drawn thinner: where a solid pose coincides with it (IK left a joint
        # in place) the solid one hides it whole, instead of the two fighting over the depth
        thin = FAINT_SIZE if opacity < 1.0 else 1.0
        joints_actor = sphere_actor(points, radius=0.022 * scale * thin, browser=browser)
        bones_actor = tube_actor(bones, radius=0.011 * scale * thin, browser=browser)
        shade(joints_actor, joint_color, opacity=opacity)
        shade(bones_actor, bone_color, specular=0.25, opacity=opacity)
        actors = [bones_actor, joints_actor]
        triads = None
        if axes:
            triads = pv.PolyData(np.zeros((6 * n, 3)))
            triads.lines = segments(np.arange(6 * n).reshape(-1, 2))
            triads.point_data["rgb"] = np.tile(np.repeat(AXIS_COLORS, 2, axis=0), (n, 1))
            triad_actor = tube_actor(triads, radius=0.0045 * scale, sides=10)
            mapper = triad_actor.mapper
            mapper.ScalarVisibilityOn()
            mapper.SetColorModeToDirectScalars()
            mapper.SetScalarModeToUsePointFieldData()
            mapper.SelectColorArray("rgb")
            actors.append(triad_actor)
        return cls(name, parents, bone_color, joint_color, points, bones, triads,
                   0.09 * scale, actors)

    @property
    def positions(self) -> Array:
        """The joint positions currently drawn, ``(J, 3)`` (a copy)."""
        return np.array(self.points.points, dtype=np.float64)

    def move(self, positions: ArrayLike, orientations: ArrayLike | None = None) -> Array:
        """Overwrite the joints (bones share their points) and the triads, if drawn (they
        need ``orientations (J, 4)``); returns the checked positions ``(J, 3)``."""
        pos = as_positions(positions, self.parents.size)
        move_points(self.points, pos)
        self.bones.Modified()
        if self.triads is not None:
            self._set_triads(self.triads, pos, orientations)
        return pos

    def _set_triads(self, triads: pv.PolyData, pos: Array, orientations: ArrayLike | None
                    ) -> None:
        if orientations is None:
            raise ValueError(f"orientations (J, 4) are needed to draw the axes of {self.name!r}")
        from course.rotations import matrix_from_quat

        R = matrix_from_quat(np.asarray(orientations, dtype=np.float64))
        if R.shape != (pos.shape[0], 3, 3):
            raise ValueError(f"orientations must have shape ({pos.shape[0]}, 4)")
        tips = pos[:, None, :] + self.axis_length * np.swapaxes(R, 1, 2)  # columns = local axes
        pts = np.asarray(triads.points).reshape(-1, 3, 2, 3)
        pts[:, :, 0] = pos[:, None, :]
        pts[:, :, 1] = tips
        triads.Modified()
