r"""The fast path's solvers: CCD, FABRIK and the Jacobian methods on a
:class:`~course.ik._engine.chain.SerialChain`, one problem in Python floats or a batch on
component arrays (:mod:`course.ik._engine.ops`).

They are the methods of :mod:`course.ik._engine.tree_solvers` specialised to one chain and one
position target (tests check both engines give the same answers): a Jacobian step solves a
3x3 system in closed form, FABRIK on free balls iterates on points alone and fits the
rotations once, CCD turns the effector alone while it sweeps tip to root. Every solver is
a :class:`ChainSolver`: it takes a :class:`ChainRun` and its method's options record
(:mod:`course.ik._engine.request`) and returns a :class:`~.history.Solution` of
:class:`ChainState`; an iterative one supplies its step to :func:`~.history.iterate` from
:func:`chain_start`. :func:`solve_on_chain` runs one on a :class:`Request`.
"""

from __future__ import annotations

from functools import reduce
from typing import Any, NamedTuple

import numpy as np

from course import fk
from course._typing import Array
from course.rotations._kernels import TINY

from ..jacobian import lost_rank
from .chain import ChainLimits, Points, Pose, SerialChain, as_quat, as_vec, fit_chain
from .components import (
    Quat,
    Scalar,
    Vec,
    add,
    aim,
    dot,
    hinge_turn,
    quat_conjugate,
    quat_mul,
    quat_rotate,
    scale,
    sub,
    units_like,
)
from .history import History, Options, Solution, Solver, iterate
from .ops import ARRAYS, FLOATS, Components, Flag, Ops
from .request import CCDOptions, JacobianOptions, NoOptions, Request, Solved


class ChainRun(NamedTuple):
    """What a chain solver gets: one problem in Python floats or a batch on component arrays
    (``ops``), every quaternion and vector as components (:mod:`.components`).

    Attributes
    ----------
    chain : SerialChain
    start : Pose
        The starting local rotations of the nodes (projected into the limits, and on the
        reach-aware start where it applies).
    base, p0 : Quat, Vec
        The held frame and the position of node 0.
    target : Vec
        The effector's position target.
    tol, max_iter, record
        As :func:`course.ik.solve` takes them.
    limits : ChainLimits
        ``(node, limit)`` of every limited variable (empty: none).
    ops : Ops
        :data:`~.ops.FLOATS` (one problem) or :data:`~.ops.ARRAYS` (a batch).
    done : Flag
        The problems whose start is already their best pose (:mod:`.reach`).
    inv_w2 : tuple of float, length C
        The columns' :math:`W^{-2}` (the Jacobian methods'; empty for the others).
    """

    chain: SerialChain
    start: Pose
    base: Quat
    p0: Vec
    target: Vec
    tol: float
    max_iter: int
    record: bool
    limits: ChainLimits
    ops: Ops
    done: Flag
    inv_w2: tuple[float, ...] = ()


class ChainState(NamedTuple):
    """A chain method's state between two steps: the local rotations ``R`` of the nodes,
    their global orientations ``Q`` and positions ``P`` (forward kinematics of ``R``), the
    effector's error ``e`` :math:`= t - p_{n-1}` and its length ``err``."""

    R: Pose
    Q: list[Quat]
    P: Points
    e: Vec
    err: Scalar

    @property
    def progress(self) -> None:
        """The chain's methods let the stall test watch ``err`` itself."""
        return None


# A method on the serial chain: ``solver(run, options) -> Solution[ChainState]``.
ChainSolver = Solver[ChainRun, Options, ChainState]


def chain_start(run: ChainRun) -> ChainState:
    """The state the chain's methods iterate from: forward kinematics of ``run.start``, bent
    off a straight chain whose target lies on its line (:meth:`SerialChain.bend_if_straight`,
    the tree engine's test)."""
    chain, base, p0, target, ops = run.chain, run.base, run.p0, run.target, run.ops
    Q, P = chain.forward(run.start, base, p0)
    R, Q, P = chain.bend_if_straight(run.start, Q, P, base, p0, target, run.tol, run.limits,
                                     ops)
    e = sub(target, P[-1])
    return ChainState(R, Q, P, e, ops.sqrt(dot(e, e)))


def solve_on_chain(req: Request, solver: ChainSolver[Any], limits: ChainLimits,
                   weighted: bool) -> Solved:
    """Run a chain ``solver`` on a request whose paths are ``req.serial``: one problem in
    Python floats (``req.local`` (J, 4), ``req.root_pos`` and the target (3,)), or a batch on
    component arrays; ``limits`` are ``req.serial.limits(...)`` (empty: none), and a
    ``weighted`` solver also gets the columns' ``inv_w2``, :math:`W^{-2}`."""
    chain, skeleton, B = req.serial, req.skeleton, req.B
    if chain is None:
        raise ValueError("solve_on_chain: the request's paths are not one serial chain")
    ops = ARRAYS if req.batched else FLOATS
    joints = list(chain.joints)
    (target_a,) = req.pos_t.values()
    local, root_pos = req.local, req.root_pos
    if req.batched:
        local = np.broadcast_to(local, (B, skeleton.n_joints, 4))
        root_pos = np.broadcast_to(root_pos, (B, 3))
    base: Quat
    if req.root == 0:  # the world frame is held and joint 0 sits at the root position
        base, p0 = (1.0, 0.0, 0.0, 0.0), as_vec(_components(root_pos, ops))
    else:
        positions, orientations = fk.forward_kernel(skeleton.parents, skeleton.offsets,
                                                        local, root_pos)
        base = as_quat(_components(orientations[..., skeleton.parents[req.root], :], ops))
        p0 = as_vec(_components(positions[..., req.root, :], ops))
    if ops is FLOATS:
        rows = local.tolist()
        start = [as_quat(rows[j]) for j in joints]
        target = as_vec(target_a.tolist())
    else:
        start = [as_quat(_components(local[:, j], ops)) for j in joints]
        target = as_vec(_components(np.broadcast_to(target_a, (B, 3)), ops))
    R = start
    if limits:
        R = chain.project(R, limits, ops)
    reach_start = done = ops.full(target[0], False)
    if req.reach_start and chain.bendable:  # near the reach: bent to its distance (reach.py)
        R, reach_start, done = chain.reach_start(R, base, p0, target, req.tol, limits, ops)
    inv_w2 = tuple((1.0 / req.col_weight**2).tolist()) if weighted else ()
    solution = solver(ChainRun(chain, R, base, p0, target, req.tol, req.max_iter, req.record,
                               limits, ops, done, inv_w2), req.options)
    covers = chain.joints == tuple(range(skeleton.n_joints))  # a chain skeleton: its own FK

    def pose(R: Pose, P: Points | None = None) -> tuple[Array, Array]:
        """Local rotations (unit, in the starting quaternions' signs) and positions of ``R``;
        ``P``, if given, are the chain's positions of ``R`` already computed."""
        q = ops.stack(units_like(R, start, ops), B)
        if covers:  # every joint is on the chain
            return q, ops.stack(chain.forward(R, base, p0)[1] if P is None else P, B)
        out = local.copy()
        out[..., joints, :] = q
        return out, fk.forward_kernel(skeleton.parents, skeleton.offsets, out, root_pos)[0]

    local_out, positions = pose(solution.R, solution.P)
    recorded = [pose(f.R) for f in solution.frames] if req.record else None
    unreachable = chain.unreachable(target, p0, ops)
    return Solved(local_out, root_pos.copy(), positions, solution.history, unreachable,
                  recorded, reach_start)


def _components(a: Array, ops: Ops) -> Components:
    """(c,) -> c floats for one problem; (B, c) -> c contiguous (B,) rows for a batch."""
    if ops is FLOATS:
        return tuple(a.tolist())
    return tuple(np.ascontiguousarray(a.T))


# --------------------------------------------------------------------------- Jacobian methods
# The six entries (a00, a01, a02, a11, a12, a22) of a symmetric 3x3 matrix, as components.
Sym3 = tuple[Scalar, Scalar, Scalar, Scalar, Scalar, Scalar]


def increment(cols: list[Vec], e: Vec, method: str, inv_w2: tuple[float, ...], damping: float,
              rcond: float, ops: Ops) -> list[Scalar]:
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
        z = as_vec(ops.vector(np.einsum("...ij,...j->...i", V, inv * y)))
    else:
        a00, a01, a02, a11, a12, a22 = A
        Ae = (a00 * e[0] + a01 * e[1] + a02 * e[2], a01 * e[0] + a11 * e[1] + a12 * e[2],
              a02 * e[0] + a12 * e[1] + a22 * e[2])
        den = dot(Ae, Ae)
        z = scale(e, dot(e, Ae) / ops.where(den > 0, den, 1.0))
    return [dot(c, z) * iw for c, iw in zip(cols, inv_w2, strict=True)]


def gram(cols: list[Vec], inv_w2: tuple[float, ...]) -> Sym3:
    r""":math:`A = J W^{-2} J^T = \sum_c J_c J_c^T / w_c^2` as its six entries
    ``(a00, a01, a02, a11, a12, a22)``."""
    a00 = a01 = a02 = a11 = a12 = a22 = 0.0
    for (x, y, z), iw in zip(cols, inv_w2, strict=True):
        wx, wy, wz = x * iw, y * iw, z * iw
        a00, a01, a02 = a00 + wx * x, a01 + wx * y, a02 + wx * z
        a11, a12, a22 = a11 + wy * y, a12 + wy * z, a22 + wz * z
    return a00, a01, a02, a11, a12, a22


def _well_conditioned(A: Sym3, rcond: float) -> Flag:
    r"""Whether no eigenvalue of the PSD ``A`` is below :math:`\text{rcond}^2\lambda_{max}`,
    sufficient test: :math:`\lambda_{min}/\lambda_{max} \ge \det A / (\mathrm{tr} A)^3`."""
    a00, a01, a02, a11, a12, a22 = A
    det = (a00 * (a11 * a22 - a12 * a12) - a01 * (a01 * a22 - a02 * a12)
           + a02 * (a01 * a12 - a02 * a11))
    tr = a00 + a11 + a22
    return det > rcond * rcond * tr * tr * tr


def _solve_sym(A: Sym3, e: Vec, lam2: float, ops: Ops) -> Vec:
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


def solve_jacobian(run: ChainRun, options: JacobianOptions, /) -> Solution[ChainState]:
    """Iterate a Jacobian method (``options.method``), as :func:`.tree_solvers.solve_jacobian`
    does on the general model: capped steps (``max_step``), backtracking (a step that raises
    the error is undone and the next one halved)."""
    chain, base, p0, target, limits, ops = (run.chain, run.base, run.p0, run.target,
                                            run.limits, run.ops)
    method, damping, rcond, max_step = (options.method, options.damping, options.rcond,
                                        options.max_step)
    step_scale: Scalar = 1.0

    def step(s: ChainState, active: Flag) -> ChainState:
        nonlocal step_scale
        R, Q, P, e, err = s
        delta = increment(chain.columns(Q, P, base), e, method, run.inv_w2, damping, rcond, ops)
        big = reduce(ops.maximum, (ops.abs(d) for d in delta))
        k = ops.minimum(1.0, max_step / ops.maximum(big, 1e-300)) * step_scale
        k = k * active
        trial = chain.step(R, Q, base, [d * k for d in delta], ops)
        if limits:
            trial = chain.project(trial, limits, ops)
        Q_t, P_t = chain.forward(trial, base, p0)
        e_t = sub(target, P_t[-1])
        err_t = ops.sqrt(dot(e_t, e_t))
        worse = err_t > err
        step_scale = ops.where(worse, 0.5 * step_scale, ops.minimum(1.0, 2.0 * step_scale))
        return ChainState(*ops.select(worse, (R, Q, P, e, err), (trial, Q_t, P_t, e_t, err_t)))

    solution = iterate(run, chain_start(run), step)
    if not ops.all(solution.history.converged):
        cols = np.array([np.broadcast_arrays(*c) for c in chain.columns(
            solution.state.Q, solution.P, base)], float)
        solution.history.singular = ops.flag(
            lost_rank(np.moveaxis(cols.reshape(len(cols), 3, -1), -1, 0), rcond))
    return solution


# --------------------------------------------------------------------------- FABRIK
def follow(P: Points, first: int, step: int, d: list[Scalar], rest: list[Vec],
           ops: Ops) -> Points:
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


def reach_forward(P: Points, target: Vec, d: list[Scalar], rest: list[Vec],
                  ops: Ops) -> Points:
    r"""FABRIK's forward reaching: :math:`p_n \leftarrow t`, then
    :math:`p_i \leftarrow p_{i+1} + d_i\,\widehat{(p_i - p_{i+1})}` down to the root.
    ``rest`` are the unit bone directions (root to tip), reversed where two joints coincide."""
    P = list(P)
    P[-1] = target
    return follow(P, len(P) - 1, -1, d, rest, ops)


def fabrik_pass(P: Points, target: Vec, root: Vec, d: list[Scalar], rest: list[Vec],
                ops: Ops) -> Points:
    r"""One FABRIK iteration: forward reaching (:func:`reach_forward`), then backward
    reaching (:math:`p_0 \leftarrow b`, then :math:`p_{i+1} \leftarrow p_i +
    d_i\,\widehat{(p_{i+1} - p_i)}`); ``rest`` are the unit bone directions (root to tip)
    to use where two joints coincide."""
    P = reach_forward(P, target, d, rest, ops)
    P[0] = root
    return follow(P, 0, 1, d, rest, ops)


def bone_directions(P: Points, ops: Ops) -> tuple[list[Scalar], list[Vec]]:
    r"""Bone lengths :math:`d_i = \lVert p_{i+1} - p_i\rVert` and unit directions of chain
    points ``P`` (+y for a zero bone)."""
    d: list[Scalar] = []
    rest: list[Vec] = []
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


def fabrik_points(P: Points, target: Vec, tol: float, max_iter: int, ops: Ops,
                  frames: list[Points] | None = None, errors: list[Scalar] | None = None
                  ) -> tuple[Points, Scalar, Scalar]:
    r"""FABRIK on chain points ``P`` (``P[0]`` fixed; bone lengths taken from them).

    A target beyond :math:`\sum d_i - tol` (and not yet reached) is answered in one pass, the
    chain stretched straight at it. A batch iterates only its problems still running. ``frames`` and
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
    # Stretched straight, the end is |dist - reach| from the target: within tol of the reach
    # that is the answer (the lecture's fabrik_positions decides the same).
    far = ops.both(dist > sum(d) - tol, ops.dist(P[-1], target) >= tol)
    if ops.any(far):  # at or beyond the reach: stretched straight at the target
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
            P_i, t, root_i, d_i, rest_i = ops.take((P, target, root, d, rest), idx)
            Q = fabrik_pass(P_i, t, root_i, d_i, rest_i, ops)
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


def solve_fabrik(run: ChainRun, options: NoOptions, /) -> Solution[ChainState]:
    """FABRIK: on positions alone for a chain of free ball joints
    (:func:`solve_fabrik_points`, whose own reachability branch answers a ``done`` problem),
    else with the backward pass in joint space (:func:`solve_fabrik_joints`)."""
    if run.chain.free_balls and not run.limits:
        return solve_fabrik_points(run)
    return solve_fabrik_joints(run)


def solve_fabrik_points(run: ChainRun) -> Solution[ChainState]:
    """FABRIK on a chain of free ball joints (``run.limits`` empty): iterate on positions alone
    (:func:`fabrik_points`, its own loop: no stall test, a batch iterating only its problems
    still running), then fit the rotations once (:func:`fit_chain`; exact, the points keep
    the bones). ``record`` fits every iteration's points too."""
    chain, base, target, tol, max_iter, record, ops = (
        run.chain, run.base, run.target, run.tol, run.max_iter, run.record, run.ops)
    start = chain_start(run)
    points: list[Points] = []
    errors: list[Scalar] = []
    P_new, its, _ = fabrik_points(ops.copy(start.P), target, tol, max_iter, ops,
                                  points if record else None, errors)
    if record and len(points) < np.max(its):  # a stretch: answered before the loop
        points.append(P_new)

    def fitted(points: Points) -> ChainState:
        """The pose that puts the chain on ``points``, with its residual (honest: what the
        returned rotations reach)."""
        R, Q, P = fit_chain(chain, start.R, start.Q, start.P, base, points, ops)
        return ChainState(R, Q, P, sub(target, P[-1]), ops.dist(target, P[-1]))

    fits = [fitted(f) for f in (points if record else [P_new])]
    # Without a record, the points' errors stand for the iterations in between (the fit is
    # exact); recorded with nothing to iterate (a stretched start already there), the start
    # stays.
    history = History.of([start.err, *([] if record else errors[:-1]), *(f.err for f in fits)],
                         its, tol, max_iter, ops)
    return Solution(fits[-1] if fits else start, history, (start, *fits) if record else ())


def solve_fabrik_joints(run: ChainRun) -> Solution[ChainState]:
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
    chain, base, p0, target, limits, ops = (run.chain, run.base, run.p0, run.target,
                                            run.limits, run.ops)
    n = len(chain.bones)
    axis_of = dict(zip(chain.variables, chain.axes, strict=True))
    limits_of = {v: [lim for lim in limits if lim[0] == v] for v in chain.variables}
    start = chain_start(run)
    d, rest = bone_directions(start.P, ops)

    def step(s: ChainState, active: Flag) -> ChainState:
        reached = reach_forward(s.P, target, d, rest, ops)
        new, q, p = list(s.R), base, p0
        Q_new: list[Quat] = []
        P_new: Points = []
        for i in range(n):  # backward reaching: forward kinematics, aiming every joint
            if i:
                p = add(p, quat_rotate(q, chain.bones[i]))
            P_new.append(p)
            if i in axis_of:
                axis = axis_of[i]
                if axis is None:  # a ball: its bone at the reached point
                    u = quat_rotate(quat_mul(q, new[i]), chain.bones[i + 1])
                    new[i] = aim(new[i], q, None, u, sub(reached[i + 1], p), ops)
                else:  # a hinge: the chain below it as close as it can to its points
                    qj, pj = quat_mul(q, new[i]), p
                    us: list[Vec] = []
                    ws: list[Vec] = []
                    for j in range(i + 1, n):
                        pj = add(pj, quat_rotate(qj, chain.bones[j]))
                        qj = quat_mul(qj, new[j])
                        us.append(sub(pj, p))
                        ws.append(sub(reached[j], p))
                    new[i] = hinge_turn(new[i], q, axis, us, ws, ops)
                new = chain.project(new, limits_of[i], ops)
            q = quat_mul(q, new[i])
            Q_new.append(q)
        R, Q, P, e = ops.select(active, (new, Q_new, P_new, sub(target, P_new[-1])),
                                (s.R, s.Q, s.P, s.e))
        return ChainState(R, Q, P, e, ops.sqrt(dot(e, e)))

    return iterate(run, start, step)


# --------------------------------------------------------------------------- CCD
def solve_ccd(run: ChainRun, options: CCDOptions, /) -> Solution[ChainState]:
    r"""CCD sweeps, as :func:`.tree_solvers.solve_ccd` on the general model: every joint
    in turn (tip to root, or root to tip) turns the effector direction :math:`e - r_i` towards
    :math:`t - r_i` (:func:`aim`), is projected into its limit, and the chain below it turns
    with it: :math:`p_j \leftarrow r_i + q\,(p_j - r_i)`, :math:`Q_j \leftarrow q\,Q_j` with
    the world turn :math:`q = Q_i' Q_i^{-1}`.
    """
    chain, base, p0, target, limits, ops = (run.chain, run.base, run.p0, run.target,
                                            run.limits, run.ops)
    tip_to_root, max_angle = options.tip_to_root, options.max_angle
    n = len(chain.bones)
    axis_of = dict(zip(chain.variables, chain.axes, strict=True))
    limits_of = {v: [lim for lim in limits if lim[0] == v] for v in chain.variables}
    order = chain.variables[::-1] if tip_to_root else chain.variables

    def step(s: ChainState, active: Flag) -> ChainState:
        new, Q, P = list(s.R), list(s.Q), list(s.P)
        for v in order:
            parent, pivot = (Q[v - 1] if v else base), P[v]
            new[v] = aim(new[v], parent, axis_of[v], sub(P[-1], pivot), sub(target, pivot),
                         ops, max_angle)
            new = chain.project(new, limits_of[v], ops)
            Qv = quat_mul(parent, new[v])
            turn = quat_mul(Qv, quat_conjugate(Q[v]))
            # Tip to root, the joints still to visit lie above v: only the effector matters.
            for j in range(n - 1, n) if tip_to_root else range(v + 1, n):
                P[j] = add(pivot, quat_rotate(turn, sub(P[j], pivot)))
                Q[j] = quat_mul(turn, Q[j])
            Q[v] = Qv
        R = ops.select(active, new, s.R)
        Q, P = chain.forward(R, base, p0)
        e = sub(target, P[-1])
        return ChainState(R, Q, P, e, ops.sqrt(dot(e, e)))

    return iterate(run, chain_start(run), step)
