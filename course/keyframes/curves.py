r"""Curves through position keys 关键帧: from straight lines to splines 样条.

The keys are values :math:`p_0, \dots, p_{K-1}` at increasing times
:math:`t_0 < \dots < t_{K-1}` (non-uniform spacing allowed). Every function here takes

* ``keys`` of shape (K, ...): a key per time, with any number of channels (a scalar
  curve (K,), a 2D/3D point (K, 3), every joint of a skeleton (K, J, 3), ...);
* ``times`` of shape (K,), strictly increasing;
* ``t`` of any shape (...), the times to evaluate at, **inside** :math:`[t_0, t_{K-1}]`:
  a time outside the keys is refused with a ``ValueError`` rather than clamped or
  extrapolated, since keys say nothing about what happens outside them (``np.clip`` the
  times first to hold the end keys);

and returns shape ``t.shape + keys.shape[1:]``. ``derivative=1`` gives the velocity
:math:`dp/dt`, ``derivative=2`` the acceleration, for the continuity plots.

Evaluation is batched: ``np.searchsorted`` finds the segment :math:`[t_i, t_{i+1}]` of every
time at once (no Python loop over times); inside it :math:`u = (t - t_i)/h_i` with
:math:`h_i = t_{i+1} - t_i`. At an interior key, ``t == t_i`` belongs to the segment that
starts there (every scheme here is continuous, so either side gives the key).

The schemes:

* :func:`linear`: :math:`p = (1-u)\,p_i + u\,p_{i+1}`; C⁰, the velocity jumps at keys.
* :func:`polynomial`: the one polynomial of degree K−1 through all keys (Newton form); it
  oscillates between equally spaced keys ever more wildly as K grows (Runge's phenomenon).
* :func:`hermite`: piecewise cubics from keys and given tangents :math:`m_i = dp/dt(t_i)`;
* :func:`cubic`: the C² cubic spline (natural or clamped ends), a tridiagonal solve for
  the tangents;
* :func:`catmull_rom`: Hermite with tangents from the neighbouring keys; C¹, local;
* :func:`bezier`: a Bézier curve from control points by de Casteljau's algorithm.

:func:`continuity_jumps` measures a curve's continuity at a key: the jumps of its value,
velocity and acceleration, from finite differences on each side.

All piecewise cubics are evaluated in Hermite form on each segment,

.. math::
    p(u) = H_{00}(u)\,p_i + H_{10}(u)\,h_i m_i + H_{01}(u)\,p_{i+1} + H_{11}(u)\,h_i m_{i+1},

with :math:`H_{00} = 2u^3-3u^2+1`, :math:`H_{10} = u^3-2u^2+u`, :math:`H_{01} = -2u^3+3u^2`,
:math:`H_{11} = u^3-u^2`; each time derivative divides by another :math:`h_i`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validate import as_array

Array = NDArray[np.float64]

KNOTS = ("time", "uniform", "centripetal")

# Knot spacings below this (coincident centripetal keys) are raised to it: the secants through
# such a gap are then 0 (the curve rests there), the limit of ever closer keys.
_MIN_KNOT_SPACING = 1e-12


# --------------------------------------------------------------------------- checks
def check_times(times: ArrayLike, min_keys: int = 2) -> Array:
    """``times`` as a float array (K,), checked to be finite and strictly increasing."""
    times = as_array(times, "times")
    if times.ndim != 1:
        raise ValueError(f"times: expected shape (K,), got {times.shape}")
    if times.size < min_keys:
        raise ValueError(f"times: need at least {min_keys} keys, got {times.size}")
    steps = np.diff(times)
    if np.any(steps <= 0):
        i = int(np.argmax(steps <= 0))
        raise ValueError(
            f"times: must be strictly increasing, but times[{i + 1}] = {times[i + 1]:g} "
            f"follows times[{i}] = {times[i]:g}"
        )
    return times


def check_keys(keys: ArrayLike, times: ArrayLike, name: str = "keys",
               min_keys: int = 2) -> tuple[Array, Array]:
    """``keys`` (K, ...) and ``times`` (K,), checked to agree; errors name ``name``."""
    times = check_times(times, min_keys)
    keys = as_array(keys, name)
    if keys.ndim == 0 or keys.shape[0] != times.size:
        raise ValueError(
            f"{name}: expected one key per time, shape ({times.size}, ...), got {keys.shape}"
        )
    return keys, times


def check_t(t: ArrayLike, times: Array, name: str = "t") -> Array:
    """``t`` checked to lie in ``[times[0], times[-1]]`` (refused outside, see the module)."""
    t = as_array(t, name)
    outside = (t < times[0]) | (t > times[-1])
    if np.any(outside):
        bad = float(t[outside].flat[0])
        raise ValueError(
            f"{name}: {bad:g} is outside the key times [{times[0]:g}, {times[-1]:g}]; keys "
            "are interpolated, not extrapolated (np.clip the times to hold the end keys)"
        )
    return t


def _check_derivative(derivative: int, highest: int = 2) -> int:
    if derivative not in range(highest + 1):
        raise ValueError(f"derivative: expected 0 (value) to {highest}, got {derivative!r}")
    return int(derivative)


def _checked(keys: ArrayLike, times: ArrayLike, t: ArrayLike, derivative: int
             ) -> tuple[Array, Array, Array, int]:
    """The arguments of a curve through ``keys``, checked in the order their errors are
    reported: keys and times, the derivative, the times ``t``."""
    checked_keys, checked_times = check_keys(keys, times)
    order = _check_derivative(derivative)
    return checked_keys, checked_times, check_t(t, checked_times), order


def segments(times: Array, t: Array) -> tuple[NDArray[np.intp], Array]:
    r"""The segment index :math:`i` with :math:`t_i \le t < t_{i+1}` (the last segment for
    :math:`t = t_{K-1}`) and the local parameter :math:`u = (t - t_i)/h_i \in [0, 1]`, for
    every time at once (``t`` checked by :func:`check_t`)."""
    i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, times.size - 2)
    return i, (t - times[i]) / (times[i + 1] - times[i])


def as_column(x: Array, ndim: int) -> Array:
    """``x`` (...) with trailing axes of 1 so that it broadcasts against ``ndim`` more axes."""
    return x.reshape(x.shape + (1,) * ndim)


# --------------------------------------------------------------------------- linear
def linear(keys: ArrayLike, times: ArrayLike, t: ArrayLike, *, derivative: int = 0) -> Array:
    r"""Piecewise linear interpolation: :math:`p(t) = (1-u)\,p_i + u\,p_{i+1}`.

    Continuous (C⁰) but the velocity :math:`(p_{i+1}-p_i)/h_i` jumps at every key.

    Parameters
    ----------
    keys : array_like, shape (K, ...)
    times : array_like, shape (K,)
        Strictly increasing.
    t : array_like, shape (...)
        Inside ``[times[0], times[-1]]``.
    derivative : {0, 1, 2}

    Returns
    -------
    ndarray, shape ``t.shape + keys.shape[1:]``
    """
    keys, times, t, derivative = _checked(keys, times, t, derivative)
    i, u = segments(times, t)
    c = keys.ndim - 1
    p0, p1 = keys[i], keys[i + 1]
    if derivative == 0:
        return p0 + as_column(u, c) * (p1 - p0)
    if derivative == 1:
        return (p1 - p0) / as_column(times[i + 1] - times[i], c)
    return np.zeros_like(p0)


# --------------------------------------------------------------------------- polynomial
def newton_coefficients(keys: ArrayLike, times: ArrayLike) -> Array:
    r"""Divided differences :math:`c_k = p[t_0, \dots, t_k]` of the Newton form
    :math:`p(t) = c_0 + c_1 (t-t_0) + c_2 (t-t_0)(t-t_1) + \dots`, shape (K, ...)."""
    keys, times = check_keys(keys, times, min_keys=1)
    c: Array = keys.copy()
    for j in range(1, times.size):
        dt = as_column(times[j:] - times[:-j], keys.ndim - 1)
        c[j:] = (c[j:] - c[j - 1:-1]) / dt
    return c


def polynomial(keys: ArrayLike, times: ArrayLike, t: ArrayLike, *, derivative: int = 0) -> Array:
    r"""The interpolating polynomial of degree :math:`K-1` through all keys (Lagrange's, in
    Newton form).

    .. math::
        p(t) = \sum_{k=0}^{K-1} c_k \prod_{j<k} (t - t_j), \qquad c_k = p[t_0,\dots,t_k],

    evaluated by Horner's rule (value and derivatives together). Smooth (C^∞) and exact for
    a polynomial of degree below K, but with many equally spaced keys it swings far beyond
    them between the last few (Runge's phenomenon, e.g. on :math:`1/(1+25x^2)`): one key
    moves the whole curve.

    Parameters and returns as :func:`linear`.
    """
    keys, times, t, derivative = _checked(keys, times, t, derivative)
    c = newton_coefficients(keys, times)
    x = as_column(t, keys.ndim - 1)
    p = np.broadcast_to(c[-1], x.shape[:t.ndim] + c.shape[1:]).copy()
    dp, d2p = np.zeros_like(p), np.zeros_like(p)
    for k in range(times.size - 2, -1, -1):  # p <- p (t - t_k) + c_k, and its derivatives
        d2p = d2p * (x - times[k]) + 2 * dp
        dp = dp * (x - times[k]) + p
        p = p * (x - times[k]) + c[k]
    value: Array = (p, dp, d2p)[derivative]
    return value


# --------------------------------------------------------------------------- Hermite
def _hermite_segments(p0: Array, p1: Array, d0: Array, d1: Array, u: Array, h: Array,
                      derivative: int) -> Array:
    """Cubic Hermite segments from end values ``p0, p1`` and end tangents ``d0, d1`` per unit
    ``u`` (i.e. already times the segment's length), with time derivatives over ``h``."""
    c = p0.ndim - u.ndim
    u = as_column(u, c)
    if derivative == 0:
        basis = (2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u, -2 * u**3 + 3 * u**2, u**3 - u**2)
    elif derivative == 1:
        basis = (6 * u**2 - 6 * u, 3 * u**2 - 4 * u + 1, -6 * u**2 + 6 * u, 3 * u**2 - 2 * u)
    else:
        basis = (12 * u - 6, 6 * u - 4, -12 * u + 6, 6 * u - 2)
    value = basis[0] * p0 + basis[1] * d0 + basis[2] * p1 + basis[3] * d1
    return value / as_column(h, c) ** derivative if derivative else value


def hermite(keys: ArrayLike, tangents: ArrayLike, times: ArrayLike, t: ArrayLike, *,
            derivative: int = 0) -> Array:
    r"""Piecewise cubic Hermite interpolation from keys and their tangents.

    On :math:`[t_i, t_{i+1}]` the cubic with :math:`p(t_i) = p_i`, :math:`p(t_{i+1}) = p_{i+1}`,
    :math:`p'(t_i) = m_i`, :math:`p'(t_{i+1}) = m_{i+1}` (see the module for the basis).
    C¹ wherever the tangents are shared by the two segments of a key, as here.

    Parameters
    ----------
    keys : array_like, shape (K, ...)
    tangents : array_like, shape (K, ...)
        :math:`m_i = dp/dt` at each key, per unit of time (not per segment).
    times, t, derivative
        As :func:`linear`.
    """
    keys, times = check_keys(keys, times)
    tangents = as_array(tangents, "tangents")
    if tangents.shape != keys.shape:
        raise ValueError(f"tangents: expected the shape of keys {keys.shape}, got {tangents.shape}")
    derivative = _check_derivative(derivative)
    t = check_t(t, times)
    i, u = segments(times, t)
    h = times[i + 1] - times[i]
    hc = as_column(h, keys.ndim - 1)
    return _hermite_segments(keys[i], keys[i + 1], hc * tangents[i], hc * tangents[i + 1], u, h,
                             derivative)


# --------------------------------------------------------------------------- cubic spline
def cubic_tangents(keys: ArrayLike, times: ArrayLike, start_tangent: ArrayLike | None = None,
                   end_tangent: ArrayLike | None = None) -> Array:
    r"""The tangents :math:`m_i` of the C² cubic spline through the keys.

    Asking the Hermite segments to agree in second derivative at every interior key gives,
    with :math:`\delta_i = (p_{i+1}-p_i)/h_i`,

    .. math::
        h_i\,m_{i-1} + 2(h_{i-1}+h_i)\,m_i + h_{i-1}\,m_{i+1}
        = 3\,(h_i\,\delta_{i-1} + h_{i-1}\,\delta_i), \qquad 0 < i < K-1,

    closed at each end by either a **clamped** end (the tangent is given, :math:`m_0 = a`)
    or a **natural** end (zero second derivative, :math:`2m_0 + m_1 = 3\delta_0` and
    :math:`m_{K-2} + 2m_{K-1} = 3\delta_{K-2}`). The system is tridiagonal and diagonally
    dominant; it is solved by the Thomas algorithm (one forward sweep, one back
    substitution: O(K), for all channels at once).

    Parameters
    ----------
    keys : array_like, shape (K, ...)
    times : array_like, shape (K,)
    start_tangent, end_tangent : array_like, shape ``keys.shape[1:]``, optional
        Clamp that end's tangent :math:`dp/dt`; ``None`` (default) leaves the end natural.

    Returns
    -------
    ndarray, shape (K, ...)
    """
    keys, times = check_keys(keys, times)
    n, c = times.size, keys.ndim - 1
    h = np.diff(times)
    delta = np.diff(keys, axis=0) / as_column(h, c)
    lower, diag, upper = np.zeros(n), np.zeros(n), np.zeros(n)
    rhs = np.zeros_like(keys)
    lower[1:-1], diag[1:-1], upper[1:-1] = h[1:], 2 * (h[:-1] + h[1:]), h[:-1]
    rhs[1:-1] = 3 * (as_column(h[1:], c) * delta[:-1] + as_column(h[:-1], c) * delta[1:])
    for end, tangent, row in (("start_tangent", start_tangent, 0),
                              ("end_tangent", end_tangent, -1)):
        if tangent is None:  # natural: 2 m_0 + m_1 = 3 delta_0 (mirrored at the end)
            diag[row] = 2.0
            (upper if row == 0 else lower)[row] = 1.0
            rhs[row] = 3 * delta[row]
        else:  # clamped: m = the given tangent
            tangent = as_array(tangent, end)
            if tangent.shape != keys.shape[1:]:
                raise ValueError(
                    f"{end}: expected one value per channel, shape {keys.shape[1:]}, "
                    f"got {tangent.shape}"
                )
            diag[row] = 1.0
            rhs[row] = tangent
    # Thomas algorithm: eliminate the sub-diagonal going down, then substitute going up.
    m: Array = rhs.copy()
    d = diag.copy()
    for i in range(1, n):
        w = lower[i] / d[i - 1]
        d[i] -= w * upper[i - 1]
        m[i] -= w * m[i - 1]
    m[-1] /= d[-1]
    for i in range(n - 2, -1, -1):
        m[i] = (m[i] - upper[i] * m[i + 1]) / d[i]
    return m


def cubic(keys: ArrayLike, times: ArrayLike, t: ArrayLike, *,
          start_tangent: ArrayLike | None = None, end_tangent: ArrayLike | None = None,
          derivative: int = 0) -> Array:
    r"""The C² cubic spline through the keys: :func:`hermite` with :func:`cubic_tangents`.

    Natural ends (the default) have zero second derivative; a given ``start_tangent`` /
    ``end_tangent`` clamps that end. Any cubic polynomial is reproduced exactly by the
    clamped spline with its own end derivatives. Unlike Catmull–Rom, moving one key moves
    every segment a little (the tangents come from one global solve).

    Parameters and returns as :func:`linear`; ``start_tangent`` and ``end_tangent`` as
    :func:`cubic_tangents`.
    """
    keys, times = check_keys(keys, times)
    return hermite(keys, cubic_tangents(keys, times, start_tangent, end_tangent), times, t,
                   derivative=derivative)


# --------------------------------------------------------------------------- Catmull-Rom
def _knot_spacing(keys: Array, times: Array, knots: str) -> Array:
    """Segment lengths in the knot parameter: (K-1,) for ``"time"`` and ``"uniform"``,
    (K-1, ...) per curve (the keys' last axis being the point) for ``"centripetal"``."""
    if knots == "time":
        return np.diff(times)
    if knots == "uniform":
        return np.ones(times.size - 1)
    if knots == "centripetal":
        step = np.diff(keys, axis=0)
        dist = np.abs(step) if keys.ndim == 1 else np.linalg.norm(step, axis=-1)
        return np.maximum(np.sqrt(dist), _MIN_KNOT_SPACING)
    raise ValueError(f"knots: expected one of {KNOTS}, got {knots!r}")


def catmull_rom(keys: ArrayLike, times: ArrayLike, t: ArrayLike, *, knots: str = "time",
                derivative: int = 0) -> Array:
    r"""Catmull–Rom spline: Hermite segments whose tangents come from the neighbouring keys.

    With knot values :math:`s_i` (the curve's own parameter at key :math:`i`) and
    :math:`\Delta_i = s_{i+1} - s_i`, the tangent at an interior key is the central difference

    .. math::
        m_i = \frac{p_{i+1} - p_{i-1}}{s_{i+1} - s_{i-1}},

    which for equal spacing :math:`\Delta` is the familiar :math:`(p_{i+1} - p_{i-1}) / 2\Delta`.
    The end keys take the one-sided slope :math:`m_0 = (p_1 - p_0)/\Delta_0`,
    :math:`m_{K-1} = (p_{K-1} - p_{K-2})/\Delta_{K-2}`. Each segment is the Hermite cubic with
    end tangents :math:`\Delta_i m_i, \Delta_i m_{i+1}` per unit :math:`u`. The curve passes
    through every key and each segment depends on four keys only (local control).

    ``knots`` chooses :math:`s_i`:

    * ``"time"`` (default): :math:`s_i = t_i`, the key times. Then :math:`m_i` is a velocity
      :math:`dp/dt` (divided by the time between the *two neighbours*,
      :math:`t_{i+1} - t_{i-1}`) and the curve is C¹ in time even for unevenly spaced keys;
      :func:`~course.keyframes.rotations.squad` has the same tangents for rotations.
    * ``"uniform"``: :math:`s_i = i`, the textbook spline that ignores how far apart the key
      times are; with uneven times its velocity jumps at the keys (by :math:`h_{i-1}/h_i`).
    * ``"centripetal"``: :math:`\Delta_i = \lVert p_{i+1} - p_i\rVert^{1/2}`, per curve (the
      last axis of ``keys`` is the point; (K,) keys are scalar curves), with Barry and
      Goldman's tangent, the slope at :math:`s_i` of the parabola through the three keys,
      :math:`m_i = (\Delta_i\,\delta_{i-1} + \Delta_{i-1}\,\delta_i)/(\Delta_{i-1} + \Delta_i)`,
      :math:`\delta_i = (p_{i+1} - p_i)/\Delta_i`. This is Yuksel et al.'s centripetal
      Catmull–Rom: it follows the key polygon without cusps or self-intersections within a
      segment, even where keys bunch up, but is C¹ only in its own parameter, not in time.

    Parameters
    ----------
    keys, times, t, derivative
        As :func:`linear`.
    knots : {"time", "uniform", "centripetal"}

    Returns
    -------
    ndarray, shape ``t.shape + keys.shape[1:]``
    """
    keys, times, t, derivative = _checked(keys, times, t, derivative)
    spacing = _knot_spacing(keys, times, knots)  # (K-1,) or (K-1, ...) without the point axis
    ds = as_column(spacing, keys.ndim - spacing.ndim)
    delta = np.diff(keys, axis=0) / ds
    m = np.empty_like(keys)
    if knots == "centripetal":
        m[1:-1] = (ds[1:] * delta[:-1] + ds[:-1] * delta[1:]) / (ds[:-1] + ds[1:])
    else:
        m[1:-1] = (keys[2:] - keys[:-2]) / (ds[:-1] + ds[1:])
    m[0], m[-1] = delta[0], delta[-1]
    i, u = segments(times, t)
    return _hermite_segments(keys[i], keys[i + 1], ds[i] * m[i], ds[i] * m[i + 1], u,
                             times[i + 1] - times[i], derivative)


# --------------------------------------------------------------------------- Bezier
def bezier(control_points: ArrayLike, s: ArrayLike, *, derivative: int = 0) -> Array:
    r"""A Bézier curve of degree :math:`n` by de Casteljau's algorithm.

    .. math::
        b_i^{(r)}(s) = (1-s)\,b_i^{(r-1)}(s) + s\,b_{i+1}^{(r-1)}(s), \qquad
        b(s) = b_0^{(n)}(s) = \sum_{i=0}^{n} \binom{n}{i} s^i (1-s)^{n-i}\, b_i,

    repeated linear interpolation of the control points :math:`b_i = b_i^{(0)}`: numerically
    stable and equal to the Bernstein form. The curve starts at :math:`b_0`, ends at
    :math:`b_n`, leaves along :math:`n(b_1 - b_0)` and is only *pulled towards* the inner
    control points. Derivatives are Bézier curves of the differences,
    :math:`b'(s) = n \sum_i \binom{n-1}{i} s^i (1-s)^{n-1-i} (b_{i+1} - b_i)`.
    A cubic Hermite segment is the Bézier curve with control points
    :math:`p_i,\ p_i + h_i m_i/3,\ p_{i+1} - h_i m_{i+1}/3,\ p_{i+1}`.

    Parameters
    ----------
    control_points : array_like, shape (n + 1, ...)
    s : array_like, shape (...)
        Curve parameter in ``[0, 1]``.
    derivative : int
        Derivative with respect to ``s`` (0 to n).

    Returns
    -------
    ndarray, shape ``s.shape + control_points.shape[1:]``
    """
    b = as_array(control_points, "control_points")
    if b.ndim == 0 or b.shape[0] < 2:
        raise ValueError(f"control_points: expected shape (n + 1, ...) with n >= 1, got {b.shape}")
    derivative = _check_derivative(derivative, b.shape[0] - 1)
    s = check_t(s, np.array([0.0, 1.0]), "s")
    for _ in range(derivative):  # b' is the degree-(n-1) curve of n (b_{i+1} - b_i)
        b = (b.shape[0] - 1) * np.diff(b, axis=0)
    sc = as_column(s, b.ndim - 1)
    level = [np.broadcast_to(bi, sc.shape[:s.ndim] + b.shape[1:]) for bi in b]
    while len(level) > 1:
        level = [(1 - sc) * a + sc * c for a, c in zip(level[:-1], level[1:], strict=True)]
    return np.array(level[0])


def continuity_jumps(curve: Callable[[Array], Array], x: float, h: float = 1e-4) -> Array:
    r"""How much a scalar curve's value, velocity and acceleration jump at ``x``: shape (3,).

    Each side is measured on its own samples only, :math:`v_k = p(x \pm k h)`, k = 1..4
    (not ``x`` itself, which belongs to one side): the cubic through them, extrapolated to
    ``x``, gives that side's :math:`p, p', p''` there, off by :math:`O(h^4), O(h^3), O(h^2)`.
    The jumps are the absolute differences of the two sides. A curve is :math:`C^k` at ``x``
    when the first k + 1 are (numerically) zero; rounding adds about :math:`10\varepsilon/h`
    and :math:`10\varepsilon/h^2` to the derivatives, so compare with tolerances (1e-9, 1e-3
    and 1e-1 for h = 1e-4 and curves of size 1).

    Parameters
    ----------
    curve : callable
        ``curve(t)`` for an array of times ``t`` (4,), returning values (4,).
    x : float
        Where to look, e.g. an interior key time (both sides inside the curve's range).
    h : float
        Sample spacing.
    """
    if not h > 0:
        raise ValueError(f"h: expected > 0, got {h}")
    sides = np.empty((2, 3))
    for k, side in enumerate((-1.0, 1.0)):
        offsets = side * h * np.arange(1.0, 5.0)
        v = np.asarray(curve(x + offsets), dtype=np.float64)
        if v.shape != (4,):
            raise ValueError(f"curve: expected 4 values for 4 times, got shape {v.shape}")
        c = np.linalg.solve(np.vander(offsets, 4, increasing=True), v)  # p(x + s) = sum c_i s^i
        sides[k] = (c[0], c[1], 2 * c[2])
    jumps: Array = np.abs(sides[1] - sides[0])
    return jumps
