r"""Axis-angle and rotation vectors.

A rotation by the angle :math:`\theta` about the unit axis :math:`u` is, as a

* unit quaternion: :math:`q = (\cos\frac\theta2,\ \sin\frac\theta2\,u)`;
* rotation matrix (Rodrigues' formula, :math:`K = [u]_\times`):
  :math:`R = I + \sin\theta\,K + (1-\cos\theta)\,K^2`;
* rotation vector: :math:`\theta u` (direction = axis, length = angle).

Conversions *to* axis-angle return the angle in :math:`[0, \pi]`. The identity has no axis;
it is returned as angle 0 about :data:`DEFAULT_AXIS` (``+x``). A half turn has two
equivalent axes, :math:`u` and :math:`-u`; the one whose first non-zero component is
positive is returned (the sign rule of :func:`~course.rotations.quat_canonical`).

Angles are in radians unless ``degrees=True`` (a rotation vector then has its length in
degrees). All functions broadcast over leading dimensions.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .._validate import as_array, as_radians, as_unit, broadcast_leading, norm, unit
from . import _kernels
from .quaternion import quat_from_matrix, quat_normalize

DEFAULT_AXIS = np.array([1.0, 0.0, 0.0])
DEFAULT_AXIS.flags.writeable = False

_ZERO_AXIS = "a rotation axis needs a non-zero vector"


def _to_unit(angle: Array, degrees: bool) -> Array:
    return np.degrees(angle) if degrees else angle


def quat_from_axis_angle(axis: ArrayLike, angle: ArrayLike, degrees: bool = False) -> Array:
    r"""Unit quaternion :math:`q = (\cos\frac\theta2,\ \sin\frac\theta2\,u)`.

    Parameters
    ----------
    axis : array_like, shape (..., 3)
        Rotation axes; normalised here, so any non-zero length works.
    angle : array_like, shape (...)
        Angles :math:`\theta` (right-hand rule about ``axis``); broadcasts against the
        leading dimensions of ``axis``.
    degrees : bool
        ``angle`` is in degrees.

    Returns
    -------
    ndarray, shape (..., 4)

    Raises
    ------
    ValueError
        If ``axis`` has zero length, either argument has a bad shape or non-finite values, or
        their leading dimensions do not broadcast.
    """
    u, theta = _axis_and_angle("quat_from_axis_angle", axis, angle, degrees)
    theta = theta[..., None]
    v = np.sin(theta / 2) * u
    w = np.broadcast_to(np.cos(theta / 2), v.shape[:-1] + (1,))
    return np.concatenate([w, v], -1)


def axis_angle_from_quat(q: ArrayLike, degrees: bool = False) -> tuple[Array, Array]:
    r"""Axis and angle of a quaternion: :math:`\theta = 2\,\mathrm{atan2}(\lVert v\rVert, w)`,
    :math:`u = v / \lVert v\rVert` for :math:`q = (w, v)` with :math:`w \ge 0`.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Quaternions (normalised here; ``q`` and ``-q`` give the same result).
    degrees : bool
        Return the angle in degrees.

    Returns
    -------
    axis : ndarray, shape (..., 3)
        Unit axes; :data:`DEFAULT_AXIS` (``+x``) where the angle is 0.
    angle : ndarray, shape (...)
        Angles in :math:`[0, \pi]` (``[0, 180]`` with ``degrees=True``).

    Raises
    ------
    ValueError
        If ``q`` is the zero quaternion, has a bad shape or non-finite values.
    """
    q = _kernels.quat_canonical(quat_normalize(q))
    # _canonical may keep a tiny negative w (|w| < 1e-15); flip it so the angle stays <= pi.
    q = np.where(q[..., :1] < 0, -q, q)
    v = q[..., 1:]
    n = norm(v)  # scaled: |v| of a 1e-162 rad turn must not underflow
    angle = 2.0 * np.arctan2(n, q[..., 0])
    return _direction(v, n), _to_unit(angle, degrees)


def _direction(v: Array, length: Array) -> Array:
    """``v / length`` (computed without underflow), or :data:`DEFAULT_AXIS` where it is 0."""
    nonzero = (length > 0)[..., None]
    return np.where(nonzero, unit(np.where(nonzero, v, DEFAULT_AXIS)), DEFAULT_AXIS)


def matrix_from_axis_angle(axis: ArrayLike, angle: ArrayLike, degrees: bool = False) -> Array:
    r"""Rotation matrix by Rodrigues' formula.

    .. math::
        R = I + \sin\theta\,K + (1 - \cos\theta)\,K^2, \qquad K = [u]_\times

    (evaluated with :math:`1-\cos\theta = 2\sin^2\frac\theta2`, exact for tiny angles too).

    Parameters
    ----------
    axis : array_like, shape (..., 3)
        Rotation axes; normalised here, so any non-zero length works.
    angle : array_like, shape (...)
        Angles; broadcast against the leading dimensions of ``axis``.
    degrees : bool
        ``angle`` is in degrees.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Raises
    ------
    ValueError
        If ``axis`` has zero length, either argument has a bad shape or non-finite values, or
        their leading dimensions do not broadcast.
    """
    return _rodrigues(*_axis_and_angle("matrix_from_axis_angle", axis, angle, degrees))


def _axis_and_angle(
    where: str, axis: ArrayLike, angle: ArrayLike, degrees: bool
) -> tuple[Array, Array]:
    """Unit axes and angles in radians, checked to broadcast; errors name ``where``."""
    u = as_unit(axis, "axis", why=_ZERO_AXIS)
    theta = as_array(angle, "angle")
    broadcast_leading(where, ("axis", u, 1), ("angle", theta, 0))
    return u, as_radians(theta, degrees)


def _rodrigues(u: Array, theta: Array) -> Array:
    K = _kernels.skew(u)
    s = np.sin(theta)[..., None, None]
    c1 = (2.0 * np.sin(theta / 2) ** 2)[..., None, None]
    return np.eye(3) + s * K + c1 * (K @ K)


def axis_angle_from_matrix(R: ArrayLike, degrees: bool = False) -> tuple[Array, Array]:
    """Axis and angle of rotation matrices (through the quaternion, which is stable near π).

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices.
    degrees : bool
        Return the angle in degrees.

    Returns
    -------
    axis : ndarray, shape (..., 3)
        Unit axes; :data:`DEFAULT_AXIS` where the angle is 0.
    angle : ndarray, shape (...)
        Angles in :math:`[0, \\pi]`.

    Raises
    ------
    ValueError
        If ``R`` is not a stack of rotation matrices.
    """
    return axis_angle_from_quat(quat_from_matrix(R), degrees)


def _split_rotvec(rotvec: ArrayLike, degrees: bool) -> tuple[Array, Array]:
    """Axis (``DEFAULT_AXIS`` for the zero vector) and angle in radians of rotation vectors."""
    r = as_radians(as_array(rotvec, "rotvec", (3,)), degrees)
    theta = norm(r)
    if not np.all(np.isfinite(theta)):
        raise ValueError("rotvec: has a length beyond the largest float; no angle to turn by")
    return _direction(r, theta), theta


def quat_from_rotvec(rotvec: ArrayLike, degrees: bool = False) -> Array:
    r"""Unit quaternion of rotation vectors :math:`r = \theta u`:
    :math:`q = (\cos\frac\theta2,\ \sin\frac\theta2\,u)`.

    Parameters
    ----------
    rotvec : array_like, shape (..., 3)
        Rotation vectors; the zero vector is the identity.
    degrees : bool
        The length of ``rotvec`` is in degrees.

    Returns
    -------
    ndarray, shape (..., 4)
    """
    axis, theta = _split_rotvec(rotvec, degrees)
    return np.concatenate([np.cos(theta / 2)[..., None], np.sin(theta / 2)[..., None] * axis], -1)


def rotvec_from_quat(q: ArrayLike, degrees: bool = False) -> Array:
    r"""Rotation vectors :math:`\theta u` of quaternions, with :math:`\theta \in [0, \pi]`.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Quaternions (normalised here; ``q`` and ``-q`` give the same result).
    degrees : bool
        Return vectors whose length is in degrees.

    Returns
    -------
    ndarray, shape (..., 3)
    """
    axis, angle = axis_angle_from_quat(q, degrees)
    return axis * angle[..., None]


def matrix_from_rotvec(rotvec: ArrayLike, degrees: bool = False) -> Array:
    """Rotation matrices of rotation vectors (Rodrigues' formula, see
    :func:`matrix_from_axis_angle`).

    Parameters
    ----------
    rotvec : array_like, shape (..., 3)
    degrees : bool
        The length of ``rotvec`` is in degrees.

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    return _rodrigues(*_split_rotvec(rotvec, degrees))


def rotvec_from_matrix(R: ArrayLike, degrees: bool = False) -> Array:
    r"""Rotation vectors :math:`\theta u`, :math:`\theta \in [0, \pi]`, of rotation matrices.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
    degrees : bool
        Return vectors whose length is in degrees.

    Returns
    -------
    ndarray, shape (..., 3)
    """
    return rotvec_from_quat(quat_from_matrix(R), degrees)
