r"""Cyclic Coordinate Descent: one joint at a time, turn the effector towards the target.

For joint :math:`i` at :math:`r_i`, with effector :math:`e` and target :math:`t`, the joint is
turned by the shortest arc taking :math:`e - r_i` onto :math:`t - r_i` (``quat_between``);
a hinge joint by the angle about its axis between the two vectors projected on its plane.
A sweep visits every joint, tip to root (the usual order) or root to tip, and sweeps repeat
until the effector is within tolerance.

With several effectors below a joint, the joint takes the rotation that best turns all their
offsets onto their targets' offsets (Kabsch; the shortest arc when there is one).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._chains import Problem
from ._small import (
    TINY,
    best_rotation,
    cross,
    dot,
    matvec,
    norm,
    orthonormalize,
    rotvec_matrix,
    rotvec_of,
)
from .result import History

Array = NDArray[np.float64]


def ccd_positions(
    positions: ArrayLike,
    target: ArrayLike,
    tol: float = 1e-4,
    max_iter: int = 200,
    tip_to_root: bool = True,
) -> tuple[Array, int, float]:
    r"""CCD on a chain of points with ball joints, the lecture's picture.

    Parameters
    ----------
    positions : array_like, shape (n, 3)
        Joint positions; ``positions[0]`` is the fixed root, the last one the effector.
    target : array_like, shape (3,)
    tol, max_iter :
        Stop when the effector is within ``tol`` or after ``max_iter`` sweeps.
    tip_to_root : bool
        Visit joints from the one next to the effector down to the root (else the reverse).

    Returns
    -------
    positions : ndarray, shape (n, 3)
    sweeps : int
    error : float
    """
    from course.rotations import quat_between
    from course.rotations._checks import as_array
    from course.rotations.quaternion import _rotate

    P = as_array(positions, "positions", (3,)).copy()
    t = as_array(target, "target", (3,))
    if P.ndim != 2 or len(P) < 2:
        raise ValueError(f"positions: expected shape (n, 3) with n >= 2, got {P.shape}")
    order = range(len(P) - 2, -1, -1) if tip_to_root else range(len(P) - 1)
    sweeps = 0
    err = float(norm(P[-1] - t))
    while err >= tol and sweeps < max_iter:
        for i in order:
            u, v = P[-1] - P[i], t - P[i]
            if norm(u) < TINY or norm(v) < TINY:
                continue  # effector or target on the joint: no direction to turn to
            q = quat_between(u, v)  # R_i <- quat_between(e - r_i, t - r_i) R_i
            P[i + 1:] = P[i] + _rotate(q, P[i + 1:] - P[i])
        sweeps += 1
        err = float(norm(P[-1] - t))
    return P, sweeps, err


def solve_problem(
    problem: Problem,
    tol: float,
    max_iter: int,
    tip_to_root: bool = True,
    max_angle: float | None = None,
    record: bool = False,
) -> tuple[Array, History, list[Array]]:
    """CCD on a :class:`~course.ik._chains.Problem`; ``max_angle`` caps each joint's turn per
    step (radians). Limits are enforced by projecting after every joint's turn."""
    m = problem.model
    if len(m.rot_effectors):
        raise ValueError("targets: CCD here reaches positions only; use a Jacobian method "
                         "(e.g. method='dls') for orientation targets")
    Rn = problem.Rn.copy()
    M, p = problem.forward(Rn)
    history = History(problem.error(M, p)[1], tol, max_iter)
    frames = [Rn.copy()] if record else []
    first_col = np.searchsorted(m.col_var, np.arange(len(m.var_nodes)))
    order = np.arange(len(m.var_nodes))
    if tip_to_root:
        order = order[::-1]
    axes_local = problem._axes()
    limited = np.isfinite(problem.hinge_limits).any() or np.isfinite(problem.ball_limit).any()
    t = problem.target_pos
    while history.active.any():
        run = history.active[:, None, None]
        for v in order:
            d = m.var_nodes[v]
            piv = p[:, m.pivot[d]][:, None]
            mask = m.pos_mask[:, first_col[v]] > 0
            u = p[:, m.effectors] - piv
            w = t - piv
            if m.hinge[v]:
                frame = M[:, d] if m.up[d] else (M[:, m.parent[d]] if d else problem.base)
                a = matvec(frame, axes_local[v])[:, None]  # (B, 1, 3)
                up_ = u - dot(u, a)[..., None] * a
                wp = w - dot(w, a)[..., None] * a
                angle = np.arctan2((dot(a, cross(up_, wp)) * mask).sum(-1),
                                   (dot(up_, wp) * mask).sum(-1))
                R = rotvec_matrix(a[:, 0] * angle[..., None])
            else:
                R = best_rotation(u[:, mask], w[:, mask])
            if max_angle is not None:
                rv = rotvec_of(R)
                ang = norm(rv)
                shrink = np.minimum(1.0, max_angle / np.maximum(ang, TINY))
                R = rotvec_matrix(rv * shrink[..., None])
            R = np.where(run, R, np.eye(3))
            Mpar = (M[:, m.parent[d]] if d else problem.base)
            if m.up[d]:  # R_c = M_d^T M_parent  ->  (M_d^T R^T M_d) R_c
                Rn[:, d] = orthonormalize(
                    np.swapaxes(M[:, d], -1, -2) @ np.swapaxes(R, -1, -2) @ M[:, d] @ Rn[:, d])
            else:  # R_d = M_parent^T M_d  ->  (M_parent^T R M_parent) R_d
                Rn[:, d] = orthonormalize(np.swapaxes(Mpar, -1, -2) @ R @ Mpar @ Rn[:, d])
            if limited:
                Rn = problem.project(Rn)
                M, p = problem.forward(Rn)
            else:  # turn the moved subtree about the pivot instead of redoing the forward pass
                moved = m.descendant[d].copy()
                if not m.up[d]:
                    moved[d] = False
                M[:, m.descendant[d]] = R[:, None] @ M[:, m.descendant[d]]
                p[:, moved] = piv + matvec(R[:, None], p[:, moved] - piv)
        history.update(problem.error(M, p)[1])
        if record:
            frames.append(Rn.copy())
    return Rn, history, frames
