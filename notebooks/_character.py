"""Helpers of notebook 09 (全身IK on a CMU clip): notebook 05's frame-to-frame measures of
joint motion, for ball joints."""

from __future__ import annotations

import numpy as np

from course import rotations as rot
from course._typing import Array


def angular_steps(local_rotations: Array, joints: list[int]) -> Array:
    r"""Per frame and joint, the turn from one frame to the next as a rotation vector,
    :math:`\omega_f = \log(R_f^{-1} R_{f+1})`: shape (F - 1, n, 3), radians."""
    R = np.asarray(local_rotations)[:, joints]
    step = rot.quat_mul(rot.quat_conjugate(R[:-1]), R[1:])
    return rot.rotvec_from_quat(step * np.where(step[..., :1] < 0, -1.0, 1.0))  # q ~ -q


def jitter(local_rotations: Array, joints: list[int]) -> tuple[float, float]:
    """Notebook 05's measures for ball joints, in degrees: the mean change per frame (the
    turns summed over the joints) and the largest jerk (the change of that change)."""
    w = angular_steps(local_rotations, joints)
    change = np.degrees(np.linalg.norm(w, axis=-1).sum(1))
    jerk = np.degrees(np.linalg.norm(np.diff(w, axis=0), axis=-1).sum(1))
    return float(change.mean()), float(jerk.max())
