r"""Swing–twist decomposition and cone + twist-range joint limits (shoulders, hips).

A joint rotation :math:`q` splits into a *twist* :math:`t` about a unit axis :math:`a` of the
joint's own (local) frame -- usually the bone -- and a *swing* :math:`s` about an axis
perpendicular to :math:`a`:

.. math::
    q = s \otimes t,\qquad t = \frac{(w,\ (\mathbf v\cdot a)\,a)}
    {\lVert (w,\ (\mathbf v\cdot a)\,a) \rVert},\qquad s = q \otimes t^{-1},

for :math:`q = (w, \mathbf v)`. **Why this order.** With active rotations :math:`q\,x` applied to
a vector of the child's frame, :math:`s \otimes t` applies the twist first, while the axis is
still the child's own axis :math:`a`, and then swings that axis to :math:`s\,a = q\,a`
(:math:`t\,a = a`). So the twist spins the bone about itself and the swing says where the bone
points: a cone limit constrains :math:`s` alone and a twist range :math:`t` alone, as game
engines and the robotics literature do for shoulders and hips.

**The singularity.** When the bone is swung by a half turn (:math:`q\,a = -a`), :math:`w` and
:math:`\mathbf v\cdot a` are both zero and every twist fits (any :math:`t` about :math:`a` pairs
with a half-turn swing): the decomposition is not unique there, and no choice is continuous
across it. We take the twist as the identity when
:math:`\lVert (w, \mathbf v\cdot a)\rVert <` :data:`SINGULAR_EPS` (so the swing is :math:`q`
itself, a half turn about an axis perpendicular to :math:`a`); the result stays exact, only
the split is a convention there.

Quaternions are made canonical (:math:`w \ge 0`) first, so both parts come out with
:math:`w \ge 0`: the swing angle lies in :math:`[0, \pi]`, the twist angle in
:math:`[-\pi, \pi]`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .._validate import as_array, as_quat, as_unit, broadcast_leading
from .quaternion import quat_conjugate, quat_mul

# Below this |(w, v.a)| the swing is a half turn and the twist is taken as the identity: the
# decomposition has no unique answer there (see the module notes).
SINGULAR_EPS = 1e-12


def _inputs(q: ArrayLike, axis: ArrayLike, where: str) -> tuple[Array, Array]:
    """Unit, canonical ``q (..., 4)`` and unit ``axis (..., 3)``, broadcast together."""
    u = as_quat(q, "q")
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    u = np.where(u[..., :1] < 0, -u, u)
    a = as_unit(axis, "axis", why="the twist needs an axis to turn about")
    shape = broadcast_leading(where, ("q", u, 1), ("axis", a, 1))
    return np.broadcast_to(u, shape + (4,)), np.broadcast_to(a, shape + (3,))


def _split(q: Array, a: Array) -> tuple[Array, Array]:
    """Swing and twist of canonical unit ``q`` about unit ``a`` (no checks)."""
    p = np.einsum("...i,...i->...", q[..., 1:], a)
    n = np.hypot(q[..., 0], p)
    singular = n < SINGULAR_EPS
    safe = np.where(singular, 1.0, n)
    twist = np.concatenate([q[..., :1], p[..., None] * a], axis=-1) / safe[..., None]
    twist = np.where(singular[..., None], np.array([1.0, 0.0, 0.0, 0.0]), twist)
    return quat_mul(q, quat_conjugate(twist)), twist


def swing_twist(q: ArrayLike, axis: ArrayLike) -> tuple[Array, Array]:
    r"""Split rotations into a swing and a twist about ``axis``: :math:`q = s \otimes t`.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Quaternions (w, x, y, z); normalised here (any non-zero length).
    axis : array_like, shape (..., 3)
        The twist axis :math:`a` in the joint's local frame (any non-zero length);
        broadcasts against ``q``.

    Returns
    -------
    swing : ndarray, shape (..., 4)
        :math:`s`, a rotation about an axis perpendicular to :math:`a`, :math:`w \ge 0`.
    twist : ndarray, shape (..., 4)
        :math:`t`, a rotation about :math:`a`, :math:`w \ge 0`; the identity at the half-turn
        singularity (module notes). ``quat_mul(swing, twist)`` is ``q`` up to sign.

    Examples
    --------
    >>> from course.rotations import quat_from_axis_angle
    >>> swing, twist = swing_twist(quat_from_axis_angle([0, 1, 0], 0.3), [0, 1, 0])
    >>> swing.round(12).tolist()            # a pure twist about the axis has no swing
    [1.0, 0.0, 0.0, 0.0]
    """
    return _split(*_inputs(q, axis, "swing_twist"))


def twist_angle(q: ArrayLike, axis: ArrayLike) -> Array:
    r"""Signed twist angle about ``axis``, in :math:`[-\pi, \pi]`, shape (...).

    :math:`2\,\mathrm{atan2}(\mathbf v\cdot a,\ w)` of canonical :math:`q`; 0 at the half-turn
    singularity, as in :func:`swing_twist`.
    """
    q, a = _inputs(q, axis, "twist_angle")
    p = np.einsum("...i,...i->...", q[..., 1:], a)
    singular = np.hypot(q[..., 0], p) < SINGULAR_EPS
    return np.where(singular, 0.0, 2.0 * np.arctan2(p, q[..., 0]))


def swing_angle(q: ArrayLike, axis: ArrayLike) -> Array:
    r"""Swing angle in :math:`[0, \pi]`: the angle between :math:`a` and :math:`q\,a`, shape (...).

    :math:`2\,\mathrm{atan2}(\lVert\mathbf v - (\mathbf v\cdot a)a\rVert,\
    \lVert(w, \mathbf v\cdot a)\rVert)`.
    """
    q, a = _inputs(q, axis, "swing_angle")
    p = np.einsum("...i,...i->...", q[..., 1:], a)
    perp = np.linalg.norm(q[..., 1:] - p[..., None] * a, axis=-1)
    angle: Array = 2.0 * np.arctan2(perp, np.hypot(q[..., 0], p))
    return angle


def _clamp_on_circle(theta: Array, lo: Array, hi: Array) -> Array:
    r"""Angles ``theta`` in :math:`[-\pi, \pi]` moved into the arc from ``lo`` up to ``hi``
    (:math:`-\pi \le lo \le hi \le \pi`) **on the circle**: an angle on the arc stays (so
    :math:`\pi` stays in :math:`[-\pi, -3]`, where it is :math:`-\pi`); one off it goes to
    the bound nearer round the circle, which across :math:`\pm\pi` is not the nearer number:
    -3.0 with the arc [-0.5, 3.0] goes to 3.0 (0.28 away), not to -0.5 (2.5 away).

    Measured from the arc's middle and wrapped to :math:`[-\pi, \pi]`, an angle is on the arc
    within half its length, above it nearer ``hi`` and below it nearer ``lo``.
    (:func:`course.ik._engine.components.clamp_swing_twist` does the same on components.)
    """
    off = theta - 0.5 * (lo + hi)
    off = np.arctan2(np.sin(off), np.cos(off))
    clamped: Array = np.where(np.abs(off) <= 0.5 * (hi - lo), theta, np.where(off > 0, hi, lo))
    return clamped


def clamp_swing_twist(
    q: ArrayLike,
    axis: ArrayLike,
    max_swing: ArrayLike,
    twist_range: tuple[ArrayLike, ArrayLike],
) -> Array:
    r"""Project rotations onto a swing cone and a twist range (a shoulder or hip limit).

    The swing is kept about its own axis and its angle clamped to ``max_swing`` (the nearest
    swing inside the cone, along the great circle towards the identity); the twist angle is
    clamped to ``twist_range`` on the circle (the nearest allowed twist, also across
    :math:`\pm\pi`: :func:`_clamp_on_circle`). The result is
    :math:`s' \otimes t'`. A rotation already inside the limits comes back unchanged (up to
    sign), and clamping twice changes nothing more. Each part is the nearest allowed one; the
    product is the nearest in this swing–twist sense, not always the geodesically nearest
    rotation of the allowed set.

    Parameters
    ----------
    q : array_like, shape (..., 4)
    axis : array_like, shape (..., 3)
        Twist axis :math:`a` in the joint's local frame (the bone).
    max_swing : array_like, shape (...)
        Half-angle of the cone in radians, in :math:`[0, \pi]`.
    twist_range : (lo, hi), each array_like of shape (...)
        Allowed twist angles in radians, :math:`-\pi \le lo \le hi \le \pi`.

    Returns
    -------
    ndarray, shape (..., 4)
        Canonical unit quaternions (:math:`w \ge 0`) within the limits.

    Raises
    ------
    ValueError
        Naming the argument: a cone outside :math:`[0, \pi]`, a twist range with
        ``lo > hi`` or outside :math:`[-\pi, \pi]`, or shapes that do not broadcast.
    """
    if not isinstance(twist_range, tuple | list | np.ndarray) or len(twist_range) != 2:
        raise ValueError(f"twist_range: expected a pair (lo, hi) in radians, got {twist_range!r}")
    cone = as_array(max_swing, "max_swing")
    lo = as_array(twist_range[0], "twist_range[0]")
    hi = as_array(twist_range[1], "twist_range[1]")
    if np.any((cone < 0) | (cone > np.pi)):
        raise ValueError(f"max_swing: must lie in [0, pi] radians, got {cone}")
    if np.any((lo < -np.pi) | (hi > np.pi)):
        raise ValueError(f"twist_range: must lie in [-pi, pi] radians, got ({lo}, {hi})")
    if np.any(lo > hi):
        raise ValueError(f"twist_range: lo must not exceed hi, got ({lo}, {hi})")
    q, a = _inputs(q, axis, "clamp_swing_twist")
    broadcast_leading(
        "clamp_swing_twist", ("q", q, 1), ("max_swing", cone, 0), ("twist_range[0]", lo, 0),
        ("twist_range[1]", hi, 0),
    )
    swing, twist = _split(q, a)

    # Swing: same axis, angle min(angle, max_swing). Both parts have w >= 0.
    sin_half = np.linalg.norm(swing[..., 1:], axis=-1)
    angle = 2.0 * np.arctan2(sin_half, swing[..., 0])
    new_half = 0.5 * np.minimum(angle, cone)
    scale = np.where(sin_half > 0, np.sin(new_half) / np.where(sin_half > 0, sin_half, 1.0), 0.0)
    swing = np.concatenate([np.cos(new_half)[..., None], swing[..., 1:] * scale[..., None]], -1)

    # Twist: angle about a, clamped on the circle.
    theta = _clamp_on_circle(2.0 * np.arctan2(np.einsum("...i,...i->...", twist[..., 1:], a),
                                              twist[..., 0]), lo, hi)
    twist = np.concatenate([np.cos(theta / 2)[..., None], np.sin(theta / 2)[..., None] * a], -1)
    out = quat_mul(swing, twist)
    return np.where(out[..., :1] < 0, -out, out)
