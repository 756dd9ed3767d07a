r"""The IK step kernels on *components* (a vector ``(x, y, z)``, a quaternion ``(w, x, y, z)``,
each component a Python float or an ndarray ``(B,)``; :mod:`course.rotations._kernels`):
the joint-limit projection :func:`limit` and the turn of one joint, :func:`aim` (CCD's step
at every joint, FABRIK's backward pass at every bone) and :func:`hinge_turn`. The serial-chain
engine (:mod:`.chain`, :mod:`.chain_solvers`) runs them as written; the tree engine uses
:func:`limit`. The rotation arithmetic is the one copy in
:mod:`course.rotations._kernels`, re-exported here under the names the chain code uses.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from course.rotations._kernels import Quat, Scalar, ScalarOps, Vec
from course.rotations._kernels import q_between as quat_between
from course.rotations._kernels import q_cap_angle as cap_angle
from course.rotations._kernels import q_clamp_swing_twist as clamp_swing_twist
from course.rotations._kernels import q_conjugate as quat_conjugate
from course.rotations._kernels import q_from_axis_angle as quat_from_axis_angle
from course.rotations._kernels import q_from_rotvec as quat_from_rotvec
from course.rotations._kernels import q_mul as quat_mul
from course.rotations._kernels import q_rotate as quat_rotate
from course.rotations._kernels import q_unit as quat_unit
from course.rotations._kernels import q_units_like as units_like
from course.rotations._kernels import v_add as add
from course.rotations._kernels import v_cross as cross
from course.rotations._kernels import v_dot as dot
from course.rotations._kernels import v_scale as scale
from course.rotations._kernels import v_sub as sub

Ops = ScalarOps

__all__ = [
    "Limit", "Ops", "Quat", "Scalar", "Vec", "add", "aim", "cap_angle", "clamp_swing_twist",
    "cross", "dot", "hinge_turn", "limit", "quat_between", "quat_conjugate",
    "quat_from_axis_angle", "quat_from_rotvec", "quat_mul", "quat_rotate", "quat_unit", "scale",
    "sub", "units_like",
]


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
    axis = lim.axis
    assert axis is not None, "a hinge or swing-twist limit has an axis"
    if lim.kind == "swing_twist":
        return clamp_swing_twist(R, axis, lim.cone, lim.lo, lim.hi, ops)
    w, x, y, z = R
    theta = ops.atan2(2.0 * w * dot((x, y, z), axis), w * w - (x * x + y * y + z * z))
    fix = ops.minimum(ops.maximum(theta, lim.lo), lim.hi) - theta
    return quat_mul(quat_from_axis_angle(axis, fix, ops), R)


def aim(R: Quat, parent: Quat, axis: Vec | None, u: Vec, w: Vec, ops: Ops,
        max_angle: float | None = None) -> Quat:
    r"""Turn a joint so that the world direction ``u`` (from its pivot) points along ``w``,
    the step CCD takes at every joint and FABRIK's backward pass at every bone.

    A hinge (``axis`` :math:`\hat a` in the parent frame, world :math:`a = Q_{i-1}\hat a`)
    turns by the angle between the projections of ``u`` and ``w`` on its plane,
    :math:`\mathrm{atan2}(a\cdot(u\times w),\ u\cdot w - (u\cdot a)(w\cdot a))`, so
    :math:`R \leftarrow \exp(\theta\hat a) R`; a ball joint by the shortest arc ``q`` from
    ``u`` to ``w``, a world turn, so :math:`R \leftarrow Q_{i-1}^{-1} q\, Q_{i-1} R`.
    ``max_angle`` caps the turn. The result is renormalised (:func:`quat_unit`).
    """
    if axis is not None:
        return hinge_turn(R, parent, axis, [u], [w], ops, max_angle)
    turn = quat_between(u, w, ops)
    if max_angle is not None:
        turn = cap_angle(turn, max_angle, ops)
    return quat_unit(quat_mul(quat_mul(quat_conjugate(parent), quat_mul(turn, parent)), R), ops)


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
    return quat_unit(quat_mul(quat_from_axis_angle(axis, theta, ops), R), ops)


