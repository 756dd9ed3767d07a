r"""Jacobian IK: transpose, pseudo-inverse and damped least squares.

Each iteration linearises forward kinematics around the current pose,
:math:`\Delta e \approx J\,\Delta\theta`, and picks an increment:

* **Jacobian transpose** (gradient descent on :math:`\frac12\lVert e\rVert^2`):
  :math:`\Delta\theta = \alpha J^T\Delta e` with Buss's step
  :math:`\alpha = \langle\Delta e, JJ^T\Delta e\rangle / \langle JJ^T\Delta e, JJ^T\Delta e\rangle`.
* **Pseudo-inverse** (least squares): :math:`\Delta\theta = J^+\Delta e`, where
  :math:`J^+ = J^T(JJ^T)^{-1}` for a wide :math:`J` (more joints than error rows: the smallest
  step) and :math:`(J^TJ)^{-1}J^T` for a tall one; both are computed from the SVD
  :math:`J = U\Sigma V^T` as :math:`V\Sigma^+U^T`, dropping singular values below
  ``rcond`` times the largest, which is what keeps it finite near singular poses.
* **Damped least squares** (Levenberg-Marquardt):
  :math:`\min \lVert J\Delta\theta - \Delta e\rVert^2 + \lambda^2\lVert W\Delta\theta\rVert^2`,
  :math:`\Delta\theta = W^{-2}J^T(JW^{-2}J^T + \lambda^2 I)^{-1}\Delta e`. Here ``damping``
  is :math:`\lambda` (a length, in the skeleton's units); the lecture's
  :math:`\lambda\lVert W\Delta\theta\rVert^2` form is the same with its :math:`\lambda` equal
  to our :math:`\lambda^2`. A larger weight :math:`W_i` makes joint *i* move less.

The columns: hinge joint *i* with world axis :math:`a_i` at :math:`r_i` contributes
:math:`a_i \times (e - r_i)`; a ball joint three such columns for the world axes x, y, z
(its increment is a rotation vector in world space, see :mod:`course.ik._engine.tree`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from course._typing import Array
from course.rotations._kernels import cross


def chain_jacobian(pivots: ArrayLike, axes: ArrayLike, effector: ArrayLike) -> Array:
    r"""Positional Jacobian of a chain of revolute joints, :math:`J_i = a_i \times (e - r_i)`.

    Parameters
    ----------
    pivots : array_like, shape (..., n, 3)
        World positions :math:`r_i` of the joints.
    axes : array_like, shape (..., n, 3)
        World rotation axes :math:`a_i` (unit), after the preceding joints' rotations.
    effector : array_like, shape (..., 3)
        End-effector position :math:`e`.

    Returns
    -------
    ndarray, shape (..., 3, n)
    """
    r = np.asarray(effector, float)[..., None, :] - np.asarray(pivots, float)
    return np.swapaxes(cross(np.asarray(axes, float), r), -1, -2)


def finite_difference_jacobian(
    f: Callable[[Array], ArrayLike], theta: ArrayLike, eps: float = 1e-6
) -> Array:
    r"""Central differences :math:`J_{:,i} = (f(\theta + \epsilon e_i) - f(\theta - \epsilon e_i))
    / 2\epsilon`, to check an analytic Jacobian (error :math:`O(\epsilon^2)`).

    Parameters
    ----------
    f : callable
        Maps parameters (n,) to outputs (m,) (or any shape, flattened).
    theta : array_like, shape (n,)

    Returns
    -------
    ndarray, shape (m, n)
    """
    theta = np.asarray(theta, float)
    cols = []
    for i in range(theta.size):
        d = np.zeros_like(theta)
        d[i] = eps
        cols.append((np.ravel(f(theta + d)) - np.ravel(f(theta - d))) / (2 * eps))
    return np.stack(cols, axis=-1)


def _inverse_square_singular(J: Array) -> tuple[Array, Array, Array]:
    r"""The thin SVD :math:`J = U\Sigma V^T` of ``J`` (..., m, n), with
    :math:`\Sigma^{-2}` (:math:`1/\sigma^2`, 0 where :math:`\sigma = 0`)."""
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    inv2 = np.where(s > 0, 1.0 / np.where(s > 0, s, 1.0) ** 2, 0.0)
    return U, inv2, Vt


def pinv_wide(J: ArrayLike) -> Array:
    r""":math:`J^+ = J^T(JJ^T)^{-1}` for full-row-rank ``J`` (..., m, n), m <= n: the smallest
    step reaching a reachable error.

    :math:`(JJ^T)^{-1} = U\Sigma^{-2}U^T` is taken from the SVD of ``J`` (never forming and
    inverting :math:`JJ^T`, whose condition number is the square of ``J``'s), so
    :math:`J^+ = V\Sigma U^T U\Sigma^{-2}U^T = V\Sigma^{-1}U^T`."""
    J = np.asarray(J, float)
    U, inv2, _ = _inverse_square_singular(J)
    return np.swapaxes(J, -1, -2) @ ((U * inv2[..., None, :]) @ np.swapaxes(U, -1, -2))


def pinv_tall(J: ArrayLike) -> Array:
    r""":math:`J^+ = (J^TJ)^{-1}J^T` for full-column-rank ``J`` (..., m, n), m >= n: the least
    squares step.

    :math:`(J^TJ)^{-1} = V\Sigma^{-2}V^T` is taken from the SVD of ``J``, so
    :math:`J^+ = V\Sigma^{-2}V^T V\Sigma U^T = V\Sigma^{-1}U^T`."""
    J = np.asarray(J, float)
    _, inv2, Vt = _inverse_square_singular(J)
    V = np.swapaxes(Vt, -1, -2)
    out: Array = ((V * inv2[..., None, :]) @ Vt) @ np.swapaxes(J, -1, -2)
    return out


def pinv_svd(J: ArrayLike, rcond: float = 1e-6) -> Array:
    r""":math:`J^+ = V\Sigma^+U^T`, with :math:`1/\sigma_i` replaced by 0 where
    :math:`\sigma_i < \text{rcond}\,\sigma_{max}`. Works for any shape and rank."""
    U, s, Vt = np.linalg.svd(np.asarray(J, float), full_matrices=False)
    cut = s > rcond * s[..., :1]
    inv = np.where(cut, 1.0 / np.where(cut, s, 1.0), 0.0)
    out: Array = np.swapaxes(Vt, -1, -2) @ (inv[..., :, None] * np.swapaxes(U, -1, -2))
    return out


def transpose_step(J: ArrayLike, e: ArrayLike) -> Array:
    r"""Jacobian-transpose increment :math:`\alpha J^T e` with Buss's
    :math:`\alpha = \langle e, JJ^Te\rangle / \lVert JJ^Te\rVert^2` (the exact line-search step
    of the linearised error). ``J`` (..., m, n), ``e`` (..., m) -> (..., n)."""
    J, e = np.asarray(J, float), np.asarray(e, float)
    g = (np.swapaxes(J, -1, -2) @ e[..., None])[..., 0]
    Jg = (J @ g[..., None])[..., 0]
    den = np.einsum("...i,...i->...", Jg, Jg)
    alpha = np.einsum("...i,...i->...", e, Jg) / np.where(den > 0, den, 1.0)
    out: Array = alpha[..., None] * g
    return out


def pinv_step(J: ArrayLike, e: ArrayLike, rcond: float = 1e-6) -> Array:
    r"""Least-squares increment :math:`J^+ e` (:func:`pinv_svd`).

    ``J`` (..., m, n), ``e`` (..., m) -> (..., n)."""
    out: Array = (pinv_svd(J, rcond) @ np.asarray(e, float)[..., None])[..., 0]
    return out


def dls_step(
    J: ArrayLike, e: ArrayLike, damping: float | ArrayLike, weights: ArrayLike | None = None
) -> Array:
    r"""Damped least-squares increment
    :math:`\Delta\theta = W^{-2}J^T(JW^{-2}J^T + \lambda^2 I)^{-1}e`.

    Parameters
    ----------
    J : array_like, shape (..., m, n)
    e : array_like, shape (..., m)
    damping : float or array_like, shape (...)
        :math:`\lambda` (not squared).
    weights : array_like, shape (n,), optional
        :math:`W`; a joint with weight 2 is penalised 4 times as much for moving.

    Returns
    -------
    ndarray, shape (..., n)
    """
    J, e = np.asarray(J, float), np.asarray(e, float)
    Dinv = 1.0 if weights is None else 1.0 / np.asarray(weights, float) ** 2
    JD = J * Dinv
    m = J.shape[-1 - 1]
    lam2 = np.asarray(damping, float)[..., None, None] ** 2
    A = JD @ np.swapaxes(J, -1, -2) + lam2 * np.eye(m)
    y = np.linalg.solve(A, e[..., None])
    return (np.swapaxes(JD, -1, -2) @ y)[..., 0]


def lost_rank(J: Array, rcond: float = 1e-6) -> NDArray[np.bool_]:
    r"""Whether each Jacobian ``J`` (..., m, n) has lost rank: its
    :math:`\min(m, n)`-th singular value is at most ``rcond`` times the largest. There the
    error components along the lost directions cannot be reduced by any small step."""
    rank = min(J.shape[-2:])
    if rank == 0:
        return np.zeros(J.shape[:-2], dtype=bool)
    s = np.linalg.svd(J, compute_uv=False)
    return s[..., rank - 1] <= rcond * s[..., 0]
