r"""Blending and concatenating clips: align the second to the first, cross-fade, check the feet.

Playing clip B after clip A needs two things the lecture names:

1. **Alignment**: B was captured somewhere else, facing some other way. Its root trajectory
   is moved on the ground plane (x, z; y is up) and turned about the vertical axis (yaw
   only: pitch and roll belong to the pose) so that B starts where, and facing the way, A
   is at the start of the transition. Heights are left alone.
2. **Cross-fade** over :math:`n` frames: the last :math:`n` frames of A and the first
   :math:`n` of B are played together, with a weight :math:`w` rising smoothly from 0 to
   1 (smoothstep :math:`w = 3a^2 - 2a^3`, :math:`a = (k+1)/(n+1)`): root positions by
   linear interpolation, every joint's rotation by SLERP.

The result has :math:`F_A + F_B - n` frames. A blend is only as good as its feet: during the
transition a foot that stands in both clips may stand at two different places, and the
weighted average drags it over the floor. :func:`course.foot_sliding.foot_sliding` measures
that, on the contacts of the two clips (:func:`concatenated_contacts`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import rotations as rot
from .._typing import BoolArray
from ..motion import Motion
from .motion import check_same_skeleton

Array = NDArray[np.float64]


def facing_yaw(q: Array) -> Array:
    r"""The heading (yaw about +y, radians) of orientations (..., 4): the angle of the body's
    forward axis :math:`Q e_z` projected on the ground plane, :math:`\operatorname{atan2}(x, z)`."""
    forward = rot.quat_rotate(q, np.array([0.0, 0.0, 1.0]))
    return np.arctan2(forward[..., 0], forward[..., 2])


def aligned(motion: Motion, position: Array, yaw: float) -> Motion:
    r"""The motion turned about the vertical through its first frame's root by the angle that
    makes its first frame face ``yaw``, and moved on the ground so that this root stands at
    ``position``'s x and z (its height is kept).

    Parameters
    ----------
    motion : Motion
    position : array_like, shape (3,)
        Where the root of the first frame goes (only x and z are used).
    yaw : float
        Heading of the first frame afterwards (see :func:`facing_yaw`), radians.
    """
    turn = yaw - float(facing_yaw(motion.local_rotations[0, 0]))
    q_turn = rot.quat_from_axis_angle([0.0, 1.0, 0.0], turn)
    start = motion.root_positions[0] * np.array([1.0, 0.0, 1.0])
    target = np.asarray(position, dtype=np.float64) * np.array([1.0, 0.0, 1.0])
    local = motion.local_rotations.copy()
    local[:, 0] = rot.quat_mul(q_turn, local[:, 0])
    return Motion(
        skeleton=motion.skeleton,
        local_rotations=local,
        root_positions=rot.quat_rotate(q_turn, motion.root_positions - start) + target,
        frame_time=motion.frame_time,
        channels=motion.channels,
        translations=motion.translations,
        name=motion.name,
        source=motion.source,
    )


def smoothstep(n: int) -> Array:
    r"""The cross-fade weights :math:`w_k = 3a^2 - 2a^3`, :math:`a = (k+1)/(n+1)`, k < n:
    strictly between 0 and 1, rising with zero slope at both ends."""
    a = np.arange(1, n + 1) / (n + 1)
    return 3 * a**2 - 2 * a**3


def concatenate(first: Motion, second: Motion, blend_frames: int = 0) -> Motion:
    """``first`` followed by ``second``, aligned and cross-faded over ``blend_frames`` frames.

    ``second`` is :func:`aligned` so that its first frame stands where, and faces the way,
    ``first`` does at frame ``F_A - n``, the start of the transition. For a plain cut
    (``n = 0``) it faces the way ``first`` does at its last frame and stands one frame of
    ``first``'s root velocity beyond it, so that the root keeps moving across the cut. The
    ``n`` overlapping frames are blended with the :func:`smoothstep` weights: root positions
    linearly, joint rotations by SLERP.

    Parameters
    ----------
    first, second : Motion
        One skeleton (same joint names and parents) and one frame time.
    blend_frames : int
        ``n``, from 0 (a hard cut) up to the length of the shorter clip.

    Returns
    -------
    Motion
        ``F_A + F_B - n`` frames, on ``first``'s skeleton; frame ``F_A - n`` starts the
        transition.
    """
    check_same_skeleton(first, second, "second")
    for name, clip in (("first", first), ("second", second)):
        if clip.translations is not None:
            raise ValueError(f"{name}: clips with animated bone vectors cannot be blended")
    if not np.isclose(first.frame_time, second.frame_time):
        raise ValueError(
            f"second: frame time {second.frame_time:g} s differs from the first clip's "
            f"{first.frame_time:g} s; resample one of them first"
        )
    n = blend_frames
    if not isinstance(n, (int, np.integer)) or not 0 <= n <= min(first.n_frames, second.n_frames):
        raise ValueError(
            f"blend_frames: expected an integer from 0 to {min(first.n_frames, second.n_frames)}"
            f" (the shorter clip), got {n!r}"
        )
    anchor = first.n_frames - max(n, 1)
    start = first.root_positions[anchor]
    if n == 0 and first.n_frames > 1:  # a cut: B starts one frame of A's velocity further on
        start = 2 * start - first.root_positions[anchor - 1]
    second = aligned(second, start, float(facing_yaw(first.local_rotations[anchor, 0])))
    head = first.n_frames - n
    w = smoothstep(n)
    fade_rot = rot.slerp(first.local_rotations[head:], second.local_rotations[:n], w[:, None])
    fade_pos = rot.lerp(first.root_positions[head:], second.root_positions[:n], w)
    return Motion(
        skeleton=first.skeleton,
        local_rotations=np.concatenate(
            [first.local_rotations[:head], fade_rot, second.local_rotations[n:]]),
        root_positions=np.concatenate(
            [first.root_positions[:head], fade_pos, second.root_positions[n:]]),
        frame_time=first.frame_time,
        channels=first.channels,
        name=f"{first.name} + {second.name} (blend {n})",
    )


def concatenated_contacts(first: ArrayLike, second: ArrayLike, blend_frames: int) -> BoolArray:
    """Contact frames of ``concatenate(A, B, n)`` from the clips' own contacts.

    Frames taken from one clip keep its contacts; in the ``n`` cross-faded frames a foot is in
    contact where it is in *both* clips: it stands in both, so the blend should leave it
    standing (where it drags it, :func:`course.foot_sliding.foot_sliding` measures that).
    Contacts of a blend cannot be found on the blend itself: a dragged foot moves fast and
    would not count as standing.

    Parameters
    ----------
    first, second : array_like of bool, shape (F_A, n_feet), (F_B, n_feet)
        :func:`course.foot_sliding.foot_contacts` of A and of B (as passed to ``concatenate``).
    blend_frames : int
        The ``n`` given to :func:`concatenate`.

    Returns
    -------
    ndarray of bool, shape (F_A + F_B - n, n_feet)
    """
    a, b = np.asarray(first), np.asarray(second)
    if a.dtype != np.bool_ or b.dtype != np.bool_ or a.ndim != 2 or b.shape[1:] != a.shape[1:]:
        raise ValueError(f"first, second: expected booleans of shapes (F_A, n_feet) and "
                         f"(F_B, n_feet), got {a.dtype} {a.shape} and {b.dtype} {b.shape}")
    n = blend_frames
    if not isinstance(n, (int, np.integer)) or not 0 <= n <= min(len(a), len(b)):
        raise ValueError(f"blend_frames: expected an integer from 0 to {min(len(a), len(b))}, "
                         f"got {n!r}")
    head = len(a) - n
    return np.concatenate([a[:head], a[head:] & b[:n], b[n:]])
