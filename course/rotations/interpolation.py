r"""Interpolating between rotations: LERP, NLERP, SLERP.

For unit quaternions :math:`q_0, q_1` at the angle :math:`\Omega` apart on the unit sphere
(:math:`\cos\Omega = q_0\cdot q_1`; the rotations then differ by :math:`2\Omega`):

* LERP :math:`(1-t)\,q_0 + t\,q_1` is not a unit quaternion between the ends;
* NLERP normalises LERP. It follows the same arc as SLERP but not at constant speed: it
  turns faster in the middle than at the ends (:math:`1/\cos^2\frac\Omega2` times);
* SLERP :math:`\frac{\sin((1-t)\Omega)}{\sin\Omega}q_0 + \frac{\sin(t\Omega)}{\sin\Omega}q_1`
  is the only one of the three with **constant angular speed**: equal steps in :math:`t`
  turn by equal angles, :math:`2t\Omega` after time :math:`t`.

Because :math:`q` and :math:`-q` are the same rotation, NLERP and SLERP take the **shortest
path**: when :math:`q_0\cdot q_1 < 0` they use :math:`-q_1`, so the turn is at most
:math:`\pi`. Both accept scalar or array ``t``, which broadcasts against the leading
dimensions of the quaternions (``q0, q1`` of shape (4,) and ``t`` of shape (N,) give (N, 4)).
``t`` outside :math:`[0, 1]` extrapolates.
"""

from __future__ import annotations

from typing import overload

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .._validate import ZERO_QUAT, as_array, as_unit, broadcast_leading


def lerp(x0: ArrayLike, x1: ArrayLike, t: ArrayLike) -> Array:
    r"""Linear interpolation :math:`(1-t)\,x_0 + t\,x_1` of vectors of any length.

    For positions this is the right blend; for quaternions it leaves the unit sphere (use
    :func:`nlerp` or :func:`slerp`) and does not pick the shortest path.

    Parameters
    ----------
    x0, x1 : array_like, shape (..., n)
        End points, equal trailing size ``n``; leading dimensions broadcast.
    t : array_like, shape (...)
        Interpolation parameters (0 gives ``x0``, 1 gives ``x1`` exactly); broadcasts against
        the leading dimensions of ``x0`` and ``x1``.

    Returns
    -------
    ndarray, shape (..., n)

    Raises
    ------
    ValueError
        If an argument has a bad shape or non-finite values, or the leading dimensions of
        ``x0``, ``x1`` and ``t`` do not broadcast.
    """
    x0 = as_array(x0, "x0")
    if x0.ndim == 0:
        raise ValueError("x0: expected shape (..., n), got a scalar")
    x1 = as_array(x1, "x1", x0.shape[-1:])
    t = as_array(t, "t")
    broadcast_leading("lerp", ("x0", x0, 1), ("x1", x1, 1), ("t", t, 0))
    t = t[..., None]
    return (1 - t) * x0 + t * x1


@overload
def _shortest_pair(
    where: str, q0: ArrayLike, q1: ArrayLike, t: ArrayLike
) -> tuple[Array, Array, Array]: ...
@overload
def _shortest_pair(
    where: str, q0: ArrayLike, q1: ArrayLike, t: None = None
) -> tuple[Array, Array, None]: ...
def _shortest_pair(
    where: str, q0: ArrayLike, q1: ArrayLike, t: ArrayLike | None = None
) -> tuple[Array, Array, Array | None]:
    """Unit ``q0``, ``q1`` with ``q1`` negated where ``q0 . q1 < 0`` (shortest path), and ``t``
    (with a trailing axis of 1), all checked to broadcast; errors name ``where``."""
    q0 = as_unit(q0, "q0", 4, ZERO_QUAT)
    q1 = as_unit(q1, "q1", 4, ZERO_QUAT)
    args = [("q0", q0, 1), ("q1", q1, 1)]
    if t is not None:
        t = as_array(t, "t")
        args.append(("t", t, 0))
        t = t[..., None]
    broadcast_leading(where, *args)
    flip = np.sum(q0 * q1, axis=-1, keepdims=True) < 0
    return q0, np.where(flip, -q1, q1), t


def _half_sphere_angle(q0: Array, q1: Array) -> Array:
    # Omega = 2 atan2(|q0 - q1|, |q0 + q1|): accurate for all angles, unlike arccos(q0 . q1).
    omega: Array = 2.0 * np.arctan2(
        np.linalg.norm(q0 - q1, axis=-1), np.linalg.norm(q0 + q1, axis=-1)
    )
    return omega


def _sinc(x: Array) -> Array:
    """sin(x) / x, 1 at x = 0 (numpy's sinc is sin(pi x) / (pi x))."""
    y: Array = np.sinc(x / np.pi)
    return y


def nlerp(q0: ArrayLike, q1: ArrayLike, t: ArrayLike) -> Array:
    r"""Normalised linear interpolation of rotations, along the shortest path.

    .. math::
        \mathrm{nlerp}(q_0, q_1, t) = \frac{(1-t)\,q_0 + t\,q_1}{\lVert(1-t)\,q_0 + t\,q_1\rVert}

    with :math:`q_1 \to -q_1` when :math:`q_0\cdot q_1 < 0`. Cheap and smooth, but **not**
    constant angular speed (see :func:`slerp`).

    Parameters
    ----------
    q0, q1 : array_like, shape (..., 4)
        Quaternions (normalised here); leading dimensions broadcast.
    t : array_like, shape (...)
        Broadcasts against the leading dimensions of ``q0`` and ``q1``.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions; ``q0`` at ``t = 0`` and ``q1`` (possibly as ``-q1``) at ``t = 1``.

    Raises
    ------
    ValueError
        If ``q0`` or ``q1`` is the zero quaternion, any argument has a bad shape or values,
        or the leading dimensions of ``q0``, ``q1`` and ``t`` do not broadcast.
    """
    q0, q1, t = _shortest_pair("nlerp", q0, q1, t)
    q = (1 - t) * q0 + t * q1
    # With q0 . q1 >= 0 the blend never passes through 0 (its norm is >= 1/sqrt(2) on [0, 1]).
    blend: Array = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return blend


def slerp(q0: ArrayLike, q1: ArrayLike, t: ArrayLike) -> Array:
    r"""Spherical linear interpolation of rotations, along the shortest path.

    .. math::
        \mathrm{slerp}(q_0, q_1, t) = \frac{\sin((1-t)\Omega)}{\sin\Omega}\,q_0
        + \frac{\sin(t\Omega)}{\sin\Omega}\,q_1, \qquad \cos\Omega = q_0\cdot q_1,

    with :math:`q_1 \to -q_1` when :math:`q_0\cdot q_1 < 0`. The rotation turns at
    **constant angular speed**: after :math:`t` it has turned by :math:`2t\Omega` about a
    fixed axis, the only one of LERP / NLERP / SLERP to do so.

    The weights are evaluated as :math:`(1-t)\,\mathrm{sinc}((1-t)\Omega)/\mathrm{sinc}\,\Omega`
    and :math:`t\,\mathrm{sinc}(t\Omega)/\mathrm{sinc}\,\Omega`
    (:math:`\mathrm{sinc}\,x = \sin x / x`), so there is no division by
    :math:`\sin\Omega \approx 0` when :math:`q_0 \approx q_1`: the weights tend smoothly to
    the NLERP weights :math:`1-t, t`, and ``q0 == q1`` returns ``q0`` (to rounding).

    Parameters
    ----------
    q0, q1 : array_like, shape (..., 4)
        Quaternions (normalised here); leading dimensions broadcast.
    t : array_like, shape (...)
        Broadcasts against the leading dimensions of ``q0`` and ``q1``; values outside
        ``[0, 1]`` continue the turn at the same speed.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions.

    Raises
    ------
    ValueError
        If ``q0`` or ``q1`` is the zero quaternion, any argument has a bad shape or values,
        or the leading dimensions of ``q0``, ``q1`` and ``t`` do not broadcast.
    """
    q0, q1, t = _shortest_pair("slerp", q0, q1, t)
    omega = _half_sphere_angle(q0, q1)[..., None]  # in [0, pi/2] after the flip
    q = ((1 - t) * _sinc((1 - t) * omega) * q0 + t * _sinc(t * omega) * q1) / _sinc(omega)
    turn: Array = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return turn


def quat_angle(q0: ArrayLike, q1: ArrayLike) -> Array:
    r"""The angle of the rotation between ``q0`` and ``q1`` (of :math:`q_0^{-1} q_1`).

    It is :math:`2\Omega` for the shortest-path :math:`\Omega` of :func:`slerp`, in
    :math:`[0, \pi]`; ``q`` and ``-q`` are at angle 0. A metric on rotations, handy to compare
    orientations with a tolerance in radians.

    Parameters
    ----------
    q0, q1 : array_like, shape (..., 4)
        Quaternions (normalised here); leading dimensions broadcast.

    Returns
    -------
    ndarray, shape (...)
    """
    q0, q1, _ = _shortest_pair("quat_angle", q0, q1)
    return 2.0 * _half_sphere_angle(q0, q1)
