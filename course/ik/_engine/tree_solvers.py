r"""The general engine's solvers: every method on a :class:`~course.ik._engine.tree.Problem`
(any tree of paths from the fixed joint, several effectors, orientation targets), batched
over ``B`` problems on rotation matrices.

Each is the lecture's method of the module of the same name in :mod:`course.ik` (whose
docstring has the maths), written for a re-rooted tree: CCD turns one variable at a time
(Kabsch where several effectors hang below it), FABRIK reaches sub-chains to their sub-bases
and fits the rotations level by level (:meth:`Problem.fit`), the Jacobian methods step all
variables at once with the steps of :mod:`course.ik.jacobian`, and the two-link solve places
the middle joint by the law of cosines (:func:`course.ik.two_link.two_link`). Every solver is
a :class:`TreeSolver`: it takes the :class:`Problem` (its run record: the batch, ``tol``,
``max_iter``, ``record``) and its method's options record (:mod:`course.ik._engine.request`)
and returns a :class:`~.history.Solution` of :class:`TreeState`, the method supplying its
step to :func:`~.history.iterate` from :func:`tree_start`; :func:`solve_on_tree` runs one on
a :class:`Request`.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from course import fk
from course._typing import Array
from course._validate import as_array
from course.rotations import matrix_from_quat, quat_from_matrix
from course.rotations._kernels import (
    TINY,
    best_rotation,
    cross,
    dot,
    matrix_from_rotvec,
    matvec,
    norm,
    orthonormalize,
    rotvec_from_matrix,
)
from course.skeleton import Skeleton

from ..jacobian import dls_step, lost_rank, pinv_step, transpose_step
from ..two_link import two_link
from .chain import as_vec
from .chain_solvers import fabrik_points
from .history import History, Options, Solution, Solver, iterate
from .ops import ARRAYS, Flag
from .request import (
    CCDOptions,
    JacobianOptions,
    NoOptions,
    Request,
    Solved,
    TwoLinkOptions,
)
from .tree import Problem, TreeModel

# DLS damping when none is given, as a share of the longest path to an effector.
DEFAULT_DAMPING = 0.05


class TreeState(NamedTuple):
    r"""A tree method's state between two steps: the edge rotations ``R`` (B, N, 3, 3), the
    nodes' global orientations ``M`` and positions ``P`` (B, N, 3) (forward kinematics of
    ``R``), the error vector ``e`` and the largest effector error ``err``
    (:meth:`Problem.error`), and the objective the stall test watches (the Jacobian methods':
    :math:`\lVert\Delta e\rVert`; None: ``err``)."""

    R: Array
    M: Array
    P: Array
    e: Array
    err: Array
    progress: Array | None = None


# A method on the tree model: ``solver(problem, options) -> Solution[TreeState]``.
TreeSolver = Solver[Problem, Options, TreeState]


def tree_start(problem: Problem, objective: bool = False) -> TreeState:
    """The state the tree's methods iterate from: forward kinematics of ``problem.Rn`` (bent
    by :func:`solve_on_tree` already) and its error; with ``objective`` the length of the
    error vector too."""
    M, p = problem.forward(problem.Rn)
    e, err = problem.error(M, p)
    return TreeState(problem.Rn, M, p, e, err, np.sqrt((e * e).sum(axis=1)) if objective
                     else None)


def solve_ccd(problem: Problem, options: CCDOptions, /) -> Solution[TreeState]:
    r"""CCD (:mod:`course.ik.ccd`); ``max_angle`` caps each joint's turn per step (radians).
    Limits are enforced by projecting after every joint's turn.

    Each joint takes the turn :math:`R` about its pivot that best moves the position
    targets below it onto theirs, weighted least squares (:func:`_ccd_pairs`). The last joint
    above an orientation target (:func:`_last_joints`) also turns the three axes of the
    effector's frame onto the target frame's (scaled by the solve's length): the
    end-orientation step, exact where that joint moves no position target.
    """
    m = problem.model
    max_angle = options.max_angle
    first_col = np.searchsorted(m.col_var, np.arange(len(m.var_nodes)))
    order = np.arange(len(m.var_nodes))
    if options.tip_to_root:
        order = order[::-1]
    axes_local = m.var_axes()
    last = _last_joints(problem)

    def step(s: TreeState, active: Flag) -> TreeState:
        Rn, M, p = s.R.copy(), s.M.copy(), s.P.copy()  # turned in place below
        run = active[:, None, None]
        for v in order:
            d = m.var_nodes[v]
            piv = p[:, m.pivot[d]][:, None]
            u, w, wt = _ccd_pairs(problem, M, p, piv, first_col[v], last == v)
            if m.hinge[v]:
                frame = M[:, d] if m.up[d] else (M[:, m.parent[d]] if d else problem.base)
                a = matvec(frame, axes_local[v])[:, None]  # (B, 1, 3)
                up_ = u - dot(u, a)[..., None] * a
                wp = w - dot(w, a)[..., None] * a
                angle = np.arctan2((dot(a, cross(up_, wp)) * wt).sum(-1),
                                   (dot(up_, wp) * wt).sum(-1))
                R = matrix_from_rotvec(a[:, 0] * angle[..., None])
            else:
                R = best_rotation(u[:, wt > 0], w[:, wt > 0], wt[wt > 0])
            if max_angle is not None:
                rv = rotvec_from_matrix(R)
                ang = norm(rv)
                shrink = np.minimum(1.0, max_angle / np.maximum(ang, TINY))
                R = matrix_from_rotvec(rv * shrink[..., None])
            R = np.where(run, R, np.eye(3))
            _turn(problem, Rn, M, d, R)
            if problem.limited:
                Rn = problem.project(Rn)
                M, p = problem.forward(Rn)
            else:  # turn the moved subtree about the pivot instead of redoing the forward pass
                moved = m.descendant[d].copy()
                if not m.up[d]:
                    moved[d] = False
                M[:, m.descendant[d]] = R[:, None] @ M[:, m.descendant[d]]
                p[:, moved] = piv + matvec(R[:, None], p[:, moved] - piv)
        return TreeState(Rn, M, p, *problem.error(M, p))

    return iterate(problem, tree_start(problem), step)


def _ccd_pairs(problem: Problem, M: Array, p: Array, piv: Array, col: int,
               orients: NDArray[np.bool_]) -> tuple[Array, Array, Array]:
    """What one CCD joint (Jacobian column ``col``, pivot ``piv`` (B, 1, 3)) turns: current
    and wanted vectors (B, K, 3) and their weights (K,), 0 for targets it does not move.
    Position targets give the effector's and the target's offsets from the pivot; the
    orientation targets it ``orients`` (E_r,) the axes of the effector's and the target's
    frames, times the solve's length."""
    m = problem.model
    u = p[:, m.effectors] - piv
    w = problem.target_pos - piv
    wt = problem.pos_weight * (m.pos_mask[:, col] > 0)
    if len(m.rot_effectors):
        B, L = len(p), m.length_scale
        u = np.concatenate([u, np.swapaxes(M[:, m.rot_effectors], -1, -2).reshape(B, -1, 3) * L],
                           1)
        w = np.concatenate([w, np.swapaxes(problem.target_rot, -1, -2).reshape(B, -1, 3) * L], 1)
        wt = np.concatenate([wt, np.repeat(problem.rot_weight * orients, 3)])
    return u, w, wt


def _last_joints(problem: Problem) -> NDArray[np.int_]:
    """The variable nearest each orientation target's effector on its path (E_r,): the
    joint that turns its end to the target orientation."""
    m = problem.model
    first_col = np.searchsorted(m.col_var, np.arange(len(m.var_nodes)))
    out = []
    for i in range(len(m.rot_effectors)):
        on_path = np.flatnonzero(m.rot_mask[i, first_col] > 0)
        out.append(on_path[np.argmax(m.var_nodes[on_path])])  # nodes are sorted by depth
    return np.array(out, dtype=int)


def _turn(problem: Problem, Rn: Array, M: Array, d: int, R: Array) -> None:
    """Turn node ``d``'s edge rotation in ``Rn`` (in place) by the world rotation ``R``
    (B, 3, 3) about its pivot (``M`` the orientations of ``Rn``)."""
    m = problem.model
    if m.up[d]:  # R_c = M_d^T M_parent  ->  (M_d^T R^T M_d) R_c
        Rn[:, d] = orthonormalize(
            np.swapaxes(M[:, d], -1, -2) @ np.swapaxes(R, -1, -2) @ M[:, d] @ Rn[:, d])
    else:  # R_d = M_parent^T M_d  ->  (M_parent^T R M_parent) R_d
        Mpar = M[:, m.parent[d]] if d else problem.base
        Rn[:, d] = orthonormalize(np.swapaxes(Mpar, -1, -2) @ R @ Mpar @ Rn[:, d])


def solve_fabrik(problem: Problem, options: NoOptions, /) -> Solution[TreeState]:
    """FABRIK (:mod:`course.ik.fabrik`) on any tree of paths, several effectors.

    Plain chains of unconstrained ball joints iterate on positions alone and fit rotations
    once at the end (exact: the positions are reachable). Otherwise the backward pass is done
    in joint space, level by level (:meth:`Problem.fit`), so the branch rigidity, hinge axes
    and limits shape every iteration and every residual is that of a real pose. A sub-base
    reaches to the centroid of its branches' proposals weighted by the heaviest position
    target below each; orientation targets are met after the backward pass
    (:func:`_orient_ends`).
    """
    m = problem.model
    start = tree_start(problem)
    lengths = norm(m.bone)
    branching = np.bincount(m.parent[1:], minlength=m.n_nodes).max() > 1
    free = (not branching and not m.hinge.any() and not problem.limited
            and not len(m.rot_effectors) and len(m.effectors) == 1
            and m.effectors[0] == m.n_nodes - 1 and not problem.record)
    if free:
        P = start.P.copy()
        errors: list[Array] = []
        its, _ = _fabrik_chain(P, problem.target_pos[:, 0], problem.tol, problem.max_iter,
                               errors)
        Rn = problem.fit_free(problem.Rn, P)
        M, p = problem.forward(Rn)
        e, err = problem.error(M, p)
        # The points' errors stand for the iterations; the last is that of the fitted pose.
        history = History.of([start.err, *errors[:-1], err], its, problem.tol, problem.max_iter)
        return Solution(TreeState(Rn, M, p, e, err), history)

    # Each node's pull on its sub-base: the heaviest position target below it (0: none).
    pull = (m.descendant[:, m.effectors] * problem.pos_weight).max(axis=1, initial=0.0)
    total = np.bincount(m.parent[1:], weights=pull[1:], minlength=m.n_nodes)
    is_eff = np.zeros(m.n_nodes, dtype=bool)
    is_eff[m.effectors] = True
    deepest_first = m.levels[:0:-1]
    held = _held_ends(problem)
    rows = np.arange(problem.batch)[:, None]  # every problem's row, beside a level's parents

    def step(s: TreeState, active: Flag) -> TreeState:
        Rn, old = s.R, s.P
        P = old.copy()
        P[:, m.effectors] = problem.target_pos
        for lvl in deepest_first:  # forward reaching, sub-bases to the centroid
            par = m.parent[lvl]
            fallback = old[:, par] - old[:, lvl]
            fallback /= np.maximum(norm(fallback), TINY)[..., None]
            proposal = _toward(P[:, lvl], P[:, par], lengths[lvl], fallback)
            acc = np.zeros_like(P)
            np.add.at(acc, (rows, par), proposal * pull[lvl][:, None])
            moved = np.unique(par)
            moved = moved[total[moved] > 0]  # sub-bases with a position target below
            keep = moved[is_eff[moved]]
            P[:, moved] = acc[:, moved] / total[moved][:, None]
            P[:, keep] = _targets_at(problem, keep)
            for i, e, par_e in held:  # a rigid end: its orientation places its parent
                if par_e in moved:
                    P[:, par_e] = P[:, e] - matvec(problem.target_rot[:, i] @ np.swapaxes(
                        Rn[:, e], -1, -2), m.bone[e])
        new = problem.fit(Rn, P)  # backward reaching from the fixed joint, in joint space
        if len(m.rot_effectors):
            new = _orient_ends(problem, new)
        Rn = np.where(active[:, None, None, None], new, Rn)
        M, p = problem.forward(Rn)
        return TreeState(Rn, M, p, *problem.error(M, p))

    return iterate(problem, start, step)


def _held_ends(problem: Problem) -> list[tuple[int, int, int]]:
    """``(i, e, parent)`` of the orientation targets whose effector ``e`` also has a position
    target but no free rotation of its own (a fixed end, down the tree): its parent's
    orientation is then :math:`Q_t R_e^{-1}`, so forward reaching places the parent at
    :math:`t - Q_t R_e^{-1} l_e` (FABRIK's orientation constraint)."""
    m = problem.model
    own = set(m.var_nodes.tolist())
    return [(i, int(e), int(m.parent[e])) for i, e in enumerate(m.rot_effectors)
            if e in m.effectors and e not in own and not m.up[e] and e > 0]


def _orient_ends(problem: Problem, Rn: Array) -> Array:
    r"""FABRIK's end-orientation step: for each orientation target, the last joint above its
    effector (its own rotation, if free) turns by the world rotation
    :math:`Q_t Q_e^{-1}` (a hinge: by its twist about the hinge's world axis) and is
    projected into its limit. Where that joint also moves a position target, it turns by the
    orientation's share of the two weights, :math:`w_o / (w_o + w_p)`, of that rotation."""
    m = problem.model
    first_col = np.searchsorted(m.col_var, np.arange(len(m.var_nodes)))
    axes = m.var_axes()
    Rn = Rn.copy()
    for i, (e, v) in enumerate(zip(m.rot_effectors, _last_joints(problem), strict=True)):
        d = m.var_nodes[v]
        M, _ = problem.forward(Rn)
        turn = problem.target_rot[:, i] @ np.swapaxes(M[:, e], -1, -2)
        if m.hinge[v]:
            frame = M[:, d] if m.up[d] else (M[:, m.parent[d]] if d else problem.base)
            a = matvec(frame, axes[v])
            q = quat_from_matrix(turn)
            rv = a * (2 * np.arctan2(dot(q[:, 1:], a), q[:, 0]))[:, None]
        else:
            rv = rotvec_from_matrix(turn)
        moved = m.pos_mask[:, first_col[v]] > 0
        w_o = problem.rot_weight[i]
        share = w_o / (w_o + problem.pos_weight[moved].max(initial=0.0))
        _turn(problem, Rn, M, d, matrix_from_rotvec(rv * share))
        Rn = problem.project(Rn)
    return Rn


def _targets_at(problem: Problem, nodes: NDArray[np.int_]) -> Array:
    """Targets of effector ``nodes``, (B, len(nodes), 3)."""
    where = {int(e): i for i, e in enumerate(problem.model.effectors)}
    return problem.target_pos[:, [where[int(u)] for u in nodes]]


def _toward(frm: Array, to: Array, length: Array, fallback: Array) -> Array:
    """``frm + length * unit(to - frm)``; ``fallback`` direction where ``to == frm``."""
    d = to - frm
    n = np.sqrt((d * d).sum(-1))
    if (n < TINY).any():
        d = np.where((n < TINY)[..., None], fallback, d)
        n = np.where(n < TINY, 1.0, n)
    out: Array = frm + (length / n)[..., None] * d
    return out


def _fabrik_chain(P: Array, t: Array, tol: float, max_iter: int,
                  errors: list[Array] | None = None) -> tuple[Array, Array]:
    """In-place FABRIK on (B, n, 3) chains; returns iterations and errors, both (B,);
    ``errors``, if given, receives the (B,) errors after every iteration.

    Runs :func:`.chain_solvers.fabrik_points` on component-major storage (each coordinate of
    each joint one contiguous (B,) row)."""
    comps = np.array(P.transpose(1, 2, 0))  # (n, 3, B), a copy the solver may write into
    points, its, err = fabrik_points([as_vec(c) for c in comps], as_vec(np.array(t.T)), tol,
                                     max_iter, ARRAYS, errors=errors)
    P[:] = np.moveaxis(np.array(points), -1, 0)
    return np.asarray(its), np.asarray(err)


def solve_jacobian(problem: Problem, options: JacobianOptions, /) -> Solution[TreeState]:
    r"""Iterate one Jacobian method of :mod:`course.ik.jacobian` (``options.method``).

    ``max_step`` caps the largest joint increment per iteration (radians; the step keeps its
    direction), so a far target is approached in several linearised steps. A step that
    increases the objective :math:`\lVert\Delta e\rVert` (all effectors' errors together) is
    undone and the next one halved (backtracking), so it never grows; when it stalls the
    solve stops (``reason="stalled"``, ``"singular"`` or ``"unreachable"``). ``damping`` is a
    length, like the errors it is added to (by default :data:`DEFAULT_DAMPING` of the longest
    path to an effector, filled in by :func:`course.ik._pipeline.validate`).
    """
    m = problem.model
    method, damping, rcond, max_step = (options.method, options.damping, options.rcond,
                                        options.max_step)
    w = problem.col_weight
    uniform = bool(np.all(w == 1.0))
    scale = np.ones(problem.batch)

    def step(s: TreeState, active: Flag) -> TreeState:
        nonlocal scale
        Rn, M, p, e, err, size = s
        assert size is not None, "the Jacobian methods start with their objective"
        J = m.jacobian(M, p, problem.base)
        if problem.row_weight is not None:  # the rows of weighted targets, as in the error
            J = J * problem.row_weight[:, None]
        Jw = J if uniform else J / w  # substitute y = W dtheta (see module docstring)
        if method == "dls":
            y = dls_step(Jw, e, damping)
        elif method == "pseudo_inverse":
            y = pinv_step(Jw, e, rcond)
        else:
            y = transpose_step(Jw, e)
        delta = y if uniform else y / w
        big = np.abs(delta).max(axis=1, keepdims=True)
        delta = delta * np.minimum(1.0, max_step / np.maximum(big, 1e-300))
        delta = np.where(active[:, None], delta * scale[:, None], 0.0)
        trial = problem.project(m.step(Rn, M, problem.base, delta))
        M_t, p_t = problem.forward(trial)
        e_t, err_t = problem.error(M_t, p_t)
        size_t = np.sqrt((e_t * e_t).sum(axis=1))
        # Backtracking: a step that made the objective worse is undone and the next one
        # halved. (Not the largest effector error: with several effectors a good step may
        # trade a little of one for much of another.)
        worse = size_t > size
        scale = np.where(worse, 0.5 * scale, np.minimum(1.0, 2.0 * scale))
        keep = ~worse
        return TreeState(np.where(keep[:, None, None, None], trial, Rn),
                         np.where(keep[:, None, None, None], M_t, M),
                         np.where(keep[:, None, None], p_t, p), np.where(keep[:, None], e_t, e),
                         np.where(keep, err_t, err), np.where(keep, size_t, size))

    # The objective every step reduces: the length of the whole error vector,
    # sqrt(sum of squares) (one effector: its error).
    solution = iterate(problem, tree_start(problem, objective=True), step)
    if not solution.history.converged.all():
        solution.history.singular = lost_rank(m.jacobian(solution.state.M, solution.P,
                                                         problem.base), rcond)
    return solution


def solve_two_link(problem: Problem, options: TwoLinkOptions, /) -> Solution[TreeState]:
    """The analytic two-bone solve; a start already within ``tol`` is kept (0 iterations),
    and a target the joints cannot reach (out of reach, off a hinge's plane) ends in their
    closest pose, reported ``"unreachable"`` or ``"stalled"`` (never ``"max_iterations"``:
    there is nothing to iterate)."""
    m = problem.model
    pole, flip = options.pole, options.flip
    if m.n_nodes != 3 or len(m.effectors) != 1 or m.effectors[0] != 2:
        raise ValueError(
            "method: 'two_link' needs the path from root to the one effector to be two bones "
            f"(three joints), got {m.n_nodes} joints; choose root accordingly")
    t = problem.target_pos[:, 0]
    hip = np.flatnonzero(m.var_nodes == 0)
    knee = np.flatnonzero(m.var_nodes == 1)
    axes = m.var_axes()
    both = bool(not m.up.any() and len(hip) and len(knee))

    def step(s: TreeState, active: Flag) -> TreeState:
        M, p = s.M, s.P
        if both and m.hinge[hip[0]]:
            Rn = _two_link_hinge_hip(problem, p, t, axes[hip[0]],
                                     axes[knee[0]] if m.hinge[knee[0]] else None, pole, flip)
            b = problem.forward(Rn)[1][:, 1]
        elif both and m.hinge[knee[0]]:
            Rn, b, _ = _two_link_hinge_knee(problem, M, p, t, axes[knee[0]], pole, flip)
        else:
            Rn = problem.Rn
            b, _, _ = two_link(p[:, 0], p[:, 1], p[:, 2], t, pole, flip)
        # With both joints free each aims at its own point (exact: no least-squares compromise).
        Rn = problem.fit(Rn, np.stack([p[:, 0], b, t], 1), subtree=not both)
        Rn = np.where(active[:, None, None, None], Rn, s.R)
        M, p = problem.forward(Rn)
        return TreeState(Rn, M, p, *problem.error(M, p))

    # Closed form: one step whatever the budget, from the start as given (no bend).
    solution = iterate(replace(problem, max_iter=1), tree_start(problem), step)
    solution.history.stalled = ~solution.history.converged
    return solution


def _two_link_hinge_hip(problem: Problem, p: Array, t: Array, hip_axis: Array,
                        knee_axis: Array | None, pole: ArrayLike | None,
                        flip: bool) -> Array:
    r"""Two-link with a hinge root (the textbook arm): the hip can only swing the knee on the
    circle :math:`b(\theta) = a + \exp(\theta[\hat a]_\times)(b_0 - a)` about its world axis
    :math:`\hat a`, so the law of cosines becomes one equation in :math:`\theta`. With
    :math:`v = b(\theta) - a` and :math:`w = t - a`, :math:`\lVert t - b\rVert = l_2` reads
    :math:`v\cdot w = (l_1^2 + d^2 - l_2^2)/2`, and
    :math:`v\cdot w = C + A\cos\theta + B\sin\theta` (:math:`C` the part along the axis), so
    :math:`\theta = \varphi \pm \arccos\frac{K - C}{\sqrt{A^2 + B^2}}`,
    :math:`\varphi = \mathrm{atan2}(B, A)`. When the knee is a hinge parallel to the hip (a
    planar arm) the same holds in the plane: the parts along the axis drop out, so a target
    off the plane gets the pose reaching its projection. Of the two roots (the elbow on
    either side of the line to the target) the one nearer the pole, else the one bending as
    the knee bends now (the smaller turn from a straight start); ``flip`` takes the other.
    Out of reach the cosine is clipped: the arm stretches (or folds) towards the target.

    Returns the edge rotations with the hip turned (and projected into its limits).
    """
    a, b0, c0 = p[:, 0], p[:, 1], p[:, 2]
    ax = matvec(problem.base, hip_axis)
    v, w, bone2 = b0 - a, t - a, c0 - b0
    va, wa = dot(v, ax), dot(w, ax)
    v_perp = v - va[:, None] * ax
    side = cross(ax, v_perp)
    K = 0.5 * (dot(v, v) + dot(w, w) - dot(bone2, bone2)) - va * wa
    if knee_axis is not None and norm(cross(np.asarray(knee_axis), hip_axis)) < 1e-9:
        h = dot(bone2, ax)  # a planar arm: solve in the plane (the axial parts drop out)
        K = K - 0.5 * ((va - wa) ** 2 - h * h)
    A, Bs = dot(v_perp, w), dot(side, w)
    radius = np.hypot(A, Bs)
    scale = problem.model.length_scale
    cos = np.where(radius > 1e-12 * scale * scale, K / np.where(radius > 0, radius, 1.0), 1.0)
    phi = np.arctan2(Bs, A)
    half = np.arccos(np.clip(cos, -1.0, 1.0))
    roots = np.stack([phi - half, phi + half], 1)  # (B, 2)
    roots = (roots + np.pi) % (2 * np.pi) - np.pi
    knees = (a[:, None] + np.cos(roots)[..., None] * v_perp[:, None]
             + np.sin(roots)[..., None] * side[:, None] + va[:, None, None] * ax[:, None])
    if pole is not None:
        pole_pt = np.broadcast_to(as_array(pole, "pole", (3,)), a.shape)
        first = norm(knees[:, 0] - pole_pt) <= norm(knees[:, 1] - pole_pt)
    else:
        now = dot(ax, cross(v, c0 - a))  # which way the knee bends now, about the hip axis
        bend = dot(ax[:, None], cross(knees - a[:, None], w[:, None]))
        straight = np.abs(now) <= 1e-9 * scale * scale
        first = np.where(straight, np.abs(roots[:, 0]) <= np.abs(roots[:, 1]),
                         bend[:, 0] * now >= bend[:, 1] * now)
    theta = np.where(first != flip, roots[:, 0], roots[:, 1])
    Rn = problem.Rn.copy()
    Rn[:, 0] = matrix_from_rotvec(hip_axis * theta[:, None]) @ Rn[:, 0]
    return problem.project(Rn)


def _two_link_hinge_knee(problem: Problem, M: Array, p: Array, t: Array, knee_axis: Array,
                         pole: ArrayLike | None, flip: bool) -> tuple[Array, Array, Array]:
    r"""Two-link with a ball root and a hinge middle joint (hip and knee): the leg's plane
    must be perpendicular to the knee axis, which turns with the hip. So the plane is chosen
    first: through the root-to-target axis :math:`\hat u` and the pole, or without a pole the
    plane whose normal is nearest the knee's world axis :math:`a = Q_{hip}\hat a` (its part
    perpendicular to :math:`\hat u`, bending to the side the knee bends now). The law of
    cosines places the knee in it (:func:`two_link`), and the hip turns (Kabsch on the two
    directions) so that its bone points at the new knee and the knee axis along the plane's
    normal; the knee's own turn about its axis then lands the end on the target.

    Returns the edge rotations with the hip turned, and the new knee and end positions.
    """
    a, b0, c0 = p[:, 0], p[:, 1], p[:, 2]
    axis = matvec(M[:, 0], knee_axis)
    u = np.where((norm(t - a) > TINY)[:, None], t - a, c0 - a)
    u = u / np.maximum(norm(u), TINY)[:, None]
    if pole is None:
        n = axis - dot(axis, u)[:, None] * u
        side = cross(u, n)  # a knee bent by a positive turn about n has its joint on this side
        bent = b0 - a - dot(b0 - a, u)[:, None] * u
        side = np.where((dot(bent, side) < 0)[:, None], -side, side)
        planar = norm(n) > 1e-9
        pole_pt = np.where(planar[:, None], a + side, b0)  # knee axis along u: keep the plane
    else:
        pole_pt = np.broadcast_to(as_array(pole, "pole", (3,)), a.shape)
    b, c, _ = two_link(a, b0, c0, t, pole_pt, flip)
    n = cross(b - a, c - a)
    n = np.where((norm(n) > TINY)[:, None], n, cross(u, pole_pt - a))
    n = n / np.maximum(norm(n), TINY)[:, None]
    n = np.where((dot(n, axis) < 0)[:, None], -n, n)  # the nearer of the two normals
    turn = best_rotation(np.stack([b0 - a, axis], 1), np.stack([b - a, n * norm(b0 - a)[:, None]],
                                                               1))
    Rn = problem.Rn.copy()
    Rn[:, 0] = orthonormalize(np.swapaxes(problem.base, -1, -2) @ turn @ M[:, 0])
    return problem.project(Rn), b, c


def solve_on_tree(req: Request, solver: TreeSolver[Any], iterative: bool = True) -> Solved:
    """Run a tree ``solver`` on a request as a batch (one problem: a batch of one, unbatched
    at the end). An ``iterative`` method starts, on a serial chain that can bend evenly, from
    the reach-aware start of :meth:`Problem.reach_start` where its target lies at or near its
    full reach, then from the bent start of :meth:`Problem.bend_if_straight`."""
    problem, base = problem_of(req)
    reach_start = np.zeros(req.B, dtype=bool)
    if iterative:
        chain = req.serial
        if req.reach_start and chain is not None and chain.bendable:
            axis = None if chain.free_balls else np.array(chain.axes[0])
            problem.Rn, reach_start = problem.reach_start(problem.Rn, req.tol, axis)
        problem.Rn = problem.bend_if_straight(problem.Rn, req.tol)
    solution = solver(problem, req.options)
    history = solution.history
    local_b, root_b, Q_k, p_k = base
    pose = _pose(req.skeleton, problem.model, local_b, root_b, Q_k, p_k, solution.R)
    recorded = []
    if req.record:
        frames = [f.R for f in solution.frames]
        T, B = len(frames), req.B
        stacked = _pose(req.skeleton, problem.model, np.tile(local_b, (T, 1, 1)),
                        np.tile(root_b, (T, 1)), None if Q_k is None else np.tile(Q_k, (T, 1)),
                        np.tile(p_k, (T, 1)), np.concatenate(frames, 0))
        recorded = [(stacked[0][t * B:(t + 1) * B], stacked[2][t * B:(t + 1) * B])
                    for t in range(T)]
    model = problem.model
    unreachable = problem.unreachable() if len(model.effectors) else np.zeros(req.B, bool)
    if not req.batched:  # one problem, solved as a batch of one
        pose = tuple(a[0] for a in pose)
        recorded = [(q[0], p[0]) for q, p in recorded]
        history.unbatch()
        return Solved(*pose, history, unreachable[0], recorded if req.record else None,
                      bool(reach_start[0]))
    return Solved(*pose, history, unreachable, recorded if req.record else None, reach_start)


def problem_of(req: Request) -> tuple[Problem, tuple[Array, Array, Array | None, Array]]:
    """The :class:`Problem` of a request (its start projected into the limits), and the
    batch's start: local rotations (B, J, 4), root positions (B, 3), and the fixed joint's
    held orientation (B, 4) (None when its parent frame is held at joint 0) and position."""
    skeleton, model, k, B = req.skeleton, req.model, req.root, req.B
    J = skeleton.n_joints
    local_b = np.broadcast_to(req.local, (B, J, 4)).copy()
    root_b = np.broadcast_to(req.root_pos, (B, 3)).copy()
    if k == 0:  # the world frame is held and joint 0 sits at the root position
        base, p_k, Q_k = np.broadcast_to(np.eye(3), (B, 3, 3)), root_b, None
    else:
        positions, orientations = fk.forward_kernel(skeleton.parents, skeleton.offsets,
                                                        local_b, root_b)
        p_k, Q_k = positions[:, k], orientations[:, k]
        base = matrix_from_quat(orientations[:, skeleton.parents[k]] if model.anchor_parent
                                else Q_k)
    Rn = np.broadcast_to(np.eye(3), (B, model.n_nodes, 3, 3)).copy()
    has = model.edge_joint >= 0
    Rn[:, has] = matrix_from_quat(local_b[:, model.edge_joint[has]])
    pos_t, rot_t = req.pos_t, req.rot_t
    problem = Problem(
        model=model, Rn=Rn, base=base, p0=p_k,
        target_pos=np.stack([np.broadcast_to(pos_t[j], (B, 3)) for j in pos_t], 1)
        if pos_t else np.zeros((B, 0, 3)),
        target_rot=np.stack([matrix_from_quat(np.broadcast_to(rot_t[j], (B, 4))) for j in rot_t],
                            1) if rot_t else np.zeros((B, 0, 3, 3)),
        col_weight=req.col_weight, limits=req.limits, pos_weight=req.pos_weight,
        rot_weight=req.rot_weight, tol=req.tol, max_iter=req.max_iter, record=req.record,
    )
    problem.Rn = problem.project(problem.Rn)
    return problem, (local_b, root_b, Q_k, p_k)


def _pose(skeleton: Skeleton, model: TreeModel, local: Array, root_pos: Array, Qk: Array | None,
          pk: Array, Rn: Array) -> tuple[Array, Array, Array]:
    """Local rotations, root position and global positions of solved edge rotations."""
    local = local.copy()
    joints = model.edge_joint[model.var_nodes]
    q = quat_from_matrix(Rn[:, model.var_nodes])
    # Keep the sign of the starting quaternion, so an animated solve has no sign flips.
    flip = np.einsum("bji,bji->bj", q, local[:, joints]) < 0
    local[:, joints] = np.where(flip[..., None], -q, q)
    if model.anchor_parent:
        if model.n_nodes == len(local[0]) and model.joints[0] == 0:
            # The paths cover the skeleton (a chain): the model's own FK has every position.
            _, p = model.forward(Rn, np.broadcast_to(np.eye(3), Rn.shape[:1] + (3, 3)), root_pos)
            positions = np.empty_like(p)
            positions[:, model.joints] = p
        else:
            positions, _ = fk.forward_kernel(skeleton.parents, skeleton.offsets, local,
                                                 root_pos)
        return local, root_pos, positions
    k = int(model.joints[0])
    positions, orientations = fk.forward_kernel(
        skeleton.parents, skeleton.offsets, local, pk, root=k, root_orientation=Qk)
    local[:, 0] = orientations[:, 0]
    return local, positions[:, 0].copy(), positions
