r"""Euler angles in all 24 conventions (the order strings of ``scipy.spatial.transform``).

An order is three axis letters, no axis twice in a row: the six Tait-Bryan orders
``XYZ XZY YXZ YZX ZXY ZYX`` and the six proper Euler orders ``XYX XZX YXY YZY ZXZ ZYZ``.

* Uppercase is **intrinsic** (each turn about the *moving* axes). ``"XYZ"`` with angles
  :math:`(a, b, c)` is :math:`R = R_X(a)\,R_Y(b)\,R_Z(c)`.
* Lowercase is **extrinsic** (each turn about the *fixed* axes). ``"xyz"`` with angles
  :math:`(a, b, c)` is :math:`R = R_z(c)\,R_y(b)\,R_x(a)`: x first, then y, then z.

So intrinsic ``"XYZ"`` with :math:`(a, b, c)` equals extrinsic ``"zyx"`` with
:math:`(c, b, a)`. The elementary rotations are the active right-handed ones, e.g.
:math:`R_Z(\gamma) = \begin{pmatrix}\cos\gamma & -\sin\gamma & 0\\ \sin\gamma & \cos\gamma & 0
\\ 0 & 0 & 1\end{pmatrix}`. A BVH channel order ``Zrotation Yrotation Xrotation`` is
``"ZYX"``.

Angles returned by the ``euler_from_*`` functions lie in :math:`[-\pi, \pi)` for the first and
third angle, and in :math:`[-\pi/2, \pi/2]` (Tait-Bryan) or :math:`[0, \pi]` (proper Euler)
for the middle one.

**Gimbal lock.** When the middle angle is :math:`\pm\pi/2` (Tait-Bryan) or :math:`0, \pi`
(proper Euler), the first and third axes line up and only the sum or difference of the
first and third angles is determined. Within :data:`GIMBAL_LOCK_TOL` (:math:`10^{-12}` rad) of
lock, ``euler_from_*`` sets the **third** angle ``angles[..., 2]`` to 0 and puts the whole turn
into the first (the choice scipy makes), and reports it when asked
(``return_gimbal_lock=True``); no warning is emitted. The tolerance is far above the
rounding noise of a rotation built exactly at lock (below :math:`10^{-15}` rad), and so small
that the returned angles still reproduce the rotation to about :math:`2\cdot 10^{-12}`.
Farther from lock, even :math:`10^{-9}` rad away, the angles are exact: they come from the
quaternion by the method of Bernardes & Viollet (2022), which never divides by a small
cosine. :func:`gimbal_lock_distance` tells how close given angles are to lock, and
:func:`is_gimbal_lock` whether they are within a tolerance of it: by default the same
:data:`GIMBAL_LOCK_TOL`, so it agrees with ``return_gimbal_lock``; a warning next to a slider
passes its own, e.g. a few degrees.

Angles are in radians unless ``degrees=True``. All functions broadcast over leading
dimensions.
"""

from __future__ import annotations

from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array, BoolArray
from .._validate import as_array, as_radians
from . import _kernels
from .quaternion import quat_from_matrix, quat_normalize

TAIT_BRYAN_ORDERS = ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX")
PROPER_EULER_ORDERS = ("XYX", "XZX", "YXY", "YZY", "ZXZ", "ZYZ")
#: All 24 conventions: 12 intrinsic (uppercase) then the same 12 extrinsic (lowercase).
EULER_ORDERS = tuple(o for case in (str.upper, str.lower)
                     for o in map(case, TAIT_BRYAN_ORDERS + PROPER_EULER_ORDERS))

#: Radians. A middle angle this close to lock counts as gimbal lock, in ``euler_from_*``
#: (third angle set to 0) and by default in :func:`is_gimbal_lock`. Treating a rotation that
#: is d from lock as locked moves it by at most 2d, so this stays tiny; a rotation built
#: exactly at lock comes back within ~1e-15 of it, far inside.
GIMBAL_LOCK_TOL = 1e-12


def _parse_order(order: object) -> tuple[tuple[int, int, int], bool]:
    """Axis indices (x=0, y=1, z=2) in the order of ``order``, and whether it is intrinsic."""
    if not isinstance(order, str):
        raise ValueError(f"order: expected a string such as 'XYZ' or 'xyz', got "
                         f"{type(order).__name__}")
    why = None
    if len(order) != 3:
        why = f"has {len(order)} characters, an Euler order has 3"
    elif set(order.lower()) - set("xyz"):
        why = "uses a letter other than x, y and z"
    elif not (order.isupper() or order.islower()):
        why = ("mixes upper and lower case; use uppercase for intrinsic (moving axes) or "
               "lowercase for extrinsic (fixed axes)")
    elif order[0].lower() == order[1].lower() or order[1].lower() == order[2].lower():
        why = "turns about the same axis twice in a row, which is a single turn"
    if why:
        raise ValueError(f"order: {order!r} {why}; valid orders are {', '.join(EULER_ORDERS)}")
    i, j, k = ("xyz".index(c) for c in order.lower())
    return (i, j, k), order.isupper()


def _checked(angles: ArrayLike, order: str, degrees: bool
             ) -> tuple[tuple[int, int, int], bool, Array]:
    """The axes of ``order``, whether it is intrinsic, and ``angles`` (..., 3) in radians (a
    bad order is reported before bad angles)."""
    axes, intrinsic = _parse_order(order)
    return axes, intrinsic, as_radians(as_array(angles, "angles", (3,)), degrees)


def _axis_matrix(axis: int, angle: Array) -> Array:
    """Elementary rotation by ``angle`` (shape (...)) about coordinate axis ``axis``."""
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros(angle.shape + (3, 3))
    b, d = (axis + 1) % 3, (axis + 2) % 3
    R[..., axis, axis] = 1.0
    R[..., b, b] = c
    R[..., d, d] = c
    R[..., b, d] = -s
    R[..., d, b] = s
    return R


def _axis_quat(axis: int, angle: Array) -> Array:
    q = np.zeros(angle.shape + (4,))
    q[..., 0] = np.cos(angle / 2)
    q[..., 1 + axis] = np.sin(angle / 2)
    return q


def matrix_from_euler(angles: ArrayLike, order: str, degrees: bool = False) -> Array:
    r"""Rotation matrices of Euler angles.

    Intrinsic ``"XYZ"``: :math:`R = R_X(a)\,R_Y(b)\,R_Z(c)`; extrinsic ``"xyz"``:
    :math:`R = R_z(c)\,R_y(b)\,R_x(a)`, for ``angles = (a, b, c)``; likewise for every order.

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        The three angles, in the order of the letters of ``order``.
    order : str
        One of :data:`EULER_ORDERS`.
    degrees : bool
        ``angles`` are in degrees.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Raises
    ------
    ValueError
        If ``order`` is not one of the 24 orders, or ``angles`` has a bad shape or values.
    """
    axes, intrinsic, a = _checked(angles, order, degrees)
    m = [_axis_matrix(axis, a[..., n]) for n, axis in enumerate(axes)]
    return m[0] @ m[1] @ m[2] if intrinsic else m[2] @ m[1] @ m[0]


def quat_from_euler(angles: ArrayLike, order: str, degrees: bool = False) -> Array:
    r"""Unit quaternions of Euler angles, in the canonical sign (``w >= 0``).

    The product of the elementary quaternions
    :math:`q_X(a) = (\cos\frac a2, \sin\frac a2, 0, 0)` etc., in the order of
    :func:`matrix_from_euler`: intrinsic ``"XYZ"`` is :math:`q_X(a)\,q_Y(b)\,q_Z(c)`.

    Parameters
    ----------
    angles : array_like, shape (..., 3)
    order : str
        One of :data:`EULER_ORDERS`.
    degrees : bool
        ``angles`` are in degrees.

    Returns
    -------
    ndarray, shape (..., 4)
    """
    axes, intrinsic, a = _checked(angles, order, degrees)
    qs = [_axis_quat(axis, a[..., n]) for n, axis in enumerate(axes)]
    mul = _kernels.quat_mul
    q = mul(mul(qs[0], qs[1]), qs[2]) if intrinsic else mul(mul(qs[2], qs[1]), qs[0])
    return _kernels.quat_canonical(q)


@overload
def euler_from_quat(
    q: ArrayLike, order: str, degrees: bool = ..., return_gimbal_lock: Literal[False] = ...
) -> Array: ...


@overload
def euler_from_quat(
    q: ArrayLike, order: str, degrees: bool, return_gimbal_lock: Literal[True]
) -> tuple[Array, BoolArray]: ...


@overload
def euler_from_quat(
    q: ArrayLike, order: str, degrees: bool = ..., *, return_gimbal_lock: Literal[True]
) -> tuple[Array, BoolArray]: ...


@overload
def euler_from_quat(
    q: ArrayLike, order: str, degrees: bool = ..., return_gimbal_lock: bool = ...
) -> Array | tuple[Array, BoolArray]: ...


def euler_from_quat(
    q: ArrayLike, order: str, degrees: bool = False, return_gimbal_lock: bool = False
) -> Array | tuple[Array, BoolArray]:
    r"""Euler angles of quaternions (``q`` and ``-q`` give the same angles).

    Bernardes & Viollet (2022): for the equivalent extrinsic sequence of axes
    :math:`(i, j, k)`, form :math:`(a, b, c, d)` from the components of :math:`q`; then the
    middle angle is :math:`2\,\mathrm{atan2}(\sqrt{c^2+d^2}, \sqrt{a^2+b^2})` and the outer
    ones are :math:`\theta_+ \mp \theta_-` with :math:`\theta_+ = \mathrm{atan2}(b, a)`,
    :math:`\theta_- = \mathrm{atan2}(d, c)` (Tait-Bryan orders are first turned into a proper
    sequence; see the paper). No ``arcsin`` and no division, so it is accurate everywhere.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Quaternions (normalised here).
    order : str
        One of :data:`EULER_ORDERS`.
    degrees : bool
        Return degrees.
    return_gimbal_lock : bool
        Also return where the rotation is at gimbal lock.

    Returns
    -------
    angles : ndarray, shape (..., 3)
        First and third angle in :math:`[-\pi, \pi)`, middle in :math:`[-\pi/2, \pi/2]`
        (Tait-Bryan) or :math:`[0, \pi]` (proper Euler). At gimbal lock the third angle is 0.
    locked : ndarray of bool, shape (...)
        Only with ``return_gimbal_lock=True``: where the middle angle was within
        :data:`GIMBAL_LOCK_TOL` of lock and the third angle was therefore set to 0 (the same
        test as ``is_gimbal_lock(angles, order)``).

    Raises
    ------
    ValueError
        If ``order`` is not one of the 24 orders, or ``q`` is zero or has a bad shape/values.
    """
    axes, intrinsic = _parse_order(order)
    q = _kernels.quat_canonical(quat_normalize(q))
    angles, locked = _euler_from_unit_quat(q, axes, intrinsic)
    if degrees:
        angles = np.degrees(angles)
    return (angles, locked) if return_gimbal_lock else angles


def _euler_from_unit_quat(
    q: Array, axes: tuple[int, int, int], intrinsic: bool
) -> tuple[Array, BoolArray]:
    # Work with the extrinsic sequence: intrinsic "IJK" (a, b, c) is extrinsic "kji" (c, b, a).
    i, j, k = axes[::-1] if intrinsic else axes
    proper = i == k
    if proper:
        k = 3 - i - j
    sign = (i - j) * (j - k) * (k - i) // 2  # Levi-Civita symbol of (i, j, k)
    w, qi, qj, qk = q[..., 0], q[..., 1 + i], q[..., 1 + j], q[..., 1 + k] * sign
    if proper:
        a, b, c, d = w, qi, qj, qk
    else:
        a, b, c, d = w - qj, qi + qk, qj + w, qk - qi
    middle = 2.0 * np.arctan2(np.hypot(c, d), np.hypot(a, b))
    half_sum, half_diff = np.arctan2(b, a), np.arctan2(d, c)
    first, third = half_sum - half_diff, half_sum + half_diff
    at_zero, at_pi = middle <= GIMBAL_LOCK_TOL, middle >= np.pi - GIMBAL_LOCK_TOL
    locked = at_zero | at_pi
    # At lock only first + third (middle 0) or third - first (middle pi) is defined; zero the
    # angle that is returned last: the extrinsic third, or for intrinsic orders the first.
    if intrinsic:
        first = np.where(locked, 0.0, first)
        third = np.where(at_zero, 2 * half_sum, np.where(at_pi, 2 * half_diff, third))
    else:
        third = np.where(locked, 0.0, third)
        first = np.where(at_zero, 2 * half_sum, np.where(at_pi, -2 * half_diff, first))
    if not proper:
        third = sign * third
        middle = middle - np.pi / 2
    angles = np.stack([_wrap(first), middle, _wrap(third)], axis=-1)
    return (angles[..., ::-1] if intrinsic else angles), locked


def _wrap(angle: Array) -> Array:
    """Angles mapped to [-pi, pi)."""
    wrapped = (angle + np.pi) % (2 * np.pi) - np.pi
    # Just below -pi, the modulo rounds up to 2 pi and the result to +pi: the same angle.
    return np.where(wrapped >= np.pi, -np.pi, wrapped)


def euler_from_matrix(
    R: ArrayLike, order: str, degrees: bool = False, return_gimbal_lock: bool = False
) -> Array | tuple[Array, BoolArray]:
    """Euler angles of rotation matrices (through the quaternion; see :func:`euler_from_quat`).

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices.
    order : str
        One of :data:`EULER_ORDERS`.
    degrees : bool
        Return degrees.
    return_gimbal_lock : bool
        Also return the boolean mask (shape (...)) of rotations at gimbal lock, where the
        third angle was set to 0.

    Returns
    -------
    angles : ndarray, shape (..., 3)
        ``matrix_from_euler(angles, order)`` reproduces ``R`` (to ~1e-15; within
        :data:`GIMBAL_LOCK_TOL` of lock, to ~2e-12).
    locked : ndarray of bool, shape (...)
        Only with ``return_gimbal_lock=True``.

    Raises
    ------
    ValueError
        If ``order`` is not one of the 24 orders, or ``R`` is not a stack of rotation matrices.
    """
    _parse_order(order)  # a bad order is reported before a bad matrix
    return euler_from_quat(quat_from_matrix(R), order, degrees, return_gimbal_lock)


def gimbal_lock_distance(angles: ArrayLike, order: str, degrees: bool = False) -> Array:
    r"""How far Euler angles are from gimbal lock: the middle angle's distance to the nearest
    lock value, :math:`\pm\pi/2` (Tait-Bryan) or :math:`0, \pi` (proper Euler), modulo
    :math:`2\pi`.

    Parameters
    ----------
    angles : array_like, shape (..., 3)
    order : str
        One of :data:`EULER_ORDERS`.
    degrees : bool
        ``angles`` are in degrees, and so is the result.

    Returns
    -------
    ndarray, shape (...)
        In :math:`[0, \pi/2]` (or ``[0, 90]`` degrees).
    """
    axes, _, a = _checked(angles, order, degrees)
    middle = a[..., 1]
    proper = axes[0] == axes[2]
    # arcsin|sin b| is the distance of b to the nearest multiple of pi; |cos b| shifts by pi/2.
    dist = np.arcsin(np.minimum(np.abs(np.sin(middle) if proper else np.cos(middle)), 1.0))
    return np.degrees(dist) if degrees else dist


def is_gimbal_lock(
    angles: ArrayLike, order: str, degrees: bool = False, tol: float | None = None
) -> BoolArray:
    """Whether Euler angles are within ``tol`` of gimbal lock (see :func:`gimbal_lock_distance`).

    Parameters
    ----------
    angles : array_like, shape (..., 3)
    order : str
        One of :data:`EULER_ORDERS`.
    degrees : bool
        ``angles`` (and ``tol``) are in degrees.
    tol : float, optional
        In the unit of ``angles``; default :data:`GIMBAL_LOCK_TOL` (its equivalent in degrees),
        the tolerance at which ``euler_from_*`` treats a rotation as locked. A slider warning
        might use a few degrees, e.g. ``is_gimbal_lock(a, "ZYX", True, tol=5)``.

    Returns
    -------
    ndarray of bool, shape (...)
    """
    if tol is None:
        tol = np.degrees(GIMBAL_LOCK_TOL) if degrees else GIMBAL_LOCK_TOL
    elif np.any(as_array(tol, "tol") < 0):
        raise ValueError(f"tol: must be a finite number >= 0, got {tol!r}")
    return gimbal_lock_distance(angles, order, degrees) <= tol
