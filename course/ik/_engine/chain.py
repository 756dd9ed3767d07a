r"""The fast path's kinematics: one serial chain from the fixed joint to one position target.

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
(:data:`~course.ik._engine.ops.FLOATS` or :data:`~course.ik._engine.ops.ARRAYS`) supplies the
handful of functions that differ (``sqrt``, ``where``, ...). The kernels are named as the
checked functions of :mod:`course.rotations` they mirror (``quat_mul``, ``quat_between``, ...).

The Jacobian columns are :math:`a_i\times(e - r_i)` (hinge, world axis
:math:`a_i = Q_{i-1}\hat a_i`) or the three world axes :math:`x, y, z` crossed with
:math:`e - r_i` (ball), and a hinge step is :math:`R_i \leftarrow \exp(\delta\,\hat a_i) R_i`,
a ball step :math:`R_i \leftarrow \exp(Q_{i-1}^{-1}\delta) R_i`, as on the general
:class:`~course.ik._engine.tree.Problem`. The solvers are in
:mod:`course.ik._engine.chain_solvers`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from course.rotations._kernels import TINY

from .components import (
    Limit,
    Quat,
    Scalar,
    Vec,
    add,
    aim,
    cross,
    dot,
    limit,
    quat_between,
    quat_conjugate,
    quat_from_axis_angle,
    quat_from_rotvec,
    quat_mul,
    quat_rotate,
    scale,
    sub,
)
from .ops import FLOATS, Flag, Ops
from .reach import REACH_START, reach_points
from .tree import TreeModel, bend_direction, bend_increment, outside_shell

Pose = list[Quat]  # the local rotations of a chain's nodes, root to tip
Points = list[Vec]  # a chain's node positions, root to tip
ChainLimits = list[tuple[int, Limit]]  # (node, limit) of every limited variable


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

    def forward(self, R: Pose, base: Quat, p0: Vec) -> tuple[list[Quat], Points]:
        r"""Global orientations and positions, :math:`Q_i = Q_{i-1}R_i`,
        :math:`p_i = p_{i-1} + Q_{i-1} l_i`."""
        Q: list[Quat] = []
        P: Points = []
        q, p = base, p0
        for i, (r, bone) in enumerate(zip(R, self.bones, strict=True)):
            if i:
                p = add(p, quat_rotate(q, bone))
            q = quat_mul(q, r)
            Q.append(q)
            P.append(p)
        return Q, P

    def columns(self, Q: list[Quat], P: Points, base: Quat) -> list[Vec]:
        r"""Jacobian columns :math:`a\times(e - r_i)`: the world hinge axis
        :math:`a = Q_{i-1}\hat a`, or the world x, y and z axes for a ball joint."""
        e = P[-1]
        cols: list[Vec] = []
        for v, axis in zip(self.variables, self.axes, strict=True):
            rx, ry, rz = sub(e, P[v])
            if axis is None:
                cols += [(0.0, -rz, ry), (rz, 0.0, -rx), (-ry, rx, 0.0)]
            else:
                cols.append(cross(quat_rotate(Q[v - 1] if v else base, axis), (rx, ry, rz)))
        return cols

    def step(self, R: Pose, Q: list[Quat], base: Quat, delta: list[Scalar], ops: Ops) -> Pose:
        r"""Turn the variables by ``delta`` (one entry per column): a hinge
        :math:`R \leftarrow \exp(\delta\hat a) R`, a ball by the world rotation vector
        :math:`\delta` applied to :math:`Q_i`, i.e. :math:`R \leftarrow
        \exp(Q_{i-1}^{-1}\delta) R`."""
        R, c = list(R), 0
        for v, axis in zip(self.variables, self.axes, strict=True):
            if axis is None:
                dx, dy, dz = delta[c:c + 3]
                local = quat_rotate(quat_conjugate(Q[v - 1] if v else base), (dx, dy, dz))
                turn, c = quat_from_rotvec(local, ops), c + 3
            else:
                turn, c = quat_from_axis_angle(axis, delta[c], ops), c + 1
            R[v] = quat_mul(turn, R[v])
        return R

    def limits(self, limits: tuple[Limit | None, ...]) -> ChainLimits:
        """``(node, limit)`` of every variable with a limit (``limits``: one entry per
        variable, None when free), for :meth:`project`."""
        return [(v, lim) for v, lim in zip(self.variables, limits, strict=True) if lim]

    def bend_if_straight(self, R: Pose, Q: list[Quat], P: Points, base: Quat, p0: Vec,
                         target: Vec, tol: float, limits: ChainLimits, ops: Ops
                         ) -> tuple[Pose, list[Quat], Points]:
        """As :meth:`course.ik._engine.tree.Problem.bend_if_straight` (the same test,
        :func:`~course.ik._engine.tree.bend_direction`): ``R`` (with its ``Q`` and ``P``) bent
        off a straight chain whose target lies on its line, unreached and not beyond the
        stretched tip; unchanged (and cheap to check) otherwise."""
        root, tip = P[0], P[-1]
        axis = sub(tip, root)
        length = ops.sqrt(dot(axis, axis))
        u = scale(axis, 1.0 / ops.where(length > TINY, length, 1.0))
        rel = sub(target, root)
        off = cross(rel, u)
        need = ops.both(length > TINY, ops.sqrt(dot(off, off)) <= tol)
        if not ops.any(need):  # the usual case: the target is off the chain's line
            return R, Q, P
        # Maybe (the pre-test above is cheap in floats): the engines' shared test, on arrays.
        B, n = np.size(length), len(P)
        far, _, slack = self.reach
        bend = bend_direction(ops.stack(P, B).reshape(B, n, 3), np.array([n - 1]),
                              np.ones((1, n), bool), ops.stack([target], B).reshape(B, 1, 3),
                              np.array([far]), slack, tol)
        if bend is None:
            return R, Q, P
        direction, need = bend
        hinge = np.array([a is not None for a in self.axes])
        delta = np.where(need[:, None], bend_increment(hinge, direction), 0.0)
        R = self.step(R, Q, base, delta[0].tolist() if ops is FLOATS else list(delta.T), ops)
        if limits:
            R = self.project(R, limits, ops)
        return (R, *self.forward(R, base, p0))

    @cached_property
    def bendable(self) -> bool:
        """The reach-aware start applies (:mod:`~course.ik._engine.reach`): every bone turns
        (nodes 0..n-2 are all variables), all of them ball joints or all hinges about one
        axis (which then stays one world axis, :attr:`bend_reach` in the plane across it)."""
        if self.variables != tuple(range(len(self.joints) - 1)):
            return False
        first = self.axes[0]
        return self.free_balls or first is not None and all(
            a is not None and math.sqrt(dot(cross(a, first), cross(a, first))) < 1e-9
            for a in self.axes)

    @cached_property
    def bend_reach(self) -> float:
        """The reach the reach-aware start measures against: the sum of the bones, for
        hinges of their parts across the common axis."""
        a = self.axes[0]
        if self.free_balls or a is None:
            return self.reach[0]
        return sum((math.sqrt(max(dot(b, b) - dot(b, a) ** 2, 0.0)) for b in self.bones[1:]),
                   start=0.0)

    def reach_start(self, R: Pose, base: Quat, p0: Vec, target: Vec, tol: float,
                    limits: ChainLimits, ops: Ops) -> tuple[Pose, Flag, Flag]:
        """As :meth:`course.ik._engine.tree.Problem.reach_start` (the same points,
        :func:`~course.ik._engine.reach.reach_points`): ``R`` put on the reach-aware start,
        which problems took it, and which are done (stretched, no limits: the start is the
        answer); ``R`` unchanged (and cheap to check) far from the reach. The caller checks
        :attr:`bendable`."""
        to_t = sub(target, p0)
        d = ops.sqrt(dot(to_t, to_t))  # at least the in-plane distance
        # A pre-test, a rounding below the line: reach_points decides, as on the tree engine.
        near = d >= (REACH_START - 1e-9) * self.bend_reach
        none = ops.both(near, False)
        if not ops.any(near):  # the usual case: the target well inside the reach
            return R, none, none
        # A batch works on its problems near the reach alone (a large one has few).
        rows = None if ops is FLOATS else np.flatnonzero(near)
        Rn, bn, pn, tn = (R, base, p0, target) if rows is None else ops.take(
            (R, base, p0, target), rows)
        Q, P = self.forward(Rn, bn, pn)
        B, n = np.size(P[0][0]), len(P)
        axis = self.axes[0]  # bendable: all hinges about this axis, or all balls (None)
        normal = None if axis is None else ops.stack([quat_rotate(bn, axis)], B)
        start = reach_points(ops.stack(P, B).reshape(B, n, 3), ops.stack([tn], B).reshape(B, 3),
                             None if normal is None else normal.reshape(B, 3), tol)
        if start is None:
            return R, none, none
        wanted, need, straight = start
        W = ([as_vec(w) for w in wanted[0].tolist()] if ops is FLOATS
             else [as_vec(np.ascontiguousarray(wanted[:, i].T)) for i in range(n)])
        placed = ops.select(ops.flag(need), self.place(Rn, bn, pn, W, limits, ops), Rn)
        done = ops.flag(straight & (not limits))
        if rows is None:
            return placed, ops.flag(need), done
        return (ops.put(ops.copy(R), rows, placed), ops.put(none.copy(), rows, need),
                ops.put(none.copy(), rows, done))

    def place(self, R: Pose, base: Quat, p0: Vec, wanted: Points, limits: ChainLimits,
              ops: Ops) -> Pose:
        """``R`` with every joint, root to tip, turned to point its bone at its ``wanted`` next
        point (:func:`aim`: a ball by the shortest arc, a hinge about its axis) and projected
        into its limit, as :meth:`course.ik._engine.tree.Problem.fit` places a chain (exact
        where the points keep the bones and the hinges' planes). Needs every node a variable
        (:attr:`bendable`)."""
        R, q, p = list(R), base, p0
        limits_of = {v: [lim for lim in limits if lim[0] == v] for v in self.variables}
        for i, axis in enumerate(self.axes):
            if i:
                p = add(p, quat_rotate(q, self.bones[i]))
            u = quat_rotate(quat_mul(q, R[i]), self.bones[i + 1])
            R[i] = aim(R[i], q, axis, u, sub(wanted[i + 1], p), ops)
            if limits_of[i]:
                R = self.project(R, limits_of[i], ops)
            q = quat_mul(q, R[i])
        return R

    def unreachable(self, target: Vec, p0: Vec, ops: Ops) -> Flag:
        """Whether the target lies outside the shell the effector can reach from ``p0``."""
        e = sub(target, p0)
        return outside_shell(ops.sqrt(dot(e, e)), *self.reach)

    @staticmethod
    def project(R: Pose, limits: ChainLimits, ops: Ops) -> Pose:
        """Variables projected into their :meth:`limits` (:func:`limit`)."""
        R = list(R)
        for v, lim in limits:
            R[v] = limit(R[v], lim, ops)
        return R


def serial_chain(model: TreeModel) -> SerialChain | None:
    """The :class:`SerialChain` of a :class:`~course.ik._engine.tree.TreeModel`, or None if its
    paths are not one chain from the fixed joint (parent frame held) to a position target."""
    n = model.n_nodes
    if (not model.anchor_parent or len(model.rot_effectors) or len(model.effectors) != 1
            or model.effectors[0] != n - 1 or np.any(model.parent[1:] != np.arange(n - 1))):
        return None
    return SerialChain(
        joints=tuple(int(j) for j in model.joints),
        bones=tuple(as_vec(b.tolist()) for b in model.bone),
        variables=tuple(int(v) for v in model.var_nodes),
        axes=tuple(as_vec(a.tolist()) if h else None
                   for a, h in zip(model.var_axes(), model.hinge, strict=True)),
        reach=(float(model.reach_far[0]), float(model.reach_near[0]), model.reach_slack),
    )


def as_vec(c: Iterable[Scalar]) -> Vec:
    """Three components as a vector (three floats, or three (B,) rows)."""
    x, y, z = c
    return x, y, z


def as_quat(c: Iterable[Scalar]) -> Quat:
    """Four components as a quaternion ``(w, x, y, z)`` (four floats, or four (B,) rows)."""
    w, x, y, z = c
    return w, x, y, z


def fit_chain(chain: SerialChain, R: Pose, Q: list[Quat], P_old: Points, base: Quat,
              P_new: Points, ops: Ops) -> tuple[Pose, list[Quat], Points]:
    r"""Local rotations that put a ball-joint chain on the points ``P_new`` (same bones): each
    node's global orientation turned by the shortest arc from its old bone direction to the
    new one, :math:`Q_i' = \mathrm{arc}(p_{i+1} - p_i,\ p'_{i+1} - p'_i)\,Q_i` (so every bone
    keeps its twist), then :math:`R_i' = Q_{i-1}'^{-1} Q_i'`; ``Q`` and ``P_old`` are the
    :math:`Q_i` and :math:`p_i` of ``R``. Also returns the new orientations :math:`Q_i'` (the
    effector's :math:`Q_{n-2}' R_{n-1}`) and the positions of the new pose by forward
    kinematics on the way, :math:`p'_{i+1} = p'_i + Q_i' l_{i+1}` from the root (equal to
    ``P_new`` up to rounding: the residual they give is the returned pose's own)."""
    R, parent, p = list(R), base, P_new[0]
    Q_new: list[Quat] = []
    P = [p]
    for i in range(len(R) - 1):
        bone = chain.bones[i + 1]
        turn = quat_between(sub(P_old[i + 1], P_old[i]), sub(P_new[i + 1], P_new[i]), ops)
        q = quat_mul(turn, Q[i])
        R[i] = quat_mul(quat_conjugate(parent), q)
        parent = q
        Q_new.append(q)
        p = add(p, quat_rotate(q, bone))
        P.append(p)
    Q_new.append(quat_mul(parent, R[-1]))
    return R, Q_new, P
