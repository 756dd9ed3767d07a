r"""The reach-aware start both engines give a serial chain whose target lies at or near its
full reach: the chain bent evenly in a plane so that its chord is the target's distance, and
aimed at the target.

Why: near the stretched pose the effector's distance from the fixed joint changes with the
*square* of the bend, so every iterative method crawls there: the Jacobian loses rank along
the line (Jacobian transpose and DLS creep, DLS's damping dominates the small singular
value), CCD zig-zags (each joint turns the end towards the target and away from the reach it
needs), FABRIK's passes shrink the error by a factor close to 1. Measured on 40 random chains
(``benchmarks/ik.py --reach``): at 0.999 of the reach CCD, FABRIK and the transpose
converged on 0-1 of 40, DLS on 21; at 0.95 CCD on 15. Far from the reach none of this
applies, and the start is the given pose.

The bend: bone :math:`k` (in-plane length :math:`L_k`) points along
:math:`\cos\alpha_k\,\hat u + \sin\alpha_k\,\hat v` with :math:`\alpha_k = \alpha_0 - k\theta`
(every joint turns by the same :math:`\theta`), so the chord is
:math:`|C(\theta)|`, :math:`C(\theta) = \sum_k L_k e^{-ik\theta}`; :math:`\theta` solves
:math:`|C(\theta)| = d` (bisection: :math:`|C|` falls from the reach at :math:`\theta = 0`) and
:math:`\alpha_0 = -\arg C(\theta)` turns the chord onto :math:`\hat u`, the direction to the
target. At or beyond the reach :math:`\theta = 0`: the stretched pose. The joints that can take
it: a chain of ball joints (the plane through the target and the chain's present bulge) or of
hinges about one axis (the plane perpendicular to it, each bone keeping its part along the
axis; a target off that plane gets the in-plane answer, its best).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from course._typing import Array
from course.rotations._kernels import TINY, cross, dot, norm

# Targets at least this share of the (in-plane) reach from the fixed joint start bent to
# their distance; below it the given pose is kept, so an ordinary solve stays as it was. The
# crawl begins about here: from the given pose, at 0.9 CCD converged on 27-29 of 40 chains
# and the others on 37-40, at 0.95 CCD on 15-16 and the transpose on 29-35.
REACH_START = 0.9
# Bisection steps of the bend angle: the bracket [0, pi / (n - 1)] shrinks to rounding.
_STEPS = 60


def bend_angle(lengths: Array, d: Array) -> tuple[Array, NDArray[np.bool_]]:
    r"""The turn :math:`\theta` (B,) of every joint that makes the chord of bones ``lengths``
    (B, K) equal ``d`` (B,), and whether a bend in :math:`[0, \pi/(K-1)]` has that chord (no
    for one bone short of ``d``, or a bone so long that the others cannot fold it to ``d``).
    :math:`\theta = 0` at or beyond the reach."""
    B, K = lengths.shape
    if K < 2:  # one bone: straight is its only pose
        return np.zeros(B), d >= lengths.sum(axis=1)
    k = np.arange(K)

    def chord(theta: Array) -> Array:
        c, s = np.cos(k * theta[:, None]), np.sin(k * theta[:, None])
        return np.asarray(np.hypot((lengths * c).sum(axis=1), (lengths * s).sum(axis=1)))

    lo, hi = np.zeros(B), np.full(B, np.pi / (K - 1))
    ok = chord(hi) <= d
    for _ in range(_STEPS):
        mid = 0.5 * (lo + hi)
        longer = chord(mid) > d
        lo, hi = np.where(longer, mid, lo), np.where(longer, hi, mid)
    beyond = d >= lengths.sum(axis=1)
    return np.where(beyond, 0.0, 0.5 * (lo + hi)), ok | beyond


def reach_points(p: Array, target: Array, normal: Array | None,
                 tol: float) -> tuple[Array, NDArray[np.bool_], NDArray[np.bool_]] | None:
    r"""Where the reach-aware start puts a serial chain's joints, and which problems take it.

    Parameters
    ----------
    p : ndarray, shape (B, N, 3)
        The chain's joint positions, ``p[:, 0]`` the fixed joint, ``p[:, -1]`` the effector.
    target : ndarray, shape (B, 3)
    normal : ndarray, shape (B, 3), or None
        The common world axis of a chain of hinges (unit), None for a chain of ball joints.
    tol : float
        A problem already within ``tol`` of its target keeps its pose.

    Returns
    -------
    (wanted, need, straight) : ndarray (B, N, 3), bool ndarrays (B,), or None
        The bent joint positions (the bones' lengths and, for hinges, their parts along the
        axis kept), the problems whose target lies at :data:`REACH_START` or more of the
        in-plane reach, unreached and bendable to its distance, and those of them stretched
        straight (the target at or beyond the reach); None when no problem is near.
    """
    root = p[:, :1]
    bones = np.diff(p, axis=1)  # (B, K, 3)
    rel = target - root[:, 0]
    rel_all = p - root
    if normal is None:  # balls: the plane through the target and the chain's present bulge
        axial = np.zeros(bones.shape[:2])
        flat, w = bones, rel
    else:
        axial = dot(bones, normal[:, None])
        flat = bones - axial[..., None] * normal[:, None]
        w = rel - dot(rel, normal)[:, None] * normal
    lengths = norm(flat)
    reach = lengths.sum(axis=1)
    d = norm(w)
    need = ((d >= REACH_START * reach) & (d > TINY * np.maximum(reach, TINY))
            & (norm(target - p[:, -1]) >= tol))
    if not need.any():
        return None
    # The rest only for the problems near the reach (a large batch has few).
    rows = np.flatnonzero(need)
    p, rel_all, axial, lengths, d, reach = (a[rows] for a in (p, rel_all, axial, lengths, d,
                                                              reach))
    normal = None if normal is None else normal[rows]
    u = w[rows] / d[:, None]
    bulge = (rel_all - dot(rel_all, u[:, None])[..., None] * u[:, None]).sum(axis=1)
    if normal is None:
        # Straight on the line: the deterministic perpendicular of bend_increment.
        perp = cross(u, np.eye(3)[np.argmin(np.abs(u), axis=-1)])
        bent = norm(bulge) > 1e-9 * reach
        v = np.where(bent[:, None], bulge, perp)
    else:
        v = cross(normal, u)
        v = np.where((dot(bulge, v) < 0)[:, None], -v, v)  # bend the way it bulges now
    v = v / np.maximum(norm(v), TINY)[:, None]
    theta, ok = bend_angle(lengths, d)
    k = np.arange(lengths.shape[1])
    a0 = np.arctan2((lengths * np.sin(k * theta[:, None])).sum(axis=1),
                    (lengths * np.cos(k * theta[:, None])).sum(axis=1))
    alpha = (a0[:, None] - k * theta[:, None])[..., None]  # (n, K, 1)
    step = lengths[..., None] * (np.cos(alpha) * u[:, None] + np.sin(alpha) * v[:, None])
    if normal is not None:
        step = step + axial[..., None] * normal[:, None]
    wanted = root.repeat(p.shape[1], axis=1)  # the others' rows: never used
    wanted[rows] = np.concatenate([p[:, :1], p[:, :1] + np.cumsum(step, axis=1)], axis=1)
    need[rows] = ok
    straight = np.zeros_like(need)
    straight[rows] = ok & (theta == 0.0)
    return (wanted, need, straight) if need.any() else None
