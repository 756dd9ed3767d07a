r"""FABRIK: Forward And Backward Reaching Inverse Kinematics (Aristidou & Lasenby 2011).

FABRIK works on joint *positions*. With bone lengths :math:`d_i = \lVert p_{i+1} - p_i\rVert`:

* **forward reaching** (end to root): put the end effector on the target,
  :math:`p_n \leftarrow t`, then pull each joint towards its successor,
  :math:`p_i \leftarrow p_{i+1} + d_i\,\widehat{(p_i - p_{i+1})}`;
* **backward reaching** (root to end): put the root back, :math:`p_0 \leftarrow b`, then
  :math:`p_{i+1} \leftarrow p_i + d_i\,\widehat{(p_{i+1} - p_i)}`.

A target farther than :math:`\sum d_i` is answered in one pass: the chain stretched straight
towards it. With several end effectors each sub-chain is reached from its end to its
*sub-base* (a joint where chains meet), the sub-base goes to the centroid of the positions the
sub-chains ask for, and reaching continues to the root; the backward pass then runs outward
from the root through every branch.

On a skeleton the positions become local rotations by turning each joint's global orientation
by the shortest arc from its old bone direction to the new one (so each bone keeps its
previous twist); joints where chains branch take the best rigid rotation of all their child
bones (Kabsch, the shortest arc again where that leaves a twist free).

Constraints act in the backward pass, which then runs in joint space. A hinge cannot aim a bone
at a point off its plane, so it takes the turn about its axis that brings everything below it
closest to the reached points (least squares): chains of hinges about different axes converge
(the 7-hinge chain of ``benchmarks/ik.py``: 199 of 200 targets), not only planar arms. A ball
joint's limit caps the angle of its whole local rotation, swing and twist together: the bone
stays within a cone of that half-angle about its rest direction, but its twist is capped too,
and a pure swing cone (free twist, Aristidou & Lasenby's elliptical cones) is not offered.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._chains import Problem
from ._ops import ARRAYS
from ._serial import fabrik_points
from ._small import TINY, norm
from .result import History

Array = NDArray[np.float64]


def _toward(frm: Array, to: Array, length: Array, fallback: Array) -> Array:
    """``frm + length * unit(to - frm)``; ``fallback`` direction where ``to == frm``."""
    d = to - frm
    n = np.sqrt((d * d).sum(-1))
    if (n < TINY).any():
        d = np.where((n < TINY)[..., None], fallback, d)
        n = np.where(n < TINY, 1.0, n)
    return frm + (length / n)[..., None] * d


def fabrik_positions(
    positions: ArrayLike, target: ArrayLike, tol: float = 1e-4, max_iter: int = 100
) -> tuple[Array, Array, Array]:
    r"""FABRIK on a chain of points (ball joints), batched over leading dimensions.

    Parameters
    ----------
    positions : array_like, shape (..., n, 3)
        Joint positions :math:`p_0 \dots p_{n-1}`; :math:`p_0` is the fixed root and the bone
        lengths are taken from them.
    target : array_like, shape (..., 3)
    tol : float
        Stop when :math:`\lVert p_{n-1} - t\rVert < tol`.
    max_iter : int

    Returns
    -------
    positions : ndarray, shape (..., n, 3)
        Same root, same bone lengths; stretched straight towards an unreachable target.
    iterations : ndarray of int, shape (...)
        Forward-and-backward passes used (0 if already there, 1 for a stretch).
    error : ndarray, shape (...)
        Final distance from the end effector to the target.

    Raises
    ------
    ValueError
        If an argument has the wrong shape or is not finite.
    """
    from course.rotations._checks import as_array

    P = as_array(positions, "positions", (3,))
    t = as_array(target, "target", (3,))
    if P.ndim < 2 or P.shape[-2] < 2:
        raise ValueError(f"positions: expected shape (..., n, 3) with n >= 2, got {P.shape}")
    batch = np.broadcast_shapes(P.shape[:-2], t.shape[:-1])
    n = P.shape[-2]
    P = np.broadcast_to(P, batch + (n, 3)).reshape(-1, n, 3).copy()
    t = np.broadcast_to(t, batch + (3,)).reshape(-1, 3)
    its, err = _fabrik_chain(P, t, tol, max_iter)
    return P.reshape(batch + (n, 3)), its.reshape(batch), err.reshape(batch)


def fabrik_batch(
    positions: ArrayLike, targets: ArrayLike, tol: float = 1e-4, max_iter: int = 100
) -> tuple[Array, Array, Array]:
    """:func:`fabrik_positions` for many targets: ``positions`` (n, 3) shared by all targets,
    or (B, n, 3); ``targets`` (B, 3). Returns positions (B, n, 3), iterations (B,), errors (B,)."""
    return fabrik_positions(np.asarray(positions, float)[..., None, :, :] if np.ndim(positions)
                            == 2 else positions, targets, tol, max_iter)


def _fabrik_chain(P: Array, t: Array, tol: float, max_iter: int,
                  errors: list | None = None) -> tuple[Array, Array]:
    """In-place FABRIK on (B, n, 3) chains; returns iterations and errors, both (B,);
    ``errors``, if given, receives the (B,) errors after every iteration.

    Runs :func:`course.ik._serial.fabrik_points` on component-major storage (each coordinate
    of each joint one contiguous (B,) row)."""
    comps = np.array(P.transpose(1, 2, 0))  # (n, 3, B), a copy the solver may write into
    points, its, err = fabrik_points([tuple(c) for c in comps], tuple(np.array(t.T)), tol,
                                     max_iter, ARRAYS, errors=errors)
    P[:] = np.moveaxis(np.array(points), -1, 0)
    return its, err


def solve_problem(
    problem: Problem, tol: float, max_iter: int, record: bool = False
) -> tuple[Array, History, list[Array]]:
    """FABRIK on a :class:`~course.ik._chains.Problem` (any tree of paths, several effectors).

    Plain chains of unconstrained ball joints iterate on positions alone and fit rotations
    once at the end (exact: the positions are reachable). Otherwise the backward pass is done
    in joint space, level by level (:meth:`Problem.fit`), so the branch rigidity, hinge axes
    and limits shape every iteration and every residual is that of a real pose.
    """
    m = problem.model
    if len(m.rot_effectors):
        raise ValueError("targets: FABRIK reaches positions only; use a Jacobian method "
                         "(e.g. method='dls') for orientation targets")
    Rn = problem.Rn
    _, p = problem.forward(Rn)
    lengths = norm(m.bone)
    branching = np.bincount(m.parent[1:], minlength=m.n_nodes).max() > 1
    free = (not branching and not m.hinge.any() and not np.isfinite(problem.ball_limit).any()
            and len(m.effectors) == 1 and m.effectors[0] == m.n_nodes - 1 and not record)
    err = norm(problem.target_pos - p[:, m.effectors]).max(axis=1)
    if free:
        P, errors = p.copy(), []
        its, err = _fabrik_chain(P, problem.target_pos[:, 0], tol, max_iter, errors)
        Rn = problem.fit_free(Rn, P)
        history = History(norm(problem.target_pos - p[:, m.effectors]).max(axis=1), tol, max_iter)
        history.iterations = its
        # The points' errors stand for the iterations; the last is that of the fitted pose.
        history.residuals += errors[:-1]
        history.residuals.append(problem.error(*problem.forward(Rn))[1])
        history.active[:] = False
        return Rn, history, []

    history = History(err, tol, max_iter)
    frames = [Rn] if record else []
    count = np.bincount(m.parent[1:], minlength=m.n_nodes).astype(float)
    is_eff = np.zeros(m.n_nodes, dtype=bool)
    is_eff[m.effectors] = True
    deepest_first = m.levels[:0:-1]
    while history.active.any():
        P = p.copy()
        P[:, m.effectors] = problem.target_pos
        old = p
        for lvl in deepest_first:  # forward reaching, sub-bases to the centroid
            par = m.parent[lvl]
            fallback = old[:, par] - old[:, lvl]
            fallback /= np.maximum(norm(fallback), TINY)[..., None]
            proposal = _toward(P[:, lvl], P[:, par], lengths[lvl], fallback)
            acc = np.zeros_like(P)
            np.add.at(acc, (slice(None), par), proposal)
            moved = np.unique(par)
            keep = moved[is_eff[moved]]
            P[:, moved] = acc[:, moved] / count[moved][:, None]
            P[:, keep] = _targets_at(problem, keep)
        new = problem.fit(Rn, P)  # backward reaching from the fixed joint, in joint space
        Rn = np.where(history.active[:, None, None, None], new, Rn)
        M, p = problem.forward(Rn)
        history.update(problem.error(M, p)[1])
        if record:
            frames.append(Rn)
    return Rn, history, frames


def _targets_at(problem: Problem, nodes: NDArray[np.int_]) -> Array:
    """Targets of effector ``nodes``, (B, len(nodes), 3)."""
    where = {int(e): i for i, e in enumerate(problem.model.effectors)}
    return problem.target_pos[:, [where[int(u)] for u in nodes]]
