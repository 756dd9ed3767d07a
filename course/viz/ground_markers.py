"""The balance markers of a simulated character's 3D view: its COM and capture point drawn on
the floor, and the push while it acts (notebooks 15 and 16).

The COM's projection is a disc, the capture point :math:`\\xi = c + \\dot c/\\omega_0`
(:func:`course.physics.lip.capture_point`, :math:`\\omega_0 = \\sqrt{g/h}` with :math:`h` the
COM's height over the floor) a ring, with a line between them: while the ring stays inside
the feet the character can stand without a step. The push is an arrow's shaft into the root.
Their points are overwritten in place; nothing is rebuilt.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .backend import configure_environment
from .live_view import shade
from .meshes import move_points, tube_actor
from .scene import SkeletonScene

configure_environment()

import pyvista as pv  # noqa: E402  (after the environment is set: VTK reads it on import)

COLORS = {"capture": "#f5a623", "com": "#3d4a5c", "push": "#8e6bd8"}


def y_up(v: ArrayLike) -> Array:
    """MuJoCo's z-up ``(x, y, z)`` as the course's y-up ``(x, z, -y)``."""
    a = np.asarray(v, dtype=np.float64)
    return np.array([a[0], a[2], -a[1]])


def com_state(character: Any, model: Any, data: Any, ground_height: float
              ) -> tuple[Array, Array, Array]:
    """The whole-body COM ``c (3,)`` and its velocity ``ċ (3,)`` (y-up m, m/s: the subtree
    COM's Jacobian times ``qvel``) of MuJoCo's ``data``, and the capture point ``ξ (2,)``
    ``(x, z)`` in m over a floor at ``ground_height`` (y-up m)."""
    from course.physics.balance import com_jacobian
    from course.physics.lip import capture_point, natural_frequency

    c = y_up(data.subtree_com[int(character.bodies[0])])
    v = y_up(com_jacobian(character, model, data) @ data.qvel)
    w0 = natural_frequency(max(c[1] - ground_height, 1e-3))
    xi: Array = capture_point(c[[0, 2]], v[[0, 2]], w0)
    return c, v, xi


def color_key(entries: Sequence[tuple[str, str]]) -> str:
    """One line of HTML naming what each colour draws: ``entries`` of ``(color, label)``."""
    return " ".join(
        f"<span style='white-space:nowrap'><span style='display:inline-block;width:10px;"
        f"height:10px;background:{color};margin:0 4px 0 6px'></span>{label}</span>"
        for color, label in entries)


class GroundMarkers:
    """The COM disc, the capture point's ring, the line between them and the push's arrow of
    ``scene``, over a floor at ``ground_height`` (skeleton units); ``meters`` per skeleton
    unit size them."""

    def __init__(self, scene: SkeletonScene, *, ground_height: float, meters: float) -> None:
        self.scene = scene
        self.ground_height, self.meters = float(ground_height), float(meters)
        u = 1.0 / self.meters  # skeleton units per meter
        self.lift = 0.012 * u  # above the floor and any footprints
        plotter, browser = scene.plotter, scene._in_browser
        self._com_disc = pv.Disc(center=(0.0, 0.0, 0.0), inner=0.0, outer=0.035 * u,
                                 normal=(0.0, 1.0, 0.0), c_res=24)
        self._xi_ring = pv.Disc(center=(0.0, 0.0, 0.0), inner=0.04 * u, outer=0.07 * u,
                                normal=(0.0, 1.0, 0.0), c_res=32)
        self._com_base = np.array(self._com_disc.points)
        self._xi_base = np.array(self._xi_ring.points)
        for mesh, color in ((self._com_disc, COLORS["com"]), (self._xi_ring, COLORS["capture"])):
            actor = plotter.add_mesh(mesh, color=color, reset_camera=False, pickable=False)
            shade(actor, color, specular=0.1)
        self._link = pv.PolyData(np.zeros((2, 3)), lines=np.array([2, 0, 1]))
        link = tube_actor(self._link, 0.008 * u, browser=browser)
        shade(link, COLORS["capture"], specular=0.1)
        plotter.add_actor(link, reset_camera=False, pickable=False)
        self._push_line = pv.PolyData(np.zeros((2, 3)), lines=np.array([2, 0, 1]))
        self._push_actor = tube_actor(self._push_line, 0.02 * u, browser=browser)
        shade(self._push_actor, COLORS["push"])
        plotter.add_actor(self._push_actor, reset_camera=False, pickable=False)
        self._push_actor.visibility = False
        self._com = np.zeros(3)
        self._xi = np.zeros(3)

    def set_ground_points(self, com: ArrayLike, capture_point: ArrayLike) -> None:
        """Put the COM's disc under ``com (3,)`` and the capture point's ring at
        ``capture_point``, ``(x, z)`` or ``(3,)`` (heights are ignored: both lie on the
        floor)."""
        c = np.asarray(com, dtype=np.float64).ravel()
        xi = np.asarray(capture_point, dtype=np.float64).ravel()
        xz = xi[[0, 2]] if xi.size == 3 else xi
        y = self.ground_height + self.lift
        self._com = np.array([c[0], y, c[2]])
        self._xi = np.array([xz[0], y, xz[1]])
        move_points(self._com_disc, self._com_base + self._com)
        move_points(self._xi_ring, self._xi_base + self._xi)
        move_points(self._link, np.array([self._com, self._xi]))

    def follow(self, character: Any, model: Any, data: Any, ground_height: float,
               root: ArrayLike | None, force: ArrayLike | None) -> tuple[Array, Array, Array]:
        """The markers where MuJoCo's ``data`` has ``character``: its COM and capture point
        (:func:`com_state` over a floor at ``ground_height``, y-up m) and the push ``force``
        on ``root`` (skeleton units; ``None``: no push acts). Returns :func:`com_state`'s
        ``(c, ċ, ξ)``, computed once per frame for the readout too."""
        state = com_state(character, model, data, ground_height)
        self.set_ground_points(state[0] / character.scale, state[2] / character.scale)
        self.show_push(root, force)
        return state

    @property
    def com_marker(self) -> Array:
        """Where the COM's disc is drawn ``(3,)`` (on the floor)."""
        return np.array(self._com)

    @property
    def capture_marker(self) -> Array:
        """Where the capture point's ring is drawn ``(3,)`` (on the floor)."""
        return np.array(self._xi)

    def show_push(self, root: ArrayLike | None, force: ArrayLike | None) -> None:
        """Draw the push acting on ``root (3,)`` along ``force (3,)`` (N; 0.4 m per 100 N, at
        most 1 m), or hide it (``None``)."""
        if root is None or force is None:
            self._push_actor.visibility = False
            return
        f = np.asarray(force, dtype=np.float64)
        size = float(np.linalg.norm(f))
        if size > 0:
            length = min(0.004 * size, 1.0) / self.meters
            end = np.asarray(root, dtype=np.float64)
            move_points(self._push_line, np.array([end - f / size * length, end]))
        self._push_actor.visibility = size > 0

    @property
    def push_segment(self) -> Array:
        """The push's arrow ``(2, 3)``: from its tail to the root it pushes (as last drawn)."""
        return np.array(self._push_line.points)

    @property
    def push_shown(self) -> bool:
        """Whether the push's arrow is drawn."""
        return bool(self._push_actor.visibility)


__all__: Sequence[str] = ("COLORS", "GroundMarkers", "color_key", "com_state", "y_up")
