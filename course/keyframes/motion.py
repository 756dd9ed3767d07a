r"""Keyframing a motion clip: keep every k-th frame, rebuild the rest, measure what was lost.

A :class:`~course.motion.Motion` is a dense set of keys: a root position
:math:`p_0(t)` and a local rotation :math:`R_j(t)` per joint at every frame. Keeping only
every :math:`k`-th frame (and the last) and interpolating the others back shows what an
animator's keys can and cannot hold: position curves (:mod:`.curves`) for the root,
rotation curves (:mod:`.rotations`) for every joint, and the error measured where it is
seen, on the joints' global positions after forward kinematics.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from ..data.registry import CMU_CM_PER_UNIT
from ..motion import Motion
from .curves import catmull_rom, cubic, linear
from .rotations import slerp_keys, squad

Array = NDArray[np.float64]


POSITION_SCHEMES: dict[str, Callable[..., Array]] = {
    "linear": linear,
    "cubic": cubic,
    "catmull_rom": catmull_rom,
}
ROTATION_SCHEMES: dict[str, Callable[..., Array]] = {"slerp": slerp_keys, "squad": squad}


def key_frames(n_frames: int, every: int) -> NDArray[np.intp]:
    """Frames ``0, k, 2k, ...`` and always the last one (so that every frame lies between
    two keys and none has to be extrapolated)."""
    if not isinstance(every, (int, np.integer)) or every < 1:
        raise ValueError(f"every: expected a positive number of frames, got {every!r}")
    if n_frames < 2:
        raise ValueError(f"motion: needs at least 2 frames to keyframe, has {n_frames}")
    frames = np.arange(0, n_frames, every)
    return frames if frames[-1] == n_frames - 1 else np.append(frames, n_frames - 1)


def keyframed(motion: Motion, every: int, *, positions: str = "catmull_rom",
              rotations: str = "squad") -> Motion:
    """The motion rebuilt from its keys at every ``every``-th frame (:func:`key_frames`).

    Parameters
    ----------
    motion : Motion
    every : int
        Keep frames ``0, every, 2 every, ...`` and the last; 1 gives the clip back.
    positions : {"linear", "cubic", "catmull_rom"}
        Scheme for the root positions (and animated bone vectors, if the clip has them);
        ``"cubic"`` is the natural spline.
    rotations : {"slerp", "squad"}
        Scheme for every joint's local rotation (the root's included).

    Returns
    -------
    Motion
        Same skeleton, frame count and frame time; every key frame is reproduced exactly.
    """
    if positions not in POSITION_SCHEMES:
        raise ValueError(f"positions: expected one of {tuple(POSITION_SCHEMES)}, got {positions!r}")
    if rotations not in ROTATION_SCHEMES:
        raise ValueError(f"rotations: expected one of {tuple(ROTATION_SCHEMES)}, got {rotations!r}")
    keys = key_frames(motion.n_frames, every)
    frames = np.arange(motion.n_frames, dtype=np.float64)
    curve = POSITION_SCHEMES[positions]
    rebuilt_rotations = ROTATION_SCHEMES[rotations](motion.local_rotations[keys], keys, frames)
    translations = None
    if motion.translations is not None:
        translations = curve(motion.translations[keys], keys, frames)
    return Motion(
        skeleton=motion.skeleton,
        local_rotations=rebuilt_rotations,
        root_positions=curve(motion.root_positions[keys], keys, frames),
        frame_time=motion.frame_time,
        channels=motion.channels,
        translations=translations,
        name=f"{motion.name} every {every} ({positions}, {rotations})",
        source=motion.source,
    )


def joint_position_error(motion: Motion, reference: Motion, *,
                         unit_cm: float = CMU_CM_PER_UNIT) -> Array:
    r"""Per frame, the mean distance between the joints of two motions after forward
    kinematics, :math:`\frac1J\sum_j \lVert p_j(t) - p_j^{\mathrm{ref}}(t)\rVert`, in cm.

    Parameters
    ----------
    motion, reference : Motion
        Same skeleton and frame count.
    unit_cm : float
        Centimetres per length unit of the clips (default: the CMU clips' ASF unit).

    Returns
    -------
    ndarray, shape (F,)
    """
    check_same_skeleton(motion, reference, "reference")
    if motion.n_frames != reference.n_frames:
        raise ValueError(
            f"reference: has {reference.n_frames} frames, motion has {motion.n_frames}"
        )
    p, _ = motion.forward_kinematics()
    p_ref, _ = reference.forward_kinematics()
    error: Array = unit_cm * np.linalg.norm(p - p_ref, axis=-1).mean(axis=-1)
    return error


def check_same_skeleton(motion: Motion, other: Motion, name: str) -> None:
    """A ``ValueError`` naming ``name`` unless ``other`` has ``motion``'s joint tree."""
    a, b = motion.skeleton, other.skeleton
    if a.names != b.names or not np.array_equal(a.parents, b.parents):
        raise ValueError(
            f"{name}: has a different skeleton ({b.n_joints} joints) from the motion's "
            f"({a.n_joints} joints); both clips must share one joint tree"
        )
