r"""FABRIK: Forward And Backward Reaching Inverse Kinematics (Aristidou & Lasenby 2011).

FABRIK works on joint *positions*. With bone lengths :math:`d_i = \lVert p_{i+1} - p_i\rVert`
(:func:`fabrik_positions` is the loop below, batched over leading dimensions):

* **forward reaching** (end to root): put the end effector on the target,
  :math:`p_n \leftarrow t`, then pull each joint towards its successor,
  :math:`p_i \leftarrow p_{i+1} + d_i\,\widehat{(p_i - p_{i+1})}`;
* **backward reaching** (root to end): put the root back, :math:`p_0 \leftarrow b`, then
  :math:`p_{i+1} \leftarrow p_i + d_i\,\widehat{(p_{i+1} - p_i)}`.

A target farther than :math:`\sum d_i - tol` is answered in one pass: the chain stretched
straight towards it (within ``tol`` of the target, or its closest pose). With several end
effectors each sub-chain is reached from its end to its *sub-base* (a joint where chains
meet), the sub-base goes to the centroid of the positions the sub-chains ask for, and reaching
continues to the root; the backward pass then runs outward from the root through every branch.

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

from course._typing import Array
from course._validate import as_point_chains
from course.rotations._kernels import TINY


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
        Same root, same bone lengths; stretched straight towards a target at (within
        ``tol``) or beyond the reach.
    iterations : ndarray of int, shape (...)
        Forward-and-backward passes used (0 if already there, 1 for a stretch).
    error : ndarray, shape (...)
        Final distance from the end effector to the target.

    Raises
    ------
    ValueError
        If an argument has the wrong shape or is not finite.
    """
    P, t, batch = as_point_chains(positions, target)
    n = P.shape[-2]
    its, err = _fabrik(P, t, tol, max_iter)
    return P.reshape(batch + (n, 3)), its.reshape(batch), err.reshape(batch)


def fabrik_batch(
    positions: ArrayLike, targets: ArrayLike, tol: float = 1e-4, max_iter: int = 100
) -> tuple[Array, Array, Array]:
    """:func:`fabrik_positions` for many targets: ``positions`` (n, 3) shared by all targets,
    or (B, n, 3); ``targets`` (B, 3). Returns positions (B, n, 3), iterations (B,), errors (B,)."""
    return fabrik_positions(np.asarray(positions, float)[..., None, :, :] if np.ndim(positions)
                            == 2 else positions, targets, tol, max_iter)


def _fabrik(P: Array, t: Array, tol: float, max_iter: int) -> tuple[Array, Array]:
    """FABRIK in place on chains ``P`` (B, n, 3) and targets ``t`` (B, 3); returns the
    iterations and errors, (B,) each. Each iteration runs only the problems still going."""
    lengths, rest = _bones(P)
    root = P[:, 0].copy()
    to_t = t - root
    dist = _length(to_t.T)
    # Stretched straight, the end is |dist - reach| from the target: within tol of the
    # reach that is the answer (iterating there crawls: at the reach 5 of 40 converged).
    far = (dist > lengths.sum(axis=0) - tol) & (_length((P[:, -1] - t).T) >= tol)
    if far.any():  # out of reach or at it: the chain stretched straight at the target
        u = to_t * (1.0 / np.where(dist > TINY, dist, 1.0))[:, None]
        reach = np.concatenate([np.zeros((1, len(P))), np.cumsum(lengths, axis=0)])
        P[far] = (root[:, None] + u[:, None] * reach.T[..., None])[far]
    err = _length((P[:, -1] - t).T)
    its = far.astype(int)
    active = ~far & (err >= tol)
    # Joint by joint, coordinate rows: p_i is (3, B), so each step runs on contiguous rows.
    joints = list(P.transpose(1, 2, 0).copy())
    t, root, rest = t.T, root.T, rest.transpose(0, 2, 1)
    for _ in range(max_iter):
        run = np.flatnonzero(active)
        if not len(run):
            break
        every = len(run) == len(P)  # every problem still going: no need to pick
        p, tr, d, r, b = (list(joints), t, lengths, rest, root) if every else (
            [q[:, run] for q in joints], t[:, run], lengths[:, run], rest[..., run], root[:, run])
        forward_reaching(p, tr, d, r)
        backward_reaching(p, b, d, r)
        joints = p if every else [_put(q, run, new) for q, new in zip(joints, p, strict=True)]
        err[run] = _length(p[-1] - tr)
        its[run] += 1
        active[run] = err[run] >= tol
    P[:] = np.array(joints).transpose(2, 0, 1)
    return its, err


def forward_reaching(p: list[Array], target: Array, lengths: Array, rest: Array) -> None:
    r"""FABRIK's forward pass, in place on the joint positions ``p`` (n arrays (3, B)): the
    end effector onto the target, :math:`p_{n-1} \leftarrow t`, then each joint pulled
    towards its successor, :math:`p_i \leftarrow p_{i+1} + d_i\,\widehat{(p_i - p_{i+1})}`,
    down to the root. ``lengths`` (n-1, B) are the bones :math:`d_i`, ``rest`` (n-1, 3, B)
    their unit directions, used where two joints coincide."""
    p[-1] = target
    for i in range(len(p) - 2, -1, -1):
        p[i] = _toward(p[i + 1], p[i], lengths[i], -rest[i])


def backward_reaching(p: list[Array], root: Array, lengths: Array, rest: Array) -> None:
    r"""FABRIK's backward pass, in place: the root back, :math:`p_0 \leftarrow b`, then each
    joint pulled towards its predecessor,
    :math:`p_{i+1} \leftarrow p_i + d_i\,\widehat{(p_{i+1} - p_i)}`, out to the end."""
    p[0] = root
    for i in range(len(p) - 1):
        p[i + 1] = _toward(p[i], p[i + 1], lengths[i], rest[i])


def _toward(fixed: Array, moved: Array, length: Array, fallback: Array) -> Array:
    """``fixed + length * unit(moved - fixed)`` (3, B); along ``fallback`` where the two
    points coincide (no direction to keep)."""
    d = moved - fixed
    n = _length(d)
    if (n < TINY).any():
        d = np.where(n < TINY, fallback, d)
        n = np.where(n < TINY, 1.0, n)
    return fixed + d * (length / n)


def _bones(P: Array) -> tuple[Array, Array]:
    """Bone lengths (n-1, B) and unit bone directions (n-1, B, 3) of chains ``P`` (B, n, 3)
    (+y for a zero bone)."""
    d = np.moveaxis(P[:, 1:] - P[:, :-1], 1, 0)
    lengths = _length(np.moveaxis(d, -1, 0))
    ok = lengths > TINY
    rest = np.where(ok[..., None], d * (1.0 / np.where(ok, lengths, 1.0))[..., None],
                    [0.0, 1.0, 0.0])
    return lengths, rest


def _put(full: Array, run: NDArray[np.intp], part: Array) -> Array:
    """A copy of ``full`` (3, B) with its columns ``run`` replaced by ``part``."""
    out: Array = full.copy()
    out[:, run] = part
    return out


def _length(v: Array) -> Array:
    r"""Euclidean length :math:`\sqrt{x^2 + y^2 + z^2}` of vectors ``v`` (3, ...)."""
    x, y, z = v
    out: Array = np.sqrt(x * x + y * y + z * z)
    return out
