r"""Cyclic Coordinate Descent: one joint at a time, turn the effector towards the target.

For joint :math:`i` at :math:`r_i`, with effector :math:`e` and target :math:`t`, the joint is
turned by the shortest arc taking :math:`e - r_i` onto :math:`t - r_i` (``quat_between``);
a hinge joint by the angle about its axis between the two vectors projected on its plane.
A sweep visits every joint, tip to root (the usual order) or root to tip, and sweeps repeat
until the effector is within tolerance (:func:`ccd_positions`, batched over chains).

With several effectors below a joint, the joint takes the rotation that best turns all their
offsets onto their targets' offsets (Kabsch; the shortest arc when there is one).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from course._typing import Array
from course._validate import as_point_chains
from course.rotations._kernels import TINY, norm, quat_between, quat_rotate


def ccd_positions(
    positions: ArrayLike,
    target: ArrayLike,
    tol: float = 1e-4,
    max_iter: int = 200,
    tip_to_root: bool = True,
) -> tuple[Array, Any, Any]:
    r"""CCD on a chain of points with ball joints, the lecture's picture, batched over leading
    dimensions.

    Parameters
    ----------
    positions : array_like, shape (..., n, 3)
        Joint positions; ``positions[..., 0, :]`` is the fixed root, the last one the effector.
    target : array_like, shape (..., 3)
    tol, max_iter :
        Stop when the effector is within ``tol`` or after ``max_iter`` sweeps (each problem of
        a batch on its own).
    tip_to_root : bool
        Visit joints from the one next to the effector down to the root (else the reverse).

    Returns
    -------
    positions : ndarray, shape (..., n, 3)
    sweeps : int, or ndarray of int, shape (...)
    error : float, or ndarray, shape (...)

    Raises
    ------
    ValueError
        If an argument has the wrong shape or is not finite.
    """
    P, t, batch = as_point_chains(positions, target)
    n = P.shape[-2]
    order = range(n - 2, -1, -1) if tip_to_root else range(n - 1)
    sweeps = np.zeros(len(P), dtype=int)
    err = norm(P[:, -1] - t)
    active = (err >= tol) & (sweeps < max_iter)
    while active.any():
        for i in order:  # one sweep: every joint in turn
            u, v = P[:, -1] - P[:, i], t - P[:, i]
            # Effector or target on the joint: no direction to turn to.
            turn = active & (norm(u) >= TINY) & (norm(v) >= TINY)
            q = quat_between(u[turn], v[turn])  # R_i <- quat_between(e - r_i, t - r_i) R_i
            pivot = P[turn, i, None]
            P[turn, i + 1:] = pivot + quat_rotate(q[:, None], P[turn, i + 1:] - pivot)
        sweeps += active
        err = np.where(active, norm(P[:, -1] - t), err)
        active &= (err >= tol) & (sweeps < max_iter)
    if not batch:  # one chain: plain numbers
        return P[0], int(sweeps[0]), float(err[0])
    return P.reshape(batch + (n, 3)), sweeps.reshape(batch), err.reshape(batch)
