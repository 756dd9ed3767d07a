r"""Rotations built from vectors: the cross-product matrix and the shortest arc from u to v.

All functions broadcast over leading dimensions.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .._validate import as_array, as_unit, broadcast_leading
from . import _kernels

# Below this |u + v| (unit u, v) the two directions count as antiparallel: the shortest arc
# is then any half turn about an axis perpendicular to u, and we pick one deterministically.
# The half turn maps u to -u, which is within this distance of v.
_ANTIPARALLEL_EPS = 1e-12


def skew(v: ArrayLike) -> Array:
    r"""Cross-product matrix :math:`[v]_\times`, so that :math:`[v]_\times w = v \times w`.

    .. math::
        [v]_\times = \begin{pmatrix} 0 & -v_z & v_y \\ v_z & 0 & -v_x \\ -v_y & v_x & 0
        \end{pmatrix}

    It is skew-symmetric, :math:`[v]_\times^T = -[v]_\times`; Rodrigues' formula
    (:func:`~course.rotations.matrix_from_axis_angle`) is written with it.

    Parameters
    ----------
    v : array_like, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    return _kernels.skew(as_array(v, "v", (3,)))


def quat_between(u: ArrayLike, v: ArrayLike) -> Array:
    r"""The shortest-arc rotation that turns direction ``u`` onto direction ``v``.

    It turns by the angle :math:`\theta = \angle(u, v)` about the axis
    :math:`u \times v / \lVert u \times v\rVert`:

    .. math::
        q = (\cos\tfrac\theta2,\ \sin\tfrac\theta2\,\mathbf n)
          \propto (1 + \hat u\cdot\hat v,\ \hat u\times\hat v)
          = (\tfrac12\lVert s\rVert^2,\ \hat u\times s), \qquad s = \hat u + \hat v,

    for unit :math:`\hat u, \hat v`. The last form is used: :math:`s` is computed without
    cancellation, so nearly opposite directions stay accurate (:math:`1 + \hat u\cdot\hat v`
    would lose all digits there).

    * Parallel ``u``, ``v`` give the identity.
    * Antiparallel ``u``, ``v`` (:math:`\lVert\hat u + \hat v\rVert < 10^{-12}`) have no
      unique shortest arc; the result is then the half turn about
      :math:`\hat u \times e_k / \lVert\hat u \times e_k\rVert`, where :math:`e_k` is the
      coordinate axis along which :math:`\hat u` has its smallest component (the first such
      axis on a tie). The axis depends on ``u`` alone, so the same ``u`` always gives the same
      turn; for ``u`` along ``+x`` it is a half turn about ``+z``.

    Parameters
    ----------
    u, v : array_like, shape (..., 3)
        Directions (any non-zero length); leading dimensions broadcast.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions ``q`` with ``quat_rotate(q, u)`` parallel to ``v``.

    Raises
    ------
    ValueError
        If ``u`` or ``v`` has zero length (or wrong shape, NaN, ...), or their leading
        dimensions do not broadcast.
    """
    u = as_unit(u, "u", why="the rotation between two directions needs non-zero vectors")
    v = as_unit(v, "v", why="the rotation between two directions needs non-zero vectors")
    broadcast_leading("quat_between", ("u", u, 1), ("v", v, 1))
    u, v = np.broadcast_arrays(u, v)
    s = u + v
    n = np.linalg.norm(s, axis=-1, keepdims=True)
    opposite = n < _ANTIPARALLEL_EPS
    q = np.concatenate([0.5 * n**2, np.cross(u, s)], axis=-1)
    # Antiparallel: the half turn (0, axis) about an axis perpendicular to u.
    e = np.eye(3)[np.argmin(np.abs(u), axis=-1)]
    axis = np.cross(u, e)
    axis = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
    half_turn = np.concatenate([np.zeros_like(n), axis], axis=-1)
    q = np.where(opposite, half_turn, q)
    turn: Array = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return turn
