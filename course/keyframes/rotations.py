r"""Curves through rotation keys: SLERP per segment and its smooth spline form, SQUAD.

Rotation keys are unit quaternions :math:`q_0, \dots, q_{K-1}` (``q_keys`` of shape
(K, ..., 4), e.g. (K, J, 4) for every joint of a skeleton) at strictly increasing times; the
times ``t`` to evaluate at are checked as for positions (:mod:`.curves`: inside the key
range, refused outside).

Two rules from the rotations notebook come first. :math:`q` and :math:`-q` are the same
rotation (the double cover), so before interpolating, every key is flipped into the
hemisphere of its predecessor, :math:`q_i \cdot q_{i-1} \ge 0` (:func:`same_hemisphere`);
each step between neighbouring keys is then the **shortest** turn, at most 180°. Without it a
spline would swing the long way round between two keys that happen to be stored with
opposite signs.

* :func:`slerp_keys`: SLERP on each segment, constant angular velocity inside a segment but
  a jump in angular velocity at every key (C⁰, like linear interpolation of positions).
* :func:`squad`: Shoemake's spherical quadrangle,
  :math:`\mathrm{squad}(u) = \mathrm{slerp}(\mathrm{slerp}(q_i, q_{i+1}, u),
  \mathrm{slerp}(s_i, s_{i+1}, u), 2u(1-u))` with intermediate control quaternions
  :math:`s_i` from :func:`squad_controls`, chosen so that the angular velocity is continuous
  across keys (C¹), the rotation analogue of Catmull–Rom.

The logarithm of a unit quaternion :math:`q = (\cos\frac\theta2, \sin\frac\theta2\,u)` is the
pure quaternion :math:`\log q = \frac\theta2 u` and :math:`\exp` its inverse; here they are half
the rotation vector (:func:`course.rotations.rotvec_from_quat`). Evaluated at many times,
SLERP is written :math:`\mathrm{slerp}(q_a, q_b, u) = q_a \exp(u \log(q_a^{-1} q_b))`
(the same curve as :func:`course.rotations.slerp`): the logarithms are taken once per
segment, and per time only :func:`_exp` and a product remain, on arrays already checked.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import rotations as rot
from .._validate import as_quat
from ..rotations._kernels import quat_mul as _mul
from .curves import as_column, check_keys, check_t, segments

Array = NDArray[np.float64]
_CONJUGATE = np.array([1.0, -1.0, -1.0, -1.0])  # times a unit quaternion: its inverse


def _unit_keys(q_keys: ArrayLike, times: ArrayLike, name: str = "q_keys"
               ) -> tuple[Array, Array]:
    """Unit quaternion keys (K, ..., 4), in one hemisphere, and checked times (K,)."""
    q = as_quat(q_keys, name)
    q, times = check_keys(q, times, name)
    if q.ndim < 2:
        raise ValueError(f"{name}: expected shape (K, ..., 4), got {q.shape}")
    return same_hemisphere(q / np.linalg.norm(q, axis=-1, keepdims=True)), times


def same_hemisphere(q_keys: ArrayLike) -> Array:
    r"""The keys with signs chosen so that neighbours are in one hemisphere:
    :math:`q_i \cdot q_{i-1} \ge 0` for every :math:`i` (each key stays the same rotation).

    Every key after the first is negated when its dot product with the already-flipped key
    before it is negative; the product of those sign changes down the sequence is a
    cumulative product, so all channels are done at once.

    Parameters
    ----------
    q_keys : array_like, shape (K, ..., 4)

    Returns
    -------
    ndarray, shape (K, ..., 4)
    """
    q = as_quat(q_keys, "q_keys")
    if q.ndim < 2:
        raise ValueError(f"q_keys: expected shape (K, ..., 4), got {q.shape}")
    step = np.where(np.sum(q[1:] * q[:-1], axis=-1) < 0, -1.0, 1.0)
    sign = np.concatenate([np.ones((1,) + step.shape[1:]), np.cumprod(step, axis=0)])
    continuous: Array = q * sign[..., None]
    return continuous


def quat_log(q: ArrayLike) -> Array:
    r""":math:`\log q = \frac\theta2\,u` (a 3-vector) of unit quaternions (..., 4), with the
    angle :math:`\theta \in [0, \pi]` (``q`` and ``-q`` give the same)."""
    return 0.5 * rot.rotvec_from_quat(q)


def quat_exp(v: ArrayLike) -> Array:
    r""":math:`\exp v = (\cos\lVert v\rVert, \sin\lVert v\rVert\,v/\lVert v\rVert)` of
    3-vectors (..., 3): the inverse of :func:`quat_log`."""
    return rot.quat_from_rotvec(2.0 * np.asarray(v, dtype=np.float64))


def _exp(v: Array) -> Array:
    r""":math:`\exp v` of (..., 3) vectors, unchecked: :math:`(\cos\lVert v\rVert,
    \mathrm{sinc}\lVert v\rVert\, v)` (no division by a zero norm)."""
    n = np.sqrt(np.einsum("...i,...i->...", v, v))
    return np.concatenate([np.cos(n)[..., None], np.sinc(n / np.pi)[..., None] * v], axis=-1)


def _log(q: Array) -> Array:
    r""":math:`\log q` of unit quaternions (..., 4), unchecked and without choosing a sign:
    :math:`\operatorname{atan2}(\lVert v\rVert, w)\, v / \lVert v\rVert` for :math:`q = (w, v)`."""
    v = q[..., 1:]
    n = np.sqrt(np.einsum("...i,...i->...", v, v))
    angle = np.arctan2(n, q[..., 0])
    scale = np.divide(angle, n, out=np.ones_like(n), where=n > 1e-300)
    log: Array = scale[..., None] * v
    return log


def _segment_logs(q: Array) -> Array:
    r""":math:`\log(q_i^{-1} q_{i+1})` of neighbouring quaternions (K, ..., 4) -> (K-1, ..., 3),
    along the great arc between them **as stored** (no sign chosen, up to 180° on the sphere).

    For keys after :func:`same_hemisphere` that arc is the shortest turn anyway. SQUAD's
    controls must not be re-signed: :math:`s_i` and :math:`s_{i+1}` each sit within 45° of
    their own key, so with keys more than ~120° of rotation apart they can land in opposite
    hemispheres, and the shortest turn from :math:`s_i` would head for :math:`-s_{i+1}`, the
    other way round, and the curve would swing back and jump in angular velocity at the key.
    """
    return _log(_mul(q[:-1] * _CONJUGATE, q[1:]))


def _slerp_segments(q: Array, i: NDArray[np.intp], u: Array) -> Array:
    r""":math:`\mathrm{slerp}(q_i, q_{i+1}, u) = q_i \exp(u \log(q_i^{-1} q_{i+1}))` on the
    keys ``q`` (K, ..., 4): segments ``i`` and their parameters ``u`` from :func:`segments`,
    ``u`` made a column (:func:`as_column`) against the keys' trailing axes."""
    return _mul(q[i], _exp(u * _segment_logs(q)[i]))


def slerp_keys(q_keys: ArrayLike, times: ArrayLike, t: ArrayLike) -> Array:
    r"""SLERP between neighbouring rotation keys (shortest path).

    .. math::
        q(t) = \mathrm{slerp}(q_i, q_{i+1}, u) = q_i \exp\!\big(u \log(q_i^{-1} q_{i+1})\big),
        \qquad u = (t - t_i)/h_i,

    after :func:`same_hemisphere`. The joint turns at a constant angular velocity
    :math:`2\log(q_i^{-1}q_{i+1})/h_i` inside each segment, which jumps at every key.

    Parameters
    ----------
    q_keys : array_like, shape (K, ..., 4)
        Rotation keys (normalised here).
    times : array_like, shape (K,)
        Strictly increasing.
    t : array_like, shape (...)
        Inside ``[times[0], times[-1]]``.

    Returns
    -------
    ndarray, shape ``t.shape + q_keys.shape[1:]``
        Unit quaternions.
    """
    q, times = _unit_keys(q_keys, times)
    t = check_t(t, times)
    i, u = segments(times, t)
    return _slerp_segments(q, i, as_column(u, q.ndim - 1))


def squad_controls(q_keys: ArrayLike, times: ArrayLike) -> Array:
    r"""The intermediate control quaternions :math:`s_i` of :func:`squad`.

    With :math:`L_i^{+} = \log(q_i^{-1} q_{i+1})` and :math:`L_i^{-} = \log(q_i^{-1} q_{i-1})`
    (the turns to the next and previous key, seen from :math:`q_i`),

    .. math::
        s_i = q_i \exp\!\left(-\frac{h_{i-1}\,L_i^{+} + h_i\,L_i^{-}}{2\,(h_{i-1} + h_i)}\right),

    which for equally spaced keys is Shoemake's
    :math:`s_i = q_i \exp\!\big(-(L_i^{+} + L_i^{-})/4\big)`. Why: squad's angular velocity
    (in :math:`q_i`'s frame, per unit :math:`u`) leaving key :math:`i` is
    :math:`L_i^{+} + 2\log(q_i^{-1}s_i)` and arriving at it is
    :math:`-L_i^{-} - 2\log(q_i^{-1}s_i)`; dividing by :math:`h_i` and :math:`h_{i-1}` and asking
    them to agree gives the formula, so the spline is C¹ in time even for uneven key times.
    The end keys are their own controls, :math:`s_0 = q_0`, :math:`s_{K-1} = q_{K-1}`.

    Parameters
    ----------
    q_keys : array_like, shape (K, ..., 4)
    times : array_like, shape (K,)

    Returns
    -------
    ndarray, shape (K, ..., 4)
        Unit quaternions, in the hemisphere of their key.
    """
    q, times = _unit_keys(q_keys, times)
    s: Array = q.copy()
    if times.size > 2:
        inv = rot.quat_conjugate(q[1:-1])
        after = quat_log(rot.quat_mul(inv, q[2:]))
        before = quat_log(rot.quat_mul(inv, q[:-2]))
        h = np.diff(times)
        h0, h1 = as_column(h[:-1], q.ndim - 1), as_column(h[1:], q.ndim - 1)
        s[1:-1] = rot.quat_mul(q[1:-1], quat_exp(-(h0 * after + h1 * before) / (2 * (h0 + h1))))
    return s


def squad(q_keys: ArrayLike, times: ArrayLike, t: ArrayLike) -> Array:
    r"""SQUAD: a smooth (C¹) spline through rotation keys.

    On :math:`[t_i, t_{i+1}]`, with :math:`u = (t - t_i)/h_i`,

    .. math::
        \mathrm{squad}(t) = \mathrm{slerp}\big(\mathrm{slerp}(q_i, q_{i+1}, u),\
        \mathrm{slerp}(s_i, s_{i+1}, u),\ 2u(1-u)\big),

    the spherical analogue of a cubic Bézier segment evaluated by de Casteljau. The keys are
    first put in one hemisphere (:func:`same_hemisphere`: the shortest way between
    neighbours) and the controls :math:`s_i` are :func:`squad_controls`. The curve passes
    through every key (:math:`2u(1-u) = 0` at both ends) and its angular velocity is
    continuous across keys. Each :math:`s_i` lies within 45° (on the unit sphere) of its
    key, so the outer blend never needs to flip a sign. The inner SLERP runs along the arc
    from :math:`s_i` to :math:`s_{i+1}` as they are, not the shortest turn between their
    rotations: the two differ once neighbouring keys are more than ~120° apart, and only the
    first keeps the curve C¹ (:func:`_segment_logs`).

    Parameters and returns as :func:`slerp_keys`.
    """
    q, times = _unit_keys(q_keys, times)
    t = check_t(t, times)
    s = squad_controls(q, times)
    i, u = segments(times, t)
    uc = as_column(u, q.ndim - 1)
    along = _slerp_segments(q, i, uc)  # slerp(q_i, q_i+1, u)
    inner = _slerp_segments(s, i, uc)  # slerp(s_i, s_i+1, u)
    blend = _log(_mul(along * _CONJUGATE, inner))
    return _mul(along, _exp(2 * uc * (1 - uc) * blend))


def angular_velocity(q: ArrayLike, times: ArrayLike) -> Array:
    r"""Angular velocity (world frame) of sampled rotations, by finite differences.

    Between samples :math:`k` and :math:`k+1`,
    :math:`\omega_k = 2\log(q_{k+1} q_k^{-1}) / (t_{k+1} - t_k)` (a rotation vector per unit
    time, the sign of :math:`q` ignored): the velocity at the midpoint
    :math:`(t_k + t_{k+1})/2`, accurate to second order for smooth motion.

    Parameters
    ----------
    q : array_like, shape (N, ..., 4)
    times : array_like, shape (N,)
        Strictly increasing sample times.

    Returns
    -------
    ndarray, shape (N - 1, ..., 3)
        Radians per unit of time.
    """
    q, times = _unit_keys(q, times, "q")
    step = rot.quat_mul(q[1:], rot.quat_conjugate(q[:-1]))
    return rot.rotvec_from_quat(step) / as_column(np.diff(times), q.ndim - 1)


def angular_velocity_jump(q_of_t: Callable[[Array], Array], x: float, h: float = 1e-4) -> float:
    r"""How much a rotation curve's angular velocity jumps at time ``x`` (radians per unit time).

    :func:`angular_velocity` on seven samples :math:`x + kh`, k = -3..3, gives velocities at
    the six midpoints; on each side the two nearest are extrapolated linearly to ``x``
    (:math:`\tfrac32\omega_{\pm 1/2} - \tfrac12\omega_{\pm 3/2}`, second order), and the jump
    is the norm of their difference: zero (to :math:`O(h^2)`) where the curve is C¹.

    Parameters
    ----------
    q_of_t : callable
        ``q_of_t(t)`` for times ``t`` (7,), returning unit quaternions (7, 4).
    x : float
        Where to look, e.g. an interior key time.
    h : float
        Sample spacing.
    """
    if not h > 0:
        raise ValueError(f"h: expected > 0, got {h}")
    t7 = x + h * np.arange(-3.0, 4.0)
    w = angular_velocity(q_of_t(t7), t7)  # at x + h (-2.5, -1.5, ..., 2.5)
    return float(np.linalg.norm((1.5 * w[3] - 0.5 * w[4]) - (1.5 * w[2] - 0.5 * w[1])))
