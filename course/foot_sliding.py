r"""Foot contacts and foot sliding 脚底打滑: how far a planted foot moves over the floor.

A foot that stands on the ground should not move. Retargeting (notebook 10) and blending
(notebook 11) both break that, and both are judged by one measure here:

1. **Contact frames** (:func:`foot_contacts`): a foot joint is in contact when it is *low*
   and *slow*, with both thresholds in the motion's own length unit, as fractions of the rest
   hip height :math:`h` (:func:`~course.retarget.rest_height`), so that a skeleton scaled by
   :math:`s` has the same contacts. Low: within :math:`0.1\,h` of that foot's lowest height in
   the clip (about 8 cm for a person; captured floors are rarely level to the centimetre, and
   toe and ankle joints sit at different heights, hence per foot). Slow: horizontal speed at
   most :math:`0.3\,h` per second (about 25 cm/s), since a swinging foot passes low but fast.
2. **Sliding** (:func:`foot_sliding`): between consecutive frames :math:`f, f+1` with the foot
   in contact at both, the horizontal (x, z) distance it moved, :math:`\lVert \Delta p_{xz}
   \rVert`, in centimetres; divided by the frame time, a speed in cm/s, which does not depend
   on the frame rate.

The speed threshold makes contacts circular on a clip that drags its feet (a dragged foot is
fast, so "not in contact"). Measure an edited clip on the contacts of the clip it was made
from: the source's for a retargeted clip, :func:`course.keyframes.concatenated_contacts` for a
blend.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._typing import Array, BoolArray
from .data.registry import CMU_CM_PER_UNIT
from .motion import Motion
from .retarget import rest_height
from .skeleton import JointNotFoundError

#: Contact thresholds as fractions of the rest hip height: height above the foot's lowest
#: point, and horizontal speed per second.
LOW, SLOW = 0.1, 0.3


def _feet(motion: Motion, feet: Sequence[str]) -> list[int]:
    if isinstance(feet, str) or not len(feet):
        raise ValueError(f"feet: expected a non-empty sequence of joint names, got {feet!r}")
    try:
        return [motion.skeleton.index(f) for f in feet]
    except JointNotFoundError as exc:
        raise ValueError(f"feet: {exc}") from None


def foot_contacts(
    motion: Motion,
    feet: Sequence[str],
    height_tolerance: float | None = None,
    speed_tolerance: float | None = None,
) -> BoolArray:
    """Contact frames per foot: the foot joint low *and* slow (see the module notes).

    Parameters
    ----------
    motion : Motion
    feet : sequence of str
        Foot joint names (toes or ankles), n of them.
    height_tolerance : float, optional
        Height above the foot's lowest point in the clip, in the motion's length unit.
        Default ``0.1 * rest_height``.
    speed_tolerance : float, optional
        Horizontal speed (central differences), motion units per second. Default
        ``0.3 * rest_height`` per second.

    Returns
    -------
    ndarray of bool, shape (F, n)
    """
    js = _feet(motion, feet)
    h = rest_height(motion.skeleton)
    low_tol = LOW * h if height_tolerance is None else float(height_tolerance)
    fast_tol = SLOW * h if speed_tolerance is None else float(speed_tolerance)
    if not (low_tol >= 0 and fast_tol >= 0):
        raise ValueError(f"height_tolerance, speed_tolerance: expected >= 0, got {low_tol}, "
                         f"{fast_tol}")
    P = motion.forward_kinematics()[0][:, js]
    y = P[..., 1]
    low: BoolArray = y <= y.min(axis=0) + low_tol
    if motion.n_frames < 2:
        return low
    speed = np.linalg.norm(np.gradient(P[..., [0, 2]], axis=0), axis=-1) / motion.frame_time
    contact: BoolArray = low & (speed <= fast_tol)
    return contact


@dataclass(frozen=True)
class FootSliding:
    """How far each foot moved while in contact: per frame step, and summed up per foot.

    Distances in centimetres, speeds in centimetres per second.

    Attributes
    ----------
    feet : tuple of str, n names
    contacts : ndarray of bool, shape (F, n)
        The contact frames measured on.
    steps_cm : ndarray, shape (F - 1, n)
        Horizontal distance moved from frame f to f + 1; NaN unless in contact at both.
    frame_time : float
        Seconds per frame.
    """

    feet: tuple[str, ...]
    contacts: BoolArray
    steps_cm: Array
    frame_time: float

    @property
    def speed_cm_per_s(self) -> Array:
        """Sliding speed per step and foot, shape (F - 1, n), NaN outside contacts."""
        speed: Array = self.steps_cm / self.frame_time
        return speed

    @property
    def contact_frames(self) -> NDArray[np.intp]:
        """Frames in contact per foot, shape (n,)."""
        return np.asarray(self.contacts.sum(axis=0), dtype=np.intp)

    @property
    def total_cm(self) -> Array:
        """Distance slid per foot over the clip, shape (n,)."""
        return np.asarray(np.nansum(self.steps_cm, axis=0), dtype=np.float64)

    @property
    def mean_cm_per_s(self) -> Array:
        """Mean sliding speed per foot over its contact steps, shape (n,); NaN without any."""
        steps = (~np.isnan(self.steps_cm)).sum(axis=0)
        mean: Array = np.divide(self.total_cm / self.frame_time, steps,
                                out=np.full(len(self.feet), np.nan), where=steps > 0)
        return mean

    def __str__(self) -> str:
        # NaN only for a foot never down (or a one-frame clip: no steps at all)
        speed = np.fmax.reduce(self.speed_cm_per_s, axis=0, initial=np.nan)
        return "\n".join(
            f"{foot:<14} {n:4d} contact frames: slides {total:6.2f} cm, {mean:6.2f} cm/s mean, "
            f"{top:6.2f} cm/s max"
            for foot, n, total, mean, top in zip(self.feet, self.contact_frames, self.total_cm,
                                                 self.mean_cm_per_s, speed, strict=True)
        )


def foot_sliding(
    motion: Motion,
    feet: Sequence[str],
    contacts: ArrayLike | None = None,
    cm_per_unit: float = CMU_CM_PER_UNIT,
) -> FootSliding:
    """Horizontal (x, z) motion of each foot between consecutive contact frames.

    Parameters
    ----------
    motion : Motion
    feet : sequence of str
        Foot joint names, n of them.
    contacts : array_like of bool, shape (F, n), optional
        Default: :func:`foot_contacts` of this clip. Pass the source clip's contacts to
        measure an edited clip (retargeted, blended) on the frames its feet should stand.
    cm_per_unit : float
        Centimetres per length unit of the motion (default: CMU's).

    Returns
    -------
    FootSliding
    """
    js = _feet(motion, feet)
    on = foot_contacts(motion, feet) if contacts is None else np.asarray(contacts)
    if on.dtype != np.bool_ or on.shape != (motion.n_frames, len(js)):
        raise ValueError(f"contacts: expected booleans of shape ({motion.n_frames}, {len(js)}), "
                         f"got {on.dtype} {on.shape}")
    if not cm_per_unit > 0:
        raise ValueError(f"cm_per_unit: expected > 0, got {cm_per_unit}")
    xz = motion.forward_kinematics()[0][:, js][..., [0, 2]]
    step = np.linalg.norm(np.diff(xz, axis=0), axis=-1) * cm_per_unit
    return FootSliding(tuple(feet), on, np.where(on[1:] & on[:-1], step, np.nan),
                       float(motion.frame_time))
