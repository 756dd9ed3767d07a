r"""The fast path: one serial chain from the fixed joint to one position target.

This is the common case (a notebook's arm, a benchmark chain, a leg from the hips): the path
is ``node 0 -> node 1 -> ... -> node n-1`` (the effector), every node's local rotation
:math:`R_i` is a hinge, a ball or fixed, and there is one position target. The lecture's
forward kinematics on it,

.. math::
    Q_i = Q_{i-1} R_i,\qquad p_i = p_{i-1} + Q_{i-1}\, l_i \qquad (Q_{-1} = \text{base}),

is written here on quaternions and 3-vectors held as tuples of *components*: a vector is
``(x, y, z)``, a quaternion ``(w, x, y, z)``, and each component is either a Python float (one
problem: plain float arithmetic costs ~50 ns where a numpy call on a tiny array costs ~1 µs)
or an ndarray of shape ``(B,)`` (a batch: every line is then one vectorised, contiguous
operation over all ``B`` problems). The same code runs both ways; ``ops``
(:data:`~course.ik._ops.FLOATS` or :data:`~course.ik._ops.ARRAYS`) supplies the handful of
functions that differ (``sqrt``, ``where``, ...).

The solvers here are the same methods as :mod:`course.ik.jacobian` and :mod:`course.ik.fabrik`
on the general :class:`~course.ik._chains.Problem` (tests check both give the same answer):
the Jacobian columns are :math:`a_i\times(e - r_i)` (hinge, world axis
:math:`a_i = Q_{i-1}\hat a_i`) or the three world axes :math:`x, y, z` crossed with
:math:`e - r_i` (ball), and a hinge step is :math:`R_i \leftarrow \exp(\delta\,\hat a_i) R_i`,
a ball step :math:`R_i \leftarrow \exp(Q_{i-1}^{-1}\delta) R_i`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property, reduce
from typing import Any

import numpy as np

from ._chains import bend_increment, outside_shell
from ._ops import FLOATS
from ._small import TINY
from .jacobian import lost_rank
from .result import History

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


def qmul(a: Quat, b: Quat) -> Quat:
    """Hamilton product :math:`a b` (rotate by ``b``, then ``a``)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def qconj(q: Quat) -> Quat:
    return (q[0], -q[1], -q[2], -q[3])


def qrot(q: Quat, v: Vec) -> Vec:
    r""":math:`q v q^*` as :math:`v + w t + u\times t`, :math:`t = 2u\times v`,
    :math:`u = (x, y, z)` (written out: this is the innermost operation)."""
    w, x, y, z = q
    vx, vy, vz = v
    tx, ty, tz = 2.0 * (y * vz - z * vy), 2.0 * (z * vx - x * vz), 2.0 * (x * vy - y * vx)
    return (vx + w * tx + y * tz - z * ty, vy + w * ty + z * tx - x * tz,
            vz + w * tz + x * ty - y * tx)


def units_like(qs: list[Quat], refs: list[Quat], ops: Any) -> list[Quat]:
    """The quaternions ``qs`` normalised, each with the sign of its ``refs`` entry (``q`` and
    ``-q`` are one rotation: keeping the starting quaternion's sign spares an animated solve
    its sign flips)."""
    sqrt, where, out = ops.sqrt, ops.where, []
    for (w, x, y, z), (rw, rx, ry, rz) in zip(qs, refs, strict=True):
        inv = 1.0 / sqrt(w * w + x * x + y * y + z * z)
        inv = where(w * rw + x * rx + y * ry + z * rz < 0, -inv, inv)
        out.append((w * inv, x * inv, y * inv, z * inv))
    return out


def axis_turn(axis: Vec, angle: Scalar, ops: Any) -> Quat:
    """Turn by ``angle`` about the unit ``axis`` (a constant)."""
    s = ops.sin(0.5 * angle)
    return (ops.cos(0.5 * angle), axis[0] * s, axis[1] * s, axis[2] * s)


def rotvec_turn(r: Vec, ops: Any) -> Quat:
    r""":math:`\exp(r)`: turn by :math:`\lVert r\rVert` about :math:`\hat r` (identity at 0)."""
    theta = ops.sqrt(dot(r, r))
    safe = ops.where(theta > 1e-8, theta, 1.0)
    k = ops.where(theta > 1e-8, ops.sin(0.5 * safe) / safe, 0.5)
    return (ops.cos(0.5 * theta), r[0] * k, r[1] * k, r[2] * k)


def arc_turn(u: Vec, v: Vec, ops: Any) -> Quat:
    r"""Shortest arc taking direction ``u`` onto ``v``: :math:`(\lVert u\rVert\lVert v\rVert +
    u\cdot v,\ u\times v)` normalised; a half turn about an axis perpendicular to ``u`` when
    they are opposite; the identity when either is shorter than ``TINY`` (as
    :func:`course.ik._small.arc_matrix`). The two special cases are rare, so they are only
    worked out when some problem needs them (FABRIK fits every bone with this)."""
    (ux, uy, uz), (vx, vy, vz) = u, v
    uu, vv = ux * ux + uy * uy + uz * uz, vx * vx + vy * vy + vz * vz
    nn = ops.sqrt(uu * vv)
    w, x, y, z = (nn + ux * vx + uy * vy + uz * vz, uy * vz - uz * vy, uz * vx - ux * vz,
                  ux * vy - uy * vx)
    opposite = w <= TINY * nn
    if ops.any(opposite):
        # Turn about u x (the coordinate axis of u's smallest component), as arc_matrix.
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


def cap_angle(q: Quat, cap: float, ops: Any) -> Quat:
    r"""``q`` with its rotation angle :math:`2\,\mathrm{atan2}(\lVert v\rVert, |w|)` capped at
    ``cap``, keeping its axis."""
    w, x, y, z = q
    s = ops.sqrt(x * x + y * y + z * z)
    over = 2.0 * ops.atan2(s, ops.abs(w)) > cap
    k = math.sin(0.5 * cap) / ops.where(s > TINY, s, 1.0)
    sign = ops.where(w < 0, -1.0, 1.0)
    return (ops.where(over, sign * math.cos(0.5 * cap), w), ops.where(over, x * k, x),
            ops.where(over, y * k, y), ops.where(over, z * k, z))


def limit(R: Quat, axis: Vec | None, lo: float, hi: float | None, ops: Any) -> Quat:
    r"""A local rotation projected into its limit: a hinge's angle
    :math:`\theta = \mathrm{atan2}(2w\,(v\cdot\hat a),\ w^2 - \lVert v\rVert^2)` clipped to
    ``[lo, hi]``; a ball's (``axis`` None) rotation angle capped at ``lo``."""
    if axis is None:
        return cap_angle(R, lo, ops)
    w, x, y, z = R
    theta = ops.atan2(2.0 * w * dot((x, y, z), axis), w * w - (x * x + y * y + z * z))
    return qmul(axis_turn(axis, ops.minimum(ops.maximum(theta, lo), hi) - theta, ops), R)


def aim(R: Quat, parent: Quat, axis: Vec | None, u: Vec, w: Vec, ops: Any,
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
    turn = arc_turn(u, w, ops)
    if max_angle is not None:
        turn = cap_angle(turn, max_angle, ops)
    return _unit(qmul(qmul(qconj(parent), qmul(turn, parent)), R), ops)


def hinge_turn(R: Quat, parent: Quat, axis: Vec, us: list[Vec], ws: list[Vec], ops: Any,
               max_angle: float | None = None) -> Quat:
    r"""Turn a hinge (``axis`` :math:`\hat a` in the parent frame, world
    :math:`a = Q_{i-1}\hat a`) by the angle that best turns the world offsets ``us`` (from its
    pivot) onto ``ws``, least squares: :math:`\mathrm{atan2}(\sum_k a\cdot(u_k\times w_k),\
    \sum_k u_k\cdot w_k - (u_k\cdot a)(w_k\cdot a))`; for one pair the angle between their
    projections on the hinge's plane. :math:`R \leftarrow \exp(\theta\hat a) R`, renormalised;
    ``max_angle`` caps :math:`|\theta|`."""
    a = qrot(parent, axis)
    num = den = 0.0
    for u, w in zip(us, ws, strict=True):
        num = num + dot(a, cross(u, w))
        den = den + dot(u, w) - dot(u, a) * dot(w, a)
    theta = ops.atan2(num, den)
    if max_angle is not None:
        theta = ops.minimum(ops.maximum(theta, -max_angle), max_angle)
    return _unit(qmul(axis_turn(axis, theta, ops), R), ops)


def _unit(q: Quat, ops: Any) -> Quat:
    """``q`` renormalised: CCD and FABRIK turn every joint hundreds of times, and rounding must
    not build up in its length."""
    qw, qx, qy, qz = q
    inv = 1.0 / ops.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    return (qw * inv, qx * inv, qy * inv, qz * inv)


# --------------------------------------------------------------------------- the chain
@dataclass(frozen=True)
class SerialChain:
    """A chain ``node 0 -> ... -> node n-1`` (the effector); see the module docstring."""

    joints: tuple[int, ...]  # skeleton joint of every node
    bones: tuple[Vec, ...]  # l_i: node i in node i-1's frame (zero for node 0)
    variables: tuple[int, ...]  # nodes whose local rotation the solve changes
    axes: tuple[Vec | None, ...]  # per variable: hinge axis (in the parent frame) or None
    reach: tuple[float, float, float]  # the effector's reach: far, near and rounding slack

    @cached_property  # fixed per chain, asked by every solve
    def free_balls(self) -> bool:
        """Every bone turns freely: nodes 0..n-2 are all ball joints (FABRIK's own case)."""
        return (self.variables == tuple(range(len(self.joints) - 1))
                and all(a is None for a in self.axes))

    def forward(self, R: list[Quat], base: Quat, p0: Vec) -> tuple[list[Quat], list[Vec]]:
        r"""Global orientations and positions, :math:`Q_i = Q_{i-1}R_i`,
        :math:`p_i = p_{i-1} + Q_{i-1} l_i`."""
        Q, P = [], []
        q, p = base, p0
        for i, (r, bone) in enumerate(zip(R, self.bones, strict=True)):
            if i:
                p = add(p, qrot(q, bone))
            q = qmul(q, r)
            Q.append(q)
            P.append(p)
        return Q, P

    def columns(self, Q: list[Quat], P: list[Vec], base: Quat) -> list[Vec]:
        r"""Jacobian columns :math:`a\times(e - r_i)`: the world hinge axis
        :math:`a = Q_{i-1}\hat a`, or the world x, y and z axes for a ball joint."""
        e, cols = P[-1], []
        for v, axis in zip(self.variables, self.axes, strict=True):
            rx, ry, rz = sub(e, P[v])
            if axis is None:
                cols += [(0.0, -rz, ry), (rz, 0.0, -rx), (-ry, rx, 0.0)]
            else:
                cols.append(cross(qrot(Q[v - 1] if v else base, axis), (rx, ry, rz)))
        return cols

    def step(self, R: list[Quat], Q: list[Quat], base: Quat, delta: list[Scalar],
             ops: Any) -> list[Quat]:
        r"""Turn the variables by ``delta`` (one entry per column): a hinge
        :math:`R \leftarrow \exp(\delta\hat a) R`, a ball by the world rotation vector
        :math:`\delta` applied to :math:`Q_i`, i.e. :math:`R \leftarrow
        \exp(Q_{i-1}^{-1}\delta) R`."""
        R, c = list(R), 0
        for v, axis in zip(self.variables, self.axes, strict=True):
            if axis is None:
                local = qrot(qconj(Q[v - 1] if v else base), tuple(delta[c:c + 3]))
                turn, c = rotvec_turn(local, ops), c + 3
            else:
                turn, c = axis_turn(axis, delta[c], ops), c + 1
            R[v] = qmul(turn, R[v])
        return R

    def limits(self, hinge_limits: np.ndarray, ball_limit: np.ndarray) -> list[tuple]:
        """Per variable with a limit, ``(node, axis, lo, hi)`` (hinge) or ``(node, None, cap,
        None)`` (ball), as floats: prepared once per solve for :meth:`project`."""
        out = []
        for i, (v, axis) in enumerate(zip(self.variables, self.axes, strict=True)):
            if axis is not None and np.isfinite(hinge_limits[i]).any():
                out.append((v, axis, float(hinge_limits[i, 0]), float(hinge_limits[i, 1])))
            elif axis is None and np.isfinite(ball_limit[i]):
                out.append((v, None, float(ball_limit[i]), None))
        return out

    def bend_if_straight(self, R: list[Quat], Q: list[Quat], P: list[Vec], base: Quat, p0: Vec,
                         target: Vec, tol: float, limits: list[tuple], ops: Any
                         ) -> tuple[list[Quat], list[Quat], list[Vec]]:
        """As :meth:`course.ik._chains.Problem.bend_if_straight`: ``R`` (with its ``Q`` and
        ``P``) bent off a straight chain whose target lies on its line, unreached and not
        beyond the stretched tip; unchanged (and cheap to check) otherwise."""
        root, tip = P[0], P[-1]
        axis = sub(tip, root)
        length = ops.sqrt(dot(axis, axis))
        u = scale(axis, 1.0 / ops.where(length > TINY, length, 1.0))
        rel = sub(target, root)
        off = cross(rel, u)
        need = ops.both(length > TINY, ops.sqrt(dot(off, off)) <= tol)
        if not ops.any(need):  # the usual case: the target is off the chain's line
            return R, Q, P
        far, _, slack = self.reach
        stretched = ops.both(length >= far - slack, dot(rel, u) >= length)
        need = ops.both(need, ops.both(ops.dist(tip, target) >= tol, ops.invert(stretched)))
        for p in P[1:-1]:
            off = cross(sub(p, root), u)
            need = ops.both(need, ops.sqrt(dot(off, off)) <= slack)
        if not ops.any(need):
            return R, Q, P
        hinge = np.array([a is not None for a in self.axes])
        delta = bend_increment(hinge, np.stack(np.broadcast_arrays(*u), -1).reshape(-1, 3))
        delta = np.where(np.reshape(need, (-1, 1)), delta, 0.0)
        R = self.step(R, Q, base, delta[0].tolist() if ops is FLOATS else list(delta.T), ops)
        if limits:
            R = self.project(R, limits, ops)
        return (R, *self.forward(R, base, p0))

    def stretch_if_far(self, R: list[Quat], base: Quat, p0: Vec, target: Vec, tol: float,
                       ops: Any) -> list[Quat]:
        """As :meth:`course.ik._chains.Problem.stretch_if_far`, for a chain of free balls:
        ``R`` stretched straight at a target at or beyond the reach (:func:`fit_chain`);
        unchanged where the target is nearer or already reached."""
        far = self.reach[0]
        to_t = sub(target, p0)
        d = ops.sqrt(dot(to_t, to_t))
        need = ops.both(d >= far - tol, d > 0.0)
        if not ops.any(need):  # the usual case: the target well inside the reach
            return R
        Q, P = self.forward(R, base, p0)
        need = ops.both(need, ops.dist(P[-1], target) >= tol)
        u = scale(to_t, 1.0 / ops.where(need, d, 1.0))
        straight, reach = [p0], 0.0
        for bone in self.bones[1:]:
            reach += math.sqrt(dot(bone, bone))
            straight.append(add(p0, scale(u, reach)))
        return ops.select(need, fit_chain(self, R, Q, P, base, straight, ops)[0], R)

    def unreachable(self, target: Vec, p0: Vec, ops: Any) -> Any:
        """Whether the target lies outside the shell the effector can reach from ``p0``."""
        e = sub(target, p0)
        return outside_shell(ops.sqrt(dot(e, e)), *self.reach)

    @staticmethod
    def project(R: list[Quat], limits: list[tuple], ops: Any) -> list[Quat]:
        """Variables projected into their :meth:`limits` (:func:`limit`)."""
        R = list(R)
        for v, axis, lo, hi in limits:
            R[v] = limit(R[v], axis, lo, hi, ops)
        return R


def serial_chain(model: Any) -> SerialChain | None:
    """The :class:`SerialChain` of a :class:`~course.ik._chains.ChainModel`, or None if its
    paths are not one chain from the fixed joint (parent frame held) to a position target."""
    n = model.n_nodes
    if (not model.anchor_parent or len(model.rot_effectors) or len(model.effectors) != 1
            or model.effectors[0] != n - 1 or np.any(model.parent[1:] != np.arange(n - 1))):
        return None
    axes = np.zeros((len(model.var_nodes), 3))
    first = np.searchsorted(model.col_var, np.arange(len(model.var_nodes)))
    axes[model.hinge] = model.col_axis[first[model.hinge]]
    return SerialChain(
        joints=tuple(int(j) for j in model.joints),
        bones=tuple(tuple(float(c) for c in b) for b in model.bone),
        variables=tuple(int(v) for v in model.var_nodes),
        axes=tuple(tuple(float(c) for c in a) if h else None
                   for a, h in zip(axes, model.hinge, strict=True)),
        reach=(float(model.reach_far[0]), float(model.reach_near[0]), model.reach_slack),
    )


# --------------------------------------------------------------------------- Jacobian methods
def increment(cols: list[Vec], e: Vec, method: str, inv_w2: np.ndarray, damping: float,
              rcond: float, ops: Any) -> list[Scalar]:
    r"""The joint increment of a Jacobian method, :math:`\Delta\theta = W^{-2}J^T z`.

    With :math:`A = JW^{-2}J^T` (3x3, built column by column), the three methods differ only
    in :math:`z`: DLS :math:`z = (A + \lambda^2 I)^{-1}\Delta e` (closed form, by cofactors),
    pseudo-inverse :math:`z = A^+\Delta e` (eigenvalues below :math:`\text{rcond}^2` times the
    largest dropped, the same cut as :math:`\sigma < \text{rcond}\,\sigma_{max}` on
    :math:`J`), transpose :math:`z = \alpha\Delta e` with Buss's
    :math:`\alpha = \langle\Delta e, A\Delta e\rangle / \lVert A\Delta e\rVert^2`.
    """
    A = gram(cols, inv_w2)
    if method == "dls":
        z = _solve_sym(A, e, damping * damping, ops)
    elif method == "pseudo_inverse" and ops.all(_well_conditioned(A, rcond)):
        z = _solve_sym(A, e, 0.0, ops)  # no eigenvalue below the cut: A^+ = A^-1
    elif method == "pseudo_inverse":
        M = ops.symmetric(A)
        lam, V = np.linalg.eigh(M)
        keep = lam > rcond * rcond * lam[..., -1:]
        inv = np.where(keep, 1.0 / np.where(keep, lam, 1.0), 0.0)
        y = np.einsum("...ji,...j->...i", V, np.stack(np.broadcast_arrays(*e), -1))
        z = ops.vector(np.einsum("...ij,...j->...i", V, inv * y))
    else:
        a00, a01, a02, a11, a12, a22 = A
        Ae = (a00 * e[0] + a01 * e[1] + a02 * e[2], a01 * e[0] + a11 * e[1] + a12 * e[2],
              a02 * e[0] + a12 * e[1] + a22 * e[2])
        den = dot(Ae, Ae)
        z = scale(e, dot(e, Ae) / ops.where(den > 0, den, 1.0))
    return [dot(c, z) * iw for c, iw in zip(cols, inv_w2, strict=True)]


def gram(cols: list[Vec], inv_w2: np.ndarray) -> tuple:
    r""":math:`A = J W^{-2} J^T = \sum_c J_c J_c^T / w_c^2` as its six entries
    ``(a00, a01, a02, a11, a12, a22)``."""
    a00 = a01 = a02 = a11 = a12 = a22 = 0.0
    for (x, y, z), iw in zip(cols, inv_w2, strict=True):
        wx, wy, wz = x * iw, y * iw, z * iw
        a00, a01, a02 = a00 + wx * x, a01 + wx * y, a02 + wx * z
        a11, a12, a22 = a11 + wy * y, a12 + wy * z, a22 + wz * z
    return a00, a01, a02, a11, a12, a22


def _well_conditioned(A: tuple, rcond: float) -> Any:
    r"""Whether no eigenvalue of the PSD ``A`` is below :math:`\text{rcond}^2\lambda_{max}`,
    sufficient test: :math:`\lambda_{min}/\lambda_{max} \ge \det A / (\mathrm{tr} A)^3`."""
    a00, a01, a02, a11, a12, a22 = A
    det = (a00 * (a11 * a22 - a12 * a12) - a01 * (a01 * a22 - a02 * a12)
           + a02 * (a01 * a12 - a02 * a11))
    tr = a00 + a11 + a22
    return det > rcond * rcond * tr * tr * tr


def _solve_sym(A: tuple, e: Vec, lam2: float, ops: Any) -> Vec:
    r""":math:`(A + \lambda^2 I)^{-1} e` for symmetric 3x3 ``A``, by the adjugate."""
    a00, a01, a02, a11, a12, a22 = A
    a00, a11, a22 = a00 + lam2, a11 + lam2, a22 + lam2
    c00, c01, c02 = a11 * a22 - a12 * a12, a02 * a12 - a01 * a22, a01 * a12 - a02 * a11
    c11, c12, c22 = a00 * a22 - a02 * a02, a01 * a02 - a00 * a12, a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    inv = 1.0 / ops.where(ops.abs(det) > 1e-300, det, 1e-300)
    x, y, z = e
    return ((c00 * x + c01 * y + c02 * z) * inv, (c01 * x + c11 * y + c12 * z) * inv,
            (c02 * x + c12 * y + c22 * z) * inv)


def solve_jacobian(
    chain: SerialChain, R: list[Quat], base: Quat, p0: Vec, target: Vec, method: str,
    tol: float, max_iter: int, *, inv_w2: np.ndarray, damping: float, rcond: float,
    max_step: float, limits: list[tuple], record: bool, ops: Any,
) -> tuple[list[Quat], list[Vec], History, list[list[Quat]]]:
    """Iterate a Jacobian method, as :func:`course.ik.jacobian.solve_problem` does on the
    general model: capped steps (``max_step``), backtracking (a step that raises the error is
    undone and the next one halved), the shared :class:`History` bookkeeping.

    Returns
    -------
    R : final local rotations of the nodes
    P : their positions (forward kinematics)
    history : History
    frames : the local rotations before the first and after every iteration (``record``)
    """
    Q, P = chain.forward(R, base, p0)
    R, Q, P = chain.bend_if_straight(R, Q, P, base, p0, target, tol, limits, ops)
    e = sub(target, P[-1])
    err = ops.sqrt(dot(e, e))
    history = History(err, tol, max_iter, ops=ops)
    frames = [R] if record else []
    step_scale = 1.0
    while ops.any(history.active) and chain.variables:
        delta = increment(chain.columns(Q, P, base), e, method, inv_w2, damping, rcond, ops)
        big = reduce(ops.maximum, (ops.abs(d) for d in delta))
        k = ops.minimum(1.0, max_step / ops.maximum(big, 1e-300)) * step_scale
        k = k * history.active
        trial = chain.step(R, Q, base, [d * k for d in delta], ops)
        if limits:
            trial = chain.project(trial, limits, ops)
        Q_t, P_t = chain.forward(trial, base, p0)
        e_t = sub(target, P_t[-1])
        err_t = ops.sqrt(dot(e_t, e_t))
        worse = err_t > err
        step_scale = ops.where(worse, 0.5 * step_scale, ops.minimum(1.0, 2.0 * step_scale))
        R, Q, P, e, err = ops.select(worse, (R, Q, P, e, err), (trial, Q_t, P_t, e_t, err_t))
        history.update(err)
        if record:
            frames.append(R)
    if not ops.all(history.converged):
        cols = np.array([np.broadcast_arrays(*c) for c in chain.columns(Q, P, base)])
        history.singular = ops.flag(lost_rank(np.moveaxis(cols.reshape(len(cols), 3, -1), -1, 0),
                                              rcond))
    return R, P, history, frames


# --------------------------------------------------------------------------- FABRIK
def follow(P: list[Vec], first: int, step: int, d: list[Scalar], rest: list[Vec],
           ops: Any) -> list[Vec]:
    r"""Pull the points after ``P[first]`` (``step = +1``: towards the tip, ``-1``: towards the
    root) one by one back to their bone lengths:
    :math:`p_j \leftarrow p_i + d\,\widehat{(p_j - p_i)}`, with :math:`p_i` the point just
    placed and :math:`d` the bone between them; where the two coincide, along that bone's unit
    ``rest`` direction (root to tip), turned the way the pass goes (``step`` times it).
    FABRIK spends its time here, so the update is written out in components, once for both
    directions."""
    P = list(P)
    sqrt, all_, where = ops.sqrt, ops.all, ops.where
    fx, fy, fz = P[first]
    j = first + step
    bone = first if step > 0 else first - 1
    for _ in range(first if step < 0 else len(P) - 1 - first):
        tx, ty, tz = P[j]
        dx, dy, dz = tx - fx, ty - fy, tz - fz
        n = sqrt(dx * dx + dy * dy + dz * dz)
        if not all_(n >= TINY):  # coinciding points: the bone's rest direction
            ok = n >= TINY
            gx, gy, gz = scale(rest[bone], step)
            dx, dy, dz, n = where(ok, dx, gx), where(ok, dy, gy), where(ok, dz, gz), \
                where(ok, n, 1.0)
        k = d[bone] / n
        fx, fy, fz = P[j] = (fx + dx * k, fy + dy * k, fz + dz * k)
        j += step
        bone += step
    return P


def reach_forward(P: list[Vec], target: Vec, d: list[Scalar], rest: list[Vec],
                  ops: Any) -> list[Vec]:
    r"""FABRIK's forward reaching: :math:`p_n \leftarrow t`, then
    :math:`p_i \leftarrow p_{i+1} + d_i\,\widehat{(p_i - p_{i+1})}` down to the root.
    ``rest`` are the unit bone directions (root to tip), reversed where two joints coincide."""
    P = list(P)
    P[-1] = target
    return follow(P, len(P) - 1, -1, d, rest, ops)


def fabrik_pass(P: list[Vec], target: Vec, root: Vec, d: list[Scalar], rest: list[Vec],
                ops: Any) -> list[Vec]:
    r"""One FABRIK iteration: forward reaching (:func:`reach_forward`), then backward
    reaching (:math:`p_0 \leftarrow b`, then :math:`p_{i+1} \leftarrow p_i +
    d_i\,\widehat{(p_{i+1} - p_i)}`); ``rest`` are the unit bone directions (root to tip)
    to use where two joints coincide."""
    P = reach_forward(P, target, d, rest, ops)
    P[0] = root
    return follow(P, 0, 1, d, rest, ops)


def bone_directions(P: list[Vec], ops: Any) -> tuple[list[Scalar], list[Vec]]:
    r"""Bone lengths :math:`d_i = \lVert p_{i+1} - p_i\rVert` and unit directions of chain
    points ``P`` (+y for a zero bone)."""
    d, rest = [], []
    for a, b in zip(P[:-1], P[1:], strict=True):
        x, y, z = sub(b, a)
        length = ops.sqrt(x * x + y * y + z * z)
        ok = length > TINY
        if ops.all(ok):
            inv = 1.0 / length
            rest.append((x * inv, y * inv, z * inv))
        else:
            inv = 1.0 / ops.where(ok, length, 1.0)
            rest.append((ops.where(ok, x * inv, 0.0), ops.where(ok, y * inv, 1.0),
                         ops.where(ok, z * inv, 0.0)))
        d.append(length)
    return d, rest


def fabrik_points(P: list[Vec], target: Vec, tol: float, max_iter: int, ops: Any,
                  frames: list | None = None, errors: list | None = None
                  ) -> tuple[list[Vec], Any, Any]:
    r"""FABRIK on chain points ``P`` (``P[0]`` fixed; bone lengths taken from them).

    A target beyond the reach :math:`\sum d_i` is answered in one pass, the chain stretched
    straight at it. A batch iterates only its problems still running. ``frames`` and
    ``errors``, if given, receive the points and the effector errors (copies, a float or
    (B,)) after every iteration.

    Returns
    -------
    P : the final points
    iterations, error : per problem
    """
    d, rest = bone_directions(P, ops)
    root = P[0]
    to_t = sub(target, root)
    dist = ops.sqrt(dot(to_t, to_t))
    far = dist > sum(d)
    if ops.any(far):  # unreachable: stretched straight at the target
        u, reach, straight = scale(to_t, 1.0 / ops.where(dist > TINY, dist, 1.0)), 0.0, [root]
        for length in d:
            reach = reach + length
            straight.append(add(root, scale(u, reach)))
        P = ops.select(far, straight, P)
    err = ops.dist(P[-1], target)
    its = ops.where(far, 1, 0)
    active = ops.both(ops.invert(far), err >= tol)
    for _ in range(max_iter):
        if not ops.any(active):
            break
        if ops.all(active):  # every problem still running
            P = fabrik_pass(P, target, root, d, rest, ops)
            err = ops.dist(P[-1], target)
            its = its + 1
            active = err >= tol
        else:  # a batch, some problems done: iterate only those still running
            idx = np.flatnonzero(active)
            Q, t = fabrik_pass(*ops.take((P, target, root, d, rest), idx), ops), \
                ops.take(target, idx)
            err_q = ops.dist(Q[-1], t)
            P = ops.put(P, idx, Q)
            err = ops.put(err, idx, err_q)
            its = ops.put(its, idx, ops.take(its, idx) + 1)
            active = ops.put(active, idx, err_q >= tol)
        if frames is not None:
            frames.append(ops.copy(P))
        if errors is not None:
            errors.append(ops.copy(err))
    return P, its, err


def fit_chain(chain: SerialChain, R: list[Quat], Q: list[Quat], P_old: list[Vec], base: Quat,
              P_new: list[Vec], ops: Any) -> tuple[list[Quat], list[Vec]]:
    r"""Local rotations that put a ball-joint chain on the points ``P_new`` (same bones): each
    node's global orientation turned by the shortest arc from its old bone direction to the
    new one, :math:`Q_i' = \mathrm{arc}(p_{i+1} - p_i,\ p'_{i+1} - p'_i)\,Q_i` (so every bone
    keeps its twist), then :math:`R_i' = Q_{i-1}'^{-1} Q_i'`; ``Q`` and ``P_old`` are the
    :math:`Q_i` and :math:`p_i` of ``R``. Also returns the positions of the new pose by
    forward kinematics on the way, :math:`p'_{i+1} = p'_i + Q_i' l_{i+1}` from the root
    (equal to ``P_new`` up to rounding: the residual they give is the returned pose's own)."""
    R, parent, p = list(R), base, P_new[0]
    P = [p]
    for i in range(len(R) - 1):
        bone = chain.bones[i + 1]
        turn = arc_turn(sub(P_old[i + 1], P_old[i]), sub(P_new[i + 1], P_new[i]), ops)
        q = qmul(turn, Q[i])
        R[i] = qmul(qconj(parent), q)
        parent = q
        p = add(p, qrot(q, bone))
        P.append(p)
    return R, P


def solve_fabrik(chain: SerialChain, R: list[Quat], base: Quat, p0: Vec, target: Vec, tol: float,
                 max_iter: int, record: bool, ops: Any
                 ) -> tuple[list[Quat], list[Vec], History, list]:
    """FABRIK on a chain of free ball joints: iterate on positions alone (:func:`fabrik_points`),
    then fit the rotations once (:func:`fit_chain`; exact, the points keep the bones).
    ``record`` fits every iteration's points too. Returns the final local rotations, their
    positions (forward kinematics), the history and the recorded rotations."""
    Q, P = chain.forward(R, base, p0)
    R, Q, P = chain.bend_if_straight(R, Q, P, base, p0, target, tol, [], ops)
    e = sub(target, P[-1])
    history = History(ops.sqrt(dot(e, e)), tol, max_iter, ops=ops)
    points: list | None = [] if record else None
    errors: list = []
    P_new, its, _ = fabrik_points(ops.copy(P), target, tol, max_iter, ops, points, errors)
    if record and len(points) < np.max(its):  # a stretch: answered before the loop
        points.append(P_new)
    fitted = [fit_chain(chain, R, Q, P, base, f, ops) for f in (points if record else [P_new])]
    # Residuals of the fitted poses (honest: what the returned rotations reach); without a
    # record, the points' errors stand for the iterations in between (the fit is exact).
    if not record:
        history.residuals += errors[:-1]
    for _, P in fitted if record else fitted[-1:]:
        history.residuals.append(ops.dist(target, P[-1]))
    history.iterations = its
    history.active = ops.full(its, False)
    R_new, P = fitted[-1]
    return R_new, P, history, [R] + [f for f, _ in fitted] if record else []


def solve_fabrik_joints(chain: SerialChain, R: list[Quat], base: Quat, p0: Vec, target: Vec,
                        tol: float, max_iter: int, limits: list[tuple], record: bool,
                        ops: Any) -> tuple[list[Quat], list[Vec], History, list]:
    r"""FABRIK with joint constraints (hinges, limits): forward reaching on the points
    (:func:`reach_forward`), then the backward pass in joint space, root to tip, with the
    parent placed (:math:`Q_{i-1}`, :math:`p_i` by forward kinematics). A ball joint turns its
    bone :math:`Q_{i-1}R_i l_{i+1}` onto the reached point :math:`p'_{i+1}` (:func:`aim`). A
    hinge cannot point its bone at a point off its plane; it turns about its axis by the angle
    that brings the whole chain below it closest to the reached points
    :math:`p'_{i+1}, \dots, p'_n` (:func:`hinge_turn`, least squares): with the next bone
    alone a chain of hinges about different axes stalls far from the target. Each joint is
    then projected into its limit. Every iteration ends on a real pose, so its residual is
    honest.
    """
    n = len(chain.bones)
    axis_of = dict(zip(chain.variables, chain.axes, strict=True))
    limits_of = {v: [lim for lim in limits if lim[0] == v] for v in chain.variables}
    Q, P = chain.forward(R, base, p0)
    R, _, P = chain.bend_if_straight(R, Q, P, base, p0, target, tol, limits, ops)
    d, rest = bone_directions(P, ops)
    e = sub(target, P[-1])
    history = History(ops.sqrt(dot(e, e)), tol, max_iter, ops=ops)
    frames = [R] if record else []
    while ops.any(history.active) and chain.variables:
        reached = reach_forward(P, target, d, rest, ops)
        new, q, p, P_new = list(R), base, p0, []
        for i in range(n):  # backward reaching: forward kinematics, aiming every joint
            if i:
                p = add(p, qrot(q, chain.bones[i]))
            P_new.append(p)
            if i in axis_of and axis_of[i] is None:  # a ball: its bone at the reached point
                u = qrot(qmul(q, new[i]), chain.bones[i + 1])
                new[i] = aim(new[i], q, None, u, sub(reached[i + 1], p), ops)
            elif i in axis_of:  # a hinge: the chain below it as close as it can to its points
                qj, pj, us, ws = qmul(q, new[i]), p, [], []
                for j in range(i + 1, n):
                    pj = add(pj, qrot(qj, chain.bones[j]))
                    qj = qmul(qj, new[j])
                    us.append(sub(pj, p))
                    ws.append(sub(reached[j], p))
                new[i] = hinge_turn(new[i], q, axis_of[i], us, ws, ops)
            if i in axis_of:
                new = chain.project(new, limits_of[i], ops)
            q = qmul(q, new[i])
        e_new = sub(target, P_new[-1])
        R, P, e = ops.select(history.active, (new, P_new, e_new), (R, P, e))
        history.update(ops.sqrt(dot(e, e)))
        if record:
            frames.append(R)
    return R, P, history, frames


# --------------------------------------------------------------------------- CCD
def solve_ccd(chain: SerialChain, R: list[Quat], base: Quat, p0: Vec, target: Vec, tol: float,
              max_iter: int, *, tip_to_root: bool, max_angle: float | None,
              limits: list[tuple], record: bool, ops: Any
              ) -> tuple[list[Quat], list[Vec], History, list]:
    r"""CCD sweeps, as :func:`course.ik.ccd.solve_problem` on the general model: every joint
    in turn (tip to root, or root to tip) turns the effector direction :math:`e - r_i` towards
    :math:`t - r_i` (:func:`aim`), is projected into its limit, and the chain below it turns
    with it: :math:`p_j \leftarrow r_i + q\,(p_j - r_i)`, :math:`Q_j \leftarrow q\,Q_j` with
    the world turn :math:`q = Q_i' Q_i^{-1}`.
    """
    n = len(chain.bones)
    axis_of = dict(zip(chain.variables, chain.axes, strict=True))
    limits_of = {v: [lim for lim in limits if lim[0] == v] for v in chain.variables}
    order = chain.variables[::-1] if tip_to_root else chain.variables
    Q, P = chain.forward(R, base, p0)
    R, Q, P = chain.bend_if_straight(R, Q, P, base, p0, target, tol, limits, ops)
    e = sub(target, P[-1])
    history = History(ops.sqrt(dot(e, e)), tol, max_iter, ops=ops)
    frames = [R] if record else []
    while ops.any(history.active) and chain.variables:
        new, Q, P = list(R), list(Q), list(P)
        for v in order:
            parent, pivot = (Q[v - 1] if v else base), P[v]
            new[v] = aim(new[v], parent, axis_of[v], sub(P[-1], pivot), sub(target, pivot),
                         ops, max_angle)
            new = chain.project(new, limits_of[v], ops)
            Qv = qmul(parent, new[v])
            turn = qmul(Qv, qconj(Q[v]))
            # Tip to root, the joints still to visit lie above v: only the effector matters.
            for j in range(n - 1, n) if tip_to_root else range(v + 1, n):
                P[j] = add(pivot, qrot(turn, sub(P[j], pivot)))
                Q[j] = qmul(turn, Q[j])
            Q[v] = Qv
        R = ops.select(history.active, new, R)
        Q, P = chain.forward(R, base, p0)
        e = sub(target, P[-1])
        history.update(ops.sqrt(dot(e, e)))
        if record:
            frames.append(R)
    return R, P, history, frames
