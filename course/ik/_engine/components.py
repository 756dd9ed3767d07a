r"""Vector and quaternion kernels on *components*: a vector is a tuple ``(x, y, z)``, a
quaternion ``(w, x, y, z)``, and each component a Python float (one problem) or an ndarray
``(B,)`` (a batch), with ``ops`` (:mod:`.ops`) supplying what differs between the two. They are
named as the checked functions of :mod:`course.rotations` they mirror, and unchecked.

The fast path (:mod:`.chain`) is written on them; the tree engine uses :func:`limit`, the one
joint-limit projection.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

from .ops import Ops
from .small import TINY

Scalar = Any  # a float, or an ndarray (B,)
Vec = tuple  # (x, y, z) of Scalars
Quat = tuple  # (w, x, y, z) of Scalars


# --------------------------------------------------------------------------- vectors
def add(a: Vec, b: Vec) -> Vec:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def scale(a: Vec, s: Scalar) -> Vec:
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a: Vec, b: Vec) -> Scalar:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def quat_mul(a: Quat, b: Quat) -> Quat:
    """Hamilton product :math:`a b` (rotate by ``b``, then ``a``)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def quat_conjugate(q: Quat) -> Quat:
    return (q[0], -q[1], -q[2], -q[3])


def quat_rotate(q: Quat, v: Vec) -> Vec:
    r""":math:`q v q^*` as :math:`v + w t + u\times t`, :math:`t = 2u\times v`,
    :math:`u = (x, y, z)` (written out: this is the innermost operation)."""
    w, x, y, z = q
    vx, vy, vz = v
    tx, ty, tz = 2.0 * (y * vz - z * vy), 2.0 * (z * vx - x * vz), 2.0 * (x * vy - y * vx)
    return (vx + w * tx + y * tz - z * ty, vy + w * ty + z * tx - x * tz,
            vz + w * tz + x * ty - y * tx)


def units_like(qs: list[Quat], refs: list[Quat], ops: Ops) -> list[Quat]:
    """The quaternions ``qs`` normalised, each with the sign of its ``refs`` entry (``q`` and
    ``-q`` are one rotation: keeping the starting quaternion's sign spares an animated solve
    its sign flips)."""
    sqrt, where, out = ops.sqrt, ops.where, []
    for (w, x, y, z), (rw, rx, ry, rz) in zip(qs, refs, strict=True):
        inv = 1.0 / sqrt(w * w + x * x + y * y + z * z)
        inv = where(w * rw + x * rx + y * ry + z * rz < 0, -inv, inv)
        out.append((w * inv, x * inv, y * inv, z * inv))
    return out


def quat_from_axis_angle(axis: Vec, angle: Scalar, ops: Ops) -> Quat:
    """Turn by ``angle`` about the unit ``axis`` (a constant)."""
    s = ops.sin(0.5 * angle)
    return (ops.cos(0.5 * angle), axis[0] * s, axis[1] * s, axis[2] * s)


def quat_from_rotvec(r: Vec, ops: Ops) -> Quat:
    r""":math:`\exp(r)`: turn by :math:`\lVert r\rVert` about :math:`\hat r` (identity at 0)."""
    theta = ops.sqrt(dot(r, r))
    safe = ops.where(theta > 1e-8, theta, 1.0)
    k = ops.where(theta > 1e-8, ops.sin(0.5 * safe) / safe, 0.5)
    return (ops.cos(0.5 * theta), r[0] * k, r[1] * k, r[2] * k)


def quat_between(u: Vec, v: Vec, ops: Ops) -> Quat:
    r"""Shortest arc taking direction ``u`` onto ``v``: :math:`(\lVert u\rVert\lVert v\rVert +
    u\cdot v,\ u\times v)` normalised; a half turn about an axis perpendicular to ``u`` when
    they are opposite; the identity when either is shorter than ``TINY`` (as
    :func:`course.ik._engine.small.matrix_between`). The two special cases are rare, so they are
    only worked out when some problem needs them (FABRIK fits every bone with this)."""
    (ux, uy, uz), (vx, vy, vz) = u, v
    uu, vv = ux * ux + uy * uy + uz * uz, vx * vx + vy * vy + vz * vz
    nn = ops.sqrt(uu * vv)
    w, x, y, z = (nn + ux * vx + uy * vy + uz * vz, uy * vz - uz * vy, uz * vx - ux * vz,
                  ux * vy - uy * vx)
    opposite = w <= TINY * nn
    if ops.any(opposite):
        # Turn about u x (the coordinate axis of u's smallest component), as matrix_between.
        ax, ay, az = ops.abs(u[0]), ops.abs(u[1]), ops.abs(u[2])
        use_x = ops.both(ax <= ay, ax <= az)
        use_y = ops.both(ops.invert(use_x), ay <= az)
        px, py, pz = ops.select(use_x, (0.0, u[2], -u[1]),  # u x (1, 0, 0)
                                ops.select(use_y, (-u[2], 0.0, u[0]), (u[1], -u[0], 0.0)))
        w, x, y, z = (ops.where(opposite, 0.0, w), ops.where(opposite, px, x),
                      ops.where(opposite, py, y), ops.where(opposite, pz, z))
    n = ops.sqrt(w * w + x * x + y * y + z * z)
    degenerate = ops.minimum(uu, vv) < TINY * TINY  # either vector (nearly) zero
    if not ops.any(degenerate):
        inv = 1.0 / n
        return (w * inv, x * inv, y * inv, z * inv)
    inv = 1.0 / ops.where(degenerate, 1.0, n)
    return (ops.where(degenerate, 1.0, w * inv), ops.where(degenerate, 0.0, x * inv),
            ops.where(degenerate, 0.0, y * inv), ops.where(degenerate, 0.0, z * inv))


def cap_angle(q: Quat, cap: float, ops: Ops) -> Quat:
    r"""``q`` with its rotation angle :math:`2\,\mathrm{atan2}(\lVert v\rVert, |w|)` capped at
    ``cap``, keeping its axis."""
    w, x, y, z = q
    s = ops.sqrt(x * x + y * y + z * z)
    over = 2.0 * ops.atan2(s, ops.abs(w)) > cap
    k = math.sin(0.5 * cap) / ops.where(s > TINY, s, 1.0)
    sign = ops.where(w < 0, -1.0, 1.0)
    return (ops.where(over, sign * math.cos(0.5 * cap), w), ops.where(over, x * k, x),
            ops.where(over, y * k, y), ops.where(over, z * k, z))


class Limit(NamedTuple):
    r"""One joint's limit on its local rotation, as :func:`limit` projects it.

    ``kind`` is ``"hinge"`` (the angle about ``axis`` in ``[lo, hi]``), ``"cap"`` (a ball's
    whole rotation angle at most ``hi``: swing and twist together) or ``"swing_twist"`` (the
    swing of the bone axis ``axis`` within the cone ``cone``, the twist about it in
    ``[lo, hi]``; :func:`course.rotations.clamp_swing_twist`).
    """

    kind: str
    axis: Vec | None
    lo: float
    hi: float
    cone: float = math.inf


def limit(R: Quat, lim: Limit, ops: Ops) -> Quat:
    r"""A local rotation projected into its limit: a hinge's angle
    :math:`\theta = \mathrm{atan2}(2w\,(v\cdot\hat a),\ w^2 - \lVert v\rVert^2)` clipped to
    ``[lo, hi]``; a ball's rotation angle capped at ``hi``; a swing–twist cone by
    :func:`clamp_swing_twist`."""
    if lim.kind == "cap":
        return cap_angle(R, lim.hi, ops)
    if lim.kind == "swing_twist":
        return clamp_swing_twist(R, lim.axis, lim.cone, lim.lo, lim.hi, ops)
    w, x, y, z = R
    axis = lim.axis
    theta = ops.atan2(2.0 * w * dot((x, y, z), axis), w * w - (x * x + y * y + z * z))
    fix = ops.minimum(ops.maximum(theta, lim.lo), lim.hi) - theta
    return quat_mul(quat_from_axis_angle(axis, fix, ops), R)


def clamp_swing_twist(q: Quat, axis: Vec, cone: float, lo: float, hi: float, ops: Ops) -> Quat:
    r""":func:`course.rotations.clamp_swing_twist` on components: :math:`q = s\otimes t`
    (twist :math:`t \propto (w, (v\cdot a)\,a)`, the identity at the half-turn singularity),
    the swing's angle capped at ``cone`` about its own axis, the twist angle clamped to
    ``[lo, hi]`` on the circle (as ``course.rotations.swing_twist._clamp_on_circle``), and
    :math:`s'\otimes t'` returned in the sign of ``q``."""
    sign = ops.where(q[0] < 0, -1.0, 1.0)  # canonical (w >= 0), as the checked function
    w, x, y, z = q[0] * sign, q[1] * sign, q[2] * sign, q[3] * sign
    p = x * axis[0] + y * axis[1] + z * axis[2]
    n = ops.sqrt(w * w + p * p)
    singular = n < 1e-12
    inv = 1.0 / ops.where(singular, 1.0, n)
    tw, tp = ops.where(singular, 1.0, w * inv), ops.where(singular, 0.0, p * inv)
    sw, sx, sy, sz = quat_mul((w, x, y, z), (tw, -tp * axis[0], -tp * axis[1], -tp * axis[2]))
    sin_half = ops.sqrt(sx * sx + sy * sy + sz * sz)
    half = 0.5 * ops.minimum(2.0 * ops.atan2(sin_half, sw), cone)
    k = ops.where(sin_half > 0, ops.sin(half) / ops.where(sin_half > 0, sin_half, 1.0), 0.0)
    twist = 2.0 * ops.atan2(tp, tw)
    off = twist - 0.5 * (lo + hi)
    off = ops.atan2(ops.sin(off), ops.cos(off))  # from the range's middle, round the circle
    theta = 0.5 * ops.where(ops.abs(off) <= 0.5 * (hi - lo), twist,
                            ops.where(off > 0, hi, lo))
    st = ops.sin(theta)
    out = quat_mul((ops.cos(half), sx * k, sy * k, sz * k),
                   (ops.cos(theta), st * axis[0], st * axis[1], st * axis[2]))
    return (out[0] * sign, out[1] * sign, out[2] * sign, out[3] * sign)


def aim(R: Quat, parent: Quat, axis: Vec | None, u: Vec, w: Vec, ops: Ops,
        max_angle: float | None = None) -> Quat:
    r"""Turn a joint so that the world direction ``u`` (from its pivot) points along ``w``,
    the step CCD takes at every joint and FABRIK's backward pass at every bone.

    A hinge (``axis`` :math:`\hat a` in the parent frame, world :math:`a = Q_{i-1}\hat a`)
    turns by the angle between the projections of ``u`` and ``w`` on its plane,
    :math:`\mathrm{atan2}(a\cdot(u\times w),\ u\cdot w - (u\cdot a)(w\cdot a))`, so
    :math:`R \leftarrow \exp(\theta\hat a) R`; a ball joint by the shortest arc ``q`` from
    ``u`` to ``w``, a world turn, so :math:`R \leftarrow Q_{i-1}^{-1} q\, Q_{i-1} R`.
    ``max_angle`` caps the turn. The result is renormalised (:func:`_unit`).
    """
    if axis is not None:
        return hinge_turn(R, parent, axis, [u], [w], ops, max_angle)
    turn = quat_between(u, w, ops)
    if max_angle is not None:
        turn = cap_angle(turn, max_angle, ops)
    return _unit(quat_mul(quat_mul(quat_conjugate(parent), quat_mul(turn, parent)), R), ops)


def hinge_turn(R: Quat, parent: Quat, axis: Vec, us: list[Vec], ws: list[Vec], ops: Ops,
               max_angle: float | None = None) -> Quat:
    r"""Turn a hinge (``axis`` :math:`\hat a` in the parent frame, world
    :math:`a = Q_{i-1}\hat a`) by the angle that best turns the world offsets ``us`` (from its
    pivot) onto ``ws``, least squares: :math:`\mathrm{atan2}(\sum_k a\cdot(u_k\times w_k),\
    \sum_k u_k\cdot w_k - (u_k\cdot a)(w_k\cdot a))`; for one pair the angle between their
    projections on the hinge's plane. :math:`R \leftarrow \exp(\theta\hat a) R`, renormalised;
    ``max_angle`` caps :math:`|\theta|`."""
    a = quat_rotate(parent, axis)
    num = den = 0.0
    for u, w in zip(us, ws, strict=True):
        num = num + dot(a, cross(u, w))
        den = den + dot(u, w) - dot(u, a) * dot(w, a)
    theta = ops.atan2(num, den)
    if max_angle is not None:
        theta = ops.minimum(ops.maximum(theta, -max_angle), max_angle)
    return _unit(quat_mul(quat_from_axis_angle(axis, theta, ops), R), ops)


def _unit(q: Quat, ops: Ops) -> Quat:
    """``q`` renormalised: CCD and FABRIK turn every joint hundreds of times, and rounding must
    not build up in its length."""
    qw, qx, qy, qz = q
    inv = 1.0 / ops.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    return (qw * inv, qx * inv, qy * inv, qz * inv)
