"""Where a skeleton scene's camera stands: the region to keep in view and the presets.

A :class:`Framing` is measured once, from the first skeleton of a scene (its pose, a clip's
frames or a sphere of reach), and then aims the camera for each preset direction.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .._typing import Array

CAMERA_PRESETS = ("iso", "front", "side", "top", "follow")
#: (direction from the focal point to the camera, up) of each preset
PRESET_DIRECTIONS: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "iso": ((0.55, 0.38, 1.0), (0.0, 1.0, 0.0)),
    "follow": ((0.55, 0.38, 1.0), (0.0, 1.0, 0.0)),
    "front": ((0.0, 0.12, 1.0), (0.0, 1.0, 0.0)),
    "side": ((1.0, 0.12, 0.0), (0.0, 1.0, 0.0)),
    "top": ((0.0, 1.0, 0.0), (0.0, 0.0, -1.0)),
}
HALF_ANGLE = np.radians(15.0)  # the cameras' vertical view angle is 30 degrees


@dataclass
class Framing:
    """The region a scene keeps in view.

    Attributes
    ----------
    scale : the size of the first pose (its extent, or 2.5 bones): glyphs are sized by it.
    center, radius : a sphere around everything framed.
    fit_points : (N, 3) points framed by projection (a clip seen from each side); None frames
        the sphere.
    envelope : (M, 3) a clip's poses about their root, on the floor (the follow camera).
    sphere : frame the whole sphere, seen the same from every side (a sphere of reach).
    """

    scale: float = 1.0
    center: Array = field(default_factory=lambda: np.zeros(3))
    radius: float = 1.0
    fit_points: Array | None = None
    envelope: Array | None = None
    sphere: bool = False

    @classmethod
    def of(cls, points: Array, pose: Array, parents: NDArray[np.intp], *, headroom: bool,
           sphere: bool, envelope: Array | None = None) -> Framing:
        """Glyphs sized by ``pose``; ``points`` covered (with ``headroom``, also a pose whose
        limbs swing out further; with ``sphere``, the bounding sphere)."""
        pts = points.reshape(-1, 3)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        bone = np.linalg.norm(pose[1:] - pose[parents[1:]], axis=1)
        scale = float(max(np.ptp(pose, axis=0).max(), 2.5 * bone.max(initial=0.0), 1e-6))
        center = (lo + hi) / 2
        radius = float(max(np.linalg.norm(pts - center, axis=1).max(),
                           (0.65 if headroom else 0.5) * scale))
        # a clip is framed by what each view sees of it (subsampled): a walk seen from the
        # front is one person, not a 20 m sphere
        fit = None if sphere or headroom else pts[:: max(1, len(pts) // 4000)]
        return cls(scale, center, radius, fit, envelope, sphere)

    def aim(self, preset: str, window_size: Sequence[int], root: Array | None = None
            ) -> tuple[Array, Array, Array]:
        """(focal point, camera position, up) of ``preset``; ``root`` (3,): the followed
        skeleton's root, for ``"follow"``."""
        direction, up_dir = PRESET_DIRECTIONS[preset]
        d = np.asarray(direction) / np.linalg.norm(direction)
        up = np.asarray(up_dir, dtype=np.float64)
        # a sphere of reach, with a margin; a lone pose's headroom is margin enough
        distance = self.radius * (1.15 / np.sin(HALF_ANGLE) if self.sphere
                                  else 1.05 / np.tan(HALF_ANGLE))
        focal = self.center
        if self.fit_points is not None:
            focal, distance = self.fit_view(d, up, window_size, self.fit_points)
        if root is not None:
            if self.envelope is not None:  # the clip's largest pose, where the root is now
                focal, distance = self.fit_view(d, up, window_size,
                                                self.envelope + root * [1.0, 0.0, 1.0])
            else:
                focal = np.array([root[0], self.center[1], root[2]])
                distance = 1.15 * 0.6 * self.scale / np.tan(HALF_ANGLE)
        return focal, focal + distance * d, up

    def fit_view(self, d: Array, up: Array, window_size: Sequence[int], points: Array
                 ) -> tuple[Array, float]:
        """Focal point and distance along ``d`` at which every one of ``points (N, 3)``, with
        its joint sphere, is in view (perspective, 30 degrees vertically, the window's aspect,
        a 10% margin)."""
        right = np.cross(up, d)
        right /= np.linalg.norm(right)
        true_up = np.cross(d, right)
        rel = points - self.center
        x, y, z = rel @ right, rel @ true_up, rel @ d  # z: towards the camera
        focal = self.center + right * (x.max() + x.min()) / 2 + true_up * (y.max() + y.min()) / 2
        pad = 0.03 * self.scale  # a joint sphere's radius and a little more
        x = np.abs(x - (x.max() + x.min()) / 2) + pad
        y = np.abs(y - (y.max() + y.min()) / 2) + pad
        w, h = window_size
        tan_v = np.tan(HALF_ANGLE) / 1.1
        tan_h = tan_v * w / h
        return focal, float(max((z + pad + y / tan_v).max(), (z + pad + x / tan_h).max(), 1e-6))
