r"""Unit quaternions, scalar first.

:math:`q = (w, x, y, z) = (\cos\frac\theta2, \sin\frac\theta2\,u)` for a turn by θ about u.
A unit quaternion :math:`q` rotates a vector by :math:`v' = q\,v\,q^*` (active rotation,
Hamilton product). :math:`q` and :math:`-q` are the same rotation; :func:`quat_canonical`
picks the one with :math:`w \ge 0`. All functions broadcast over leading dimensions; shapes
that do not broadcast are a ``ValueError`` naming the arguments.

**Non-unit and zero quaternions.** :func:`quat_mul` and :func:`quat_conjugate` are the
quaternion algebra and accept any length, e.g. the pure quaternion :math:`(0, v)` of the
sandwich :math:`q\,(0, v)\,q^*`; the functions that read ``q`` as a rotation normalise it.
None of them accepts the **zero quaternion** (norm below :math:`10^{-12}`): it is no rotation,
has no inverse, and is nearly always an array that was never filled in, so it is a
``ValueError`` naming the argument and the index, not a silent zero. (To rotate vectors, the
zero vector included, use :func:`quat_rotate`.)
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .._validate import (
    ZERO_QUAT,
    as_array,
    as_quat,
    as_rotation_matrix,
    broadcast_leading,
    nonzero_norm,
    unit,
)
from . import _kernels


def quat_identity(shape: int | tuple[int, ...] = ()) -> Array:
    """Identity quaternions ``(1, 0, 0, 0)`` of shape ``shape + (4,)`` (an int n means (n,)).

    Raises
    ------
    ValueError
        If ``shape`` is not a non-negative int or a tuple of them.
    """
    shape = (shape,) if isinstance(shape, (int, np.integer)) else shape
    if not isinstance(shape, (tuple, list)) or not all(
        isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n >= 0 for n in shape
    ):
        raise ValueError(f"shape: expected a non-negative int or a tuple of them, got {shape!r}")
    q = np.zeros((*shape, 4))
    q[..., 0] = 1.0
    return q


def quat_mul(a: ArrayLike, b: ArrayLike) -> Array:
    r"""Hamilton product :math:`a\,b`: rotate by :math:`b` first, then by :math:`a`.

    .. math::
        a b = (w_a w_b - \mathbf v_a\cdot\mathbf v_b,\;
               w_a \mathbf v_b + w_b \mathbf v_a + \mathbf v_a \times \mathbf v_b)

    Parameters
    ----------
    a, b : array_like, shape (..., 4)
        Quaternions (w, x, y, z), unit or not (not normalised here); leading dimensions
        broadcast.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit if ``a`` and ``b`` are.

    Raises
    ------
    ValueError
        If ``a`` or ``b`` is the zero quaternion, has a bad shape or non-finite values, or
        their leading dimensions do not broadcast.
    """
    a = as_quat(a, "a")
    b = as_quat(b, "b")
    broadcast_leading("quat_mul", ("a", a, 1), ("b", b, 1))
    return _kernels.quat_mul(a, b)


def quat_conjugate(q: ArrayLike) -> Array:
    r"""Conjugate :math:`q^* = (w, -x, -y, -z)`; the inverse rotation of a unit quaternion.

    Raises
    ------
    ValueError
        If ``q`` is the zero quaternion, or has a bad shape or non-finite values.
    """
    conj: Array = as_quat(q, "q") * np.array([1.0, -1.0, -1.0, -1.0])
    return conj


def quat_inverse(q: ArrayLike) -> Array:
    r"""Inverse :math:`q^{-1} = q^* / \lVert q\rVert^2` (also for non-unit quaternions).

    Raises
    ------
    ValueError
        If ``q`` is the zero quaternion.
    """
    q = as_array(q, "q", (4,))
    n = nonzero_norm(q, "q", ZERO_QUAT)
    # (q / |q|)* / |q|: squaring |q| would overflow for |q| above ~1e154.
    inverse: Array = unit(q) * np.array([1.0, -1.0, -1.0, -1.0]) / n[..., None]
    return inverse


def quat_normalize(q: ArrayLike) -> Array:
    r"""Scale ``q`` to unit length, :math:`q / \lVert q\rVert`.

    Any non-zero finite ``q`` gives a unit quaternion: where squaring the components would
    overflow (above ~1e154) or underflow, they are divided by the largest one first.

    Raises
    ------
    ValueError
        If ``q`` is the zero quaternion, which is no rotation.
    """
    return unit(as_quat(q, "q"))


def quat_canonical(q: ArrayLike) -> Array:
    """The sign of ``q`` with ``w >= 0`` (ties broken by the first non-zero of x, y, z).

    ``q`` and ``-q`` are the same rotation; this picks one deterministically so that
    quaternions can be compared entry by entry. A component with magnitude below 1e-15 counts
    as zero, so for half turns (``w`` = 0 up to rounding) the first non-zero of x, y, z is
    made positive and the result is the same whichever sign the rounding gave ``w``. The
    length of ``q`` is kept.

    Raises
    ------
    ValueError
        If ``q`` is the zero quaternion (which has no sign to choose), or has a bad shape or
        non-finite values.
    """
    return _kernels.quat_canonical(as_quat(q, "q"))


def quat_rotate(q: ArrayLike, v: ArrayLike) -> Array:
    r"""Rotate vectors ``v`` by unit quaternions ``q``: :math:`v' = q\,v\,q^*`.

    ``q`` is normalised first (so it must not be zero). Computed as
    :math:`v' = v + 2w(\mathbf u\times v) + 2\,\mathbf u\times(\mathbf u\times v)` with
    :math:`\mathbf u = (x, y, z)`, which is the same for a unit ``q`` and cheaper.

    Parameters
    ----------
    q : array_like, shape (..., 4)
    v : array_like, shape (..., 3)
        Leading dimensions broadcast against those of ``q``.

    Returns
    -------
    ndarray, shape (..., 3)

    Raises
    ------
    ValueError
        If ``q`` is the zero quaternion, an argument has a bad shape or non-finite values, or
        the leading dimensions do not broadcast.
    """
    q = quat_normalize(q)
    v = as_array(v, "v", (3,))
    broadcast_leading("quat_rotate", ("q", q, 1), ("v", v, 1))
    return _kernels.quat_rotate(q, v)


def matrix_from_quat(q: ArrayLike) -> Array:
    r"""Rotation matrix of a unit quaternion.

    .. math::
        R = \begin{pmatrix}
        1-2(y^2+z^2) & 2(xy-wz) & 2(xz+wy)\\
        2(xy+wz) & 1-2(x^2+z^2) & 2(yz-wx)\\
        2(xz-wy) & 2(yz+wx) & 1-2(x^2+y^2)
        \end{pmatrix}

    ``q`` is normalised first, so a slightly non-unit quaternion still gives an orthogonal
    matrix.

    Parameters
    ----------
    q : array_like, shape (..., 4)

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    q = quat_normalize(q)
    w, x, y, z = np.moveaxis(q, -1, 0)
    R = np.empty(q.shape[:-1] + (3, 3))
    R[..., 0, 0] = 1 - 2 * (y * y + z * z)
    R[..., 0, 1] = 2 * (x * y - w * z)
    R[..., 0, 2] = 2 * (x * z + w * y)
    R[..., 1, 0] = 2 * (x * y + w * z)
    R[..., 1, 1] = 1 - 2 * (x * x + z * z)
    R[..., 1, 2] = 2 * (y * z - w * x)
    R[..., 2, 0] = 2 * (x * z - w * y)
    R[..., 2, 1] = 2 * (y * z + w * x)
    R[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return R


def quat_from_matrix(R: ArrayLike) -> Array:
    r"""Unit quaternion of a rotation matrix, in the canonical sign of :func:`quat_canonical`.

    Uses the numerically stable branch of Shepperd's method: of :math:`4w^2 = 1 + \mathrm{tr}R`
    and :math:`4x^2 = 1 + R_{00} - R_{11} - R_{22}` (and likewise y, z), the largest is solved
    first and the others follow from off-diagonal sums, so no division by a tiny number.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices (orthonormal, det +1).

    Returns
    -------
    ndarray, shape (..., 4)

    Raises
    ------
    ValueError
        If ``R`` is not a stack of rotation matrices (wrong shape, not orthonormal, or a
        reflection).
    """
    R = as_rotation_matrix(R, "R")
    m00, m11, m22 = R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]
    # Candidate 4*q_k^2 for k = w, x, y, z.
    d = np.stack(
        [1 + m00 + m11 + m22, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22],
        axis=-1,
    )
    r21, r12 = R[..., 2, 1], R[..., 1, 2]
    r02, r20 = R[..., 0, 2], R[..., 2, 0]
    r10, r01 = R[..., 1, 0], R[..., 0, 1]
    s21, s02, s10 = r21 - r12, r02 - r20, r10 - r01
    a21, a02, a10 = r21 + r12, r02 + r20, r10 + r01
    # Each row: the quaternion times 4*q_k when solving for component k.
    cands = np.stack(
        [
            np.stack([d[..., 0], s21, s02, s10], -1),
            np.stack([s21, d[..., 1], a10, a02], -1),
            np.stack([s02, a10, d[..., 2], a21], -1),
            np.stack([s10, a02, a21, d[..., 3]], -1),
        ],
        axis=-2,
    )
    k = np.argmax(d, axis=-1)
    q = np.take_along_axis(cands, k[..., None, None], axis=-2)[..., 0, :]
    return _kernels.quat_canonical(q / np.linalg.norm(q, axis=-1, keepdims=True))
