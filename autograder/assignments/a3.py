r"""Assignment a3, inverse kinematics: the spec ``assignments/a3_inverse_kinematics.py`` is
checked by.

IK has many right answers, so the solvers are graded by what they achieve, never by
matching one reference pose: the root stays where it was, every bone keeps its length, the
end effector is on the target (or, out of reach, the chain is stretched straight towards
it), and the solver stops after ``max_iter`` iterations (a per-case time limit catches one
that does not). ``two_link_ik`` has a unique answer, checked against the law of cosines and
the pole's plane; ``jacobian`` against finite differences of the hinge chain;
``dls_step`` against the damped normal equations
:math:`\Delta\theta = J^T(JJ^T + \lambda^2 I)^{-1} e`. Mistakes of the iterative solvers are
recognised by their symptoms (the root moved, the bone lengths came out reversed, ...).
Reference: :mod:`course.ik` and numpy closed forms.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from course import rotations as rot
from course.ik import ccd_positions, fabrik_positions, two_link

from ..catalogue import pivot_mistakes
from ..checks import Check, PointsCheck, TupleCheck, show
from ..spec import Assignment, Case, Function, Misconception, Picture, Test, random_edge_hidden

ROOT_TOL = 1e-6  # times the chain's length: how far the root and the bone lengths may drift
STRETCH_TOL = 1e-3  # times the chain's length: how close to straight an out-of-reach chain ends


def _norm(v: np.ndarray) -> np.ndarray:
    n: np.ndarray = np.linalg.norm(v, axis=-1)
    return n


def bones(P: np.ndarray) -> np.ndarray:
    """Bone lengths ``|p_{i+1} - p_i|`` of a chain ``(n, 3)``: shape ``(n - 1,)``."""
    return _norm(np.diff(P, axis=0))


def chain_problems(got: np.ndarray, P: np.ndarray, target: np.ndarray, tol: float) -> list[str]:
    """What is wrong with ``got`` as an IK answer for the chain ``P`` and ``target``, worst
    first: a moved root, changed bone lengths, an end effector short of the target."""
    d_in, d_got = bones(P), bones(got)
    reach = float(d_in.sum())
    slack = ROOT_TOL * max(reach, 1.0)
    out = []
    if _norm(got[0] - P[0]) > slack:
        out.append(f"the root moved from {show(P[0])} to {show(got[0])}; it is fixed")
    bad = np.flatnonzero(np.abs(d_got - d_in) > slack)
    if bad.size:
        i = int(bad[0])
        out.append(f"bone {i} (joint {i} to {i + 1}) has length {d_got[i]:.4g}, was "
                   f"{d_in[i]:.4g}" + (f" ({bad.size} bones changed)" if bad.size > 1 else "")
                   + "; joints turn, bones keep their lengths")
    miss = float(_norm(got[-1] - target))
    far = float(_norm(target - P[0]))
    if far <= reach:
        if miss > max(tol, slack) * (1 + 1e-9):
            out.append(f"the end effector stopped {miss:.3g} from the target (tol = {tol:g})")
    elif miss > far - reach + STRETCH_TOL * reach:
        out.append(f"the target is out of reach ({far:.4g} from the root, the chain is "
                   f"{reach:.4g} long): the best is the chain stretched straight at it, "
                   f"{far - reach:.4g} away; yours stopped {miss:.4g} away")
    return out


class ChainCheck(Check):
    """An IK answer ``(n, 3)`` for ``(positions, target, tol, max_iter)``, judged by what it
    achieves (root, bone lengths, reach), not by the reference's pose."""

    def __init__(self) -> None:
        super().__init__(None, noun="chain")

    def judge(self, got: Any, expected: Any, args: tuple[Any, ...]) -> str | None:
        problems = chain_problems(got, args[0], args[1], args[2])
        return problems[0] if problems else None

    def show_expected(self, expected: Any, digits: int = 3) -> str:
        return "the root fixed, the bone lengths kept and the end effector on the target"


class CurveCheck(Check):
    """``trace_curve``'s poses ``(K, n, 3)``: every pose a valid IK answer for its point."""

    def __init__(self) -> None:
        super().__init__(None, noun="poses")

    def judge(self, got: Any, expected: Any, args: tuple[Any, ...]) -> str | None:
        P, curve, tol = args[0], args[1], args[2]
        for k, point in enumerate(curve):
            problems = chain_problems(got[k], P, point, tol)
            if problems:
                path = float(np.max(_norm(got[:, -1] - curve)))
                return (f"at curve point {k}, {problems[0]} (the traced path is up to "
                        f"{path:.3g} from the curve)")
        return None

    def show_expected(self, expected: Any, digits: int = 3) -> str:
        return "one pose per curve point, each with the end effector on that point"


class TwoLinkCheck(TupleCheck):
    """``(mid, end)``, checked against the law of cosines and the plane of the pole."""

    def __init__(self) -> None:
        super().__init__((PointsCheck(shape=(3,), row="coordinate"),
                          PointsCheck(shape=(3,), row="coordinate")), ("mid", "end"))

    def judge(self, got: Any, expected: Any, args: tuple[Any, ...]) -> str | None:
        problems = two_link_problems(got, *args)
        return problems[0] if problems else None

    def show_expected(self, expected: Any, digits: int = 3) -> str:
        return f"(mid, end) = {super().show_expected(expected, digits)}"


def two_link_problems(got, root, mid, end, target, pole) -> list[str]:
    new_mid, new_end = got
    l1, l2 = float(_norm(mid - root)), float(_norm(end - mid))
    slack = ROOT_TOL * max(l1 + l2, 1.0)
    out = []
    for name, a, b, length in (("upper", root, new_mid, l1), ("lower", new_mid, new_end, l2)):
        if abs(float(_norm(b - a)) - length) > slack:
            out.append(f"the {name} bone has length {float(_norm(b - a)):.4g}, was {length:.4g}")
    d = float(_norm(target - root))
    best = max(d - (l1 + l2), abs(l1 - l2) - d, 0.0)
    miss = float(_norm(new_end - target))
    if abs(miss - best) > slack:
        where = "on the target" if best == 0 else f"{best:.4g} from it (as close as it gets)"
        out.append(f"the end is {miss:.4g} from the target, expected {where}")
    plane = _pole_plane(root, target, pole)
    if plane is not None and best == 0 and d < l1 + l2 - slack:
        n, normal = plane
        off = float(normal @ (new_mid - root))
        if abs(off) > slack:
            out.append(f"the middle joint is {abs(off):.3g} off the plane through root, target "
                       "and pole")
        elif n @ (new_mid - root) < -slack:
            out.append("the middle joint bends away from the pole")
    return out


def _pole_plane(root, target, pole):
    """(unit bend direction n, unit plane normal), or None if the pole is on the axis."""
    u = (target - root) / _norm(target - root)
    v = pole - root
    n = v - (v @ u) * u
    if _norm(n) < 1e-6 * max(float(_norm(v)), 1.0):
        return None
    n = n / _norm(n)
    return n, np.cross(u, n)


# --- random chains and targets -----------------------------------------------------------------


def random_chain(rng: np.random.Generator, n: int, bend: float = 0.6) -> np.ndarray:
    """``n`` points from a random root: bone lengths 0.5-2, each turned up to ``bend`` rad
    from the previous one (so the chain is neither straight nor folded)."""
    P = [rng.normal(0, 1, 3)]
    d = rng.normal(size=3)
    d /= _norm(d)
    for _ in range(n - 1):
        turn = rng.normal(size=3)
        turn -= (turn @ d) * d
        d = rot.quat_rotate(rot.quat_from_axis_angle(turn / _norm(turn), rng.uniform(0.1, bend)),
                            d)
        P.append(P[-1] + rng.uniform(0.5, 2.0) * d)
    return np.array(P)


def _direction(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    unit: np.ndarray = v / _norm(v)
    return unit


def reachable_target(rng: np.random.Generator, P: np.ndarray, lo=0.25, hi=0.85) -> np.ndarray:
    target: np.ndarray = P[0] + rng.uniform(lo, hi) * bones(P).sum() * _direction(rng)
    return target


def _solves(method, P, t, tol, max_iter) -> bool:
    """Whether the reference reaches ``t`` within a quarter of ``max_iter`` (so a correct
    solver that differs in its details has room to spare)."""
    got = method(P, t, tol, max(1, max_iter // 4))
    return not chain_problems(got, P, t, tol)


def ik_cases(rng, method, max_iter: int, count: int, label: str) -> list[Case]:
    out: list[Case] = []
    while len(out) < count:
        n = int(rng.integers(3, 9))
        P = random_chain(rng, n)
        t = reachable_target(rng, P)
        if _solves(method, P, t, 1e-4, max_iter):
            out.append(Case(f"{label} #{len(out) + 1}: {n} joints, a reachable target",
                            (P, t, 1e-4, max_iter)))
    return out


def ik_edges(rng, method, max_iter: int) -> list[Case]:
    P = random_chain(rng, 5)
    reach = bones(P).sum()
    one = random_chain(rng, 2)
    straight = np.outer(np.arange(5.0), [0.0, 0.0, 1.0])
    long = random_chain(rng, 12, bend=0.3)
    tight = random_chain(rng, 4)
    while True:
        t = reachable_target(rng, tight, 0.5, 0.7)
        if _solves(method, tight, t, 1e-9, 60):
            break
    return [
        Case("the target out of reach (1.5 × the chain's length): stretch towards it",
             (P, P[0] + 1.5 * reach * _direction(rng), 1e-4, max_iter)),
        Case("the target on the last bone (the last joint has no turn to make)",
             (P, 0.6 * P[-1] + 0.4 * P[-2], 1e-4, max_iter)),
        Case("one bone, the target out of reach: it can only turn towards it",
             (one, one[0] + 1.3 * bones(one)[0] * _direction(rng), 1e-4, max_iter)),
        Case("a straight chain, target off to the side",
             (straight, np.array([1.5, 0.5, 2.0]), 1e-4, max_iter)),
        Case("a straight chain, the target straight behind it (e - r_i and t - r_i point "
             "opposite ways: a half turn, not none)",
             (straight, np.array([0.0, 0.0, -2.0]), 1e-4, max_iter)),
        Case("a long chain (12 joints)", (long, reachable_target(rng, long), 1e-4, max_iter)),
        Case("tol = 0 is never met: stop after max_iter = 60", (tight, t, 0.0, 60)),
    ]


def _ccd(P, t, tol, max_iter):
    return ccd_positions(P, t, tol, max_iter)[0]


def _fabrik(P, t, tol, max_iter):
    return fabrik_positions(P, t, tol, max_iter)[0]


CCD_ITER, FABRIK_ITER = 200, 100


def ccd_random(rng: np.random.Generator) -> list[Case]:
    return ik_cases(rng, _ccd, CCD_ITER, 6, "random chain")


def ccd_edges(rng: np.random.Generator) -> list[Case]:
    return ik_edges(rng, _ccd, CCD_ITER)


def ccd_hidden(rng: np.random.Generator) -> list[Case]:
    return _hidden_ik_cases(rng, _ccd, CCD_ITER)


def fabrik_random(rng: np.random.Generator) -> list[Case]:
    return ik_cases(rng, _fabrik, FABRIK_ITER, 6, "random chain")


def fabrik_edges(rng: np.random.Generator) -> list[Case]:
    return ik_edges(rng, _fabrik, FABRIK_ITER)


def fabrik_hidden(rng: np.random.Generator) -> list[Case]:
    return _hidden_ik_cases(rng, _fabrik, FABRIK_ITER)


def _hidden_ik_cases(rng: np.random.Generator, solver: Callable[..., np.ndarray],
                     max_iter: int) -> list[Case]:
    """Random reachable chains plus one target twice the chain's reach away."""
    cases = ik_cases(rng, solver, max_iter, 8, "hidden chain")
    P = random_chain(rng, 6)
    far = P[0] + 2 * bones(P).sum() * _direction(rng)
    return cases + [Case("hidden: out of reach", (P, far, 1e-4, max_iter))]


def _two_link_case(rng, label: str, d_frac: float) -> Case:
    a, b, c = random_chain(rng, 3, bend=1.5)
    l1, l2 = _norm(b - a), _norm(c - b)
    t = a + d_frac * (l1 + l2) * _direction(rng)
    pole = a + 2 * _direction(rng)
    return Case(label, (a, b, c, t, pole))


def two_link_random(rng: np.random.Generator) -> list[Case]:
    return [_two_link_case(rng, f"random limb #{i + 1}", rng.uniform(0.4, 0.95))
            for i in range(8)]


def two_link_edges(rng: np.random.Generator) -> list[Case]:
    a, b, c = np.zeros(3), np.array([0.0, -1.0, 0.1]), np.array([0.0, -2.0, 0.0])
    l1, l2 = 1.0, float(_norm(c - b))
    knee_front = np.array([0.0, -1.0, 5.0])
    return [
        Case("a leg: hip, knee, ankle; the knee bends towards a pole in front",
             (a, b, c, np.array([0.3, -1.5, 0.4]), knee_front)),
        Case("the pole behind the leg: the knee bends backwards",
             (a, b, c, np.array([0.0, -1.6, 0.0]), np.array([0.0, -1.0, -5.0]))),
        Case("the target out of reach: the limb points straight at it",
             (a, b, c, np.array([1.0, -3.0, 1.0]), knee_front)),
        Case("the target at exactly full reach", (a, b, c, np.array([0.0, -(l1 + l2), 0.0]),
                                                  knee_front)),
        Case("the target too close to fold to (d < |l1 - l2|)",
             (np.zeros(3), np.array([2.0, 0.0, 0.0]), np.array([2.0, 0.5, 0.0]),
              np.array([0.3, 0.2, 0.0]), np.array([0.0, 0.0, 3.0]))),
        _two_link_case(rng, "a random limb, the target close to the root", 0.15),
    ]


def two_link_hidden(rng: np.random.Generator) -> list[Case]:
    return [_two_link_case(rng, f"hidden limb #{i + 1}", rng.uniform(0.1, 1.3)) for i in range(16)]


def hinge_chain(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` hinge joints and the end effector (``(n + 1, 3)``), and unit world axes ``(n, 3)``."""
    P = random_chain(rng, n + 1, bend=1.0)
    axes = rng.normal(size=(n, 3))
    return P, axes / _norm(axes)[:, None]


def jacobian_reference(positions, axes, eps: float = 1e-6):
    """Central differences of the effector when hinge ``i`` turns by ``±eps`` about ``a_i``
    through ``r_i`` (Rodrigues), independent of the closed form ``a_i × (e - r_i)``."""
    e = positions[-1]
    cols = []
    for r, a in zip(positions[:-1], axes, strict=False):
        moved = [r + rot.matrix_from_axis_angle(a, s * eps) @ (e - r) for s in (1, -1)]
        cols.append((moved[0] - moved[1]) / (2 * eps))
    return np.stack(cols, axis=1)


def jacobian_random(rng: np.random.Generator) -> list[Case]:
    return [Case(f"random hinge chain #{i + 1} ({n} joints)", hinge_chain(rng, n))
            for i, n in enumerate((1, 2, 3, 5, 8))]


def jacobian_edges(rng: np.random.Generator) -> list[Case]:
    planar = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [2.5, 1, 0]], dtype=float)
    z = np.tile([0.0, 0.0, 1.0], (3, 1))
    P, axes = hinge_chain(rng, 3)
    along = axes.copy()
    along[1] = (P[-1] - P[1]) / _norm(P[-1] - P[1])
    return [
        Case("a planar chain, every axis along z", (planar, z)),
        Case("an axis pointing at the end effector: its column is zero", (P, along)),
        Case("the end effector on a joint: its column is zero",
             (np.vstack([P[:3], P[2]]), axes)),
        Case("a stretched chain (a singular pose)",
             (np.outer(np.arange(4.0), [1.0, 0, 0]), np.tile([0.0, 1.0, 0.0], (3, 1)))),
    ]


def jacobian_hidden(rng: np.random.Generator) -> list[Case]:
    return [Case(f"hidden hinge chain #{i + 1}", hinge_chain(rng, int(rng.integers(1, 9))))
            for i in range(10)]


def dls_reference(J, error, damping):
    """:math:`J^T (J J^T + \\lambda^2 I)^{-1} e`, solved rather than inverted."""
    m = J.shape[0]
    return J.T @ np.linalg.solve(J @ J.T + damping**2 * np.eye(m), error)


def dls_random(rng: np.random.Generator) -> list[Case]:
    out = []
    for m, n in ((3, 2), (3, 3), (3, 5), (3, 8), (2, 4), (6, 7)):
        damping = float(rng.choice([0.05, 0.3, 1.0]))
        out.append(Case(f"random J {m}×{n}, λ = {damping:g}", (rng.normal(size=(m, n)),
                                                                 rng.normal(size=m), damping)))
    return out


def dls_edges(rng: np.random.Generator) -> list[Case]:
    P = np.outer(np.arange(4.0), [1.0, 0, 0])
    J_stretched = jacobian_reference(P, np.tile([0.0, 0.0, 1.0], (3, 1)))  # all columns along y
    return [
        Case("a stretched chain (rank 1), the error along x where it cannot move: dθ = 0",
             (J_stretched, np.array([1.0, 0.0, 0.0]), 0.1)),
        Case("a stretched chain (rank 1), the error along y", (J_stretched,
                                                                np.array([0.0, 1.0, 0.5]), 0.1)),
        Case("a nearly stretched chain, small λ: the step stays bounded",
             (jacobian_reference(P + [[0, 0, 0], [0, 1e-4, 0], [0, 0, 0], [0, 0, 0]],
                                 np.tile([0.0, 0.0, 1.0], (3, 1))),
              np.array([1.0, 0.2, 0.0]), 0.01)),
        Case("λ = 0 and full rank: the pseudo-inverse step J⁺e", (rng.normal(size=(3, 5)),
                                                                  rng.normal(size=3), 0.0)),
        Case("a large λ = 100: almost J^T e / λ²", (rng.normal(size=(3, 4)), rng.normal(size=3),
                                                    100.0)),
        Case("λ = 2 (is it squared?)", (rng.normal(size=(3, 3)), rng.normal(size=3), 2.0)),
    ]


def dls_hidden(rng: np.random.Generator) -> list[Case]:
    return [Case(f"hidden J #{i + 1}", (rng.normal(size=(3, n)), rng.normal(size=3),
                                        float(rng.uniform(0.01, 2.0))))
            for i, n in enumerate(rng.integers(2, 9, 10))]


def trace_reference(positions, curve, tol, max_iter):
    """FABRIK from point to point, each solve starting from the previous pose."""
    poses, P = [], positions
    for point in curve:
        P = _fabrik(P, point, tol, max_iter)
        poses.append(P)
    return np.array(poses)


def _curve_case(rng, label: str, n: int, k: int) -> Case:
    """A figure eight the reference traces point by point within a quarter of its iterations
    (a chain with one dominant bone cannot reach points near its root: drawn again)."""
    while True:
        P = random_chain(rng, n)
        reach = bones(P).sum()
        u, w = _direction(rng), _direction(rng)
        w -= (w @ u) * u
        w /= _norm(w)
        s = np.linspace(0, 2 * np.pi, k, endpoint=False)
        centre = P[0] + 0.4 * reach * _direction(rng)
        curve = centre + 0.3 * reach * (np.cos(s)[:, None] * u + np.sin(2 * s)[:, None] * w / 2)
        poses = trace_reference(P, curve, 1e-4, max(1, FABRIK_ITER // 4))
        if not any(chain_problems(pose, P, point, 1e-4) for pose, point in zip(
                poses, curve, strict=True)):
            return Case(label, (P, curve, 1e-4, FABRIK_ITER))


def trace_visible(rng: np.random.Generator) -> list[Case]:
    return [_curve_case(rng, f"a figure eight of {k} points, {n} joints", n, k)
            for n, k in ((4, 24), (7, 40))]


def trace_hidden(rng: np.random.Generator) -> list[Case]:
    return [_curve_case(rng, f"hidden curve #{i + 1}", int(rng.integers(3, 8)), 30)
            for i in range(3)]


# --- the catalogue of known mistakes -----------------------------------------------------------


def _unchanged(got, positions, target, *_):
    return np.allclose(got, positions, atol=1e-12) and not np.allclose(positions[-1], target)


def _root_moved_lengths_kept(got, positions, *_):
    return (_norm(got[0] - positions[0]) > 1e-6
            and np.allclose(bones(got), bones(positions), atol=1e-6))


def _lengths_reversed(got, positions, *_):
    d, g = bones(positions), bones(got)
    return not np.allclose(d, d[::-1], atol=1e-6) and np.allclose(g, d[::-1], atol=1e-6)


def _effector_pivot(got, positions, target, *_):
    # (a one-bone chain turned about its effector does not move at all)
    return np.allclose(got[-1], positions[-1], atol=1e-9) and not np.allclose(positions[-1],
                                                                              target)


def ccd_turning(positions, target, tol, max_iter, lever: int = 0, half_turns: bool = True):
    """CCD as :func:`course.ik.ccd_positions` sweeps it, tip to root, except that the turn of
    joint i is measured from joint ``i + lever``: the shortest arc from e - r_{i+lever} to
    t - r_{i+lever}, applied about r_i (``lever = 1``: the wrong joint; a joint whose lever
    would be the effector itself has no turn). ``half_turns=False`` skips a joint whose two
    vectors are parallel or opposite (|u × v| = 0), as a CCD built on the cross product does.
    """
    P = np.array(positions, dtype=float)
    n = len(P)
    sweeps = 0
    while np.linalg.norm(P[-1] - target) >= tol and sweeps < max_iter:
        for i in range(n - 2, -1, -1):
            j = i + lever
            if j >= n - 1:
                continue
            u, v = P[-1] - P[j], target - P[j]
            if _norm(u) < 1e-12 or _norm(v) < 1e-12 or (
                    not half_turns and _norm(np.cross(u, v)) < 1e-12 * _norm(u) * _norm(v)):
                continue
            q = rot.quat_between(u, v)
            P[i + 1:] = P[i] + rot.quat_rotate(q, P[i + 1:] - P[i])
        sweeps += 1
    return P


def _same_chain(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and bool(np.all(np.abs(a - b) <= 1e-6 * max(1.0, bones(b).sum())))


def _wrong_joint(got, positions, target, tol, max_iter):
    return any(_same_chain(got, ccd_turning(positions, target, tol, max_iter, 1, half))
               for half in (True, False))


def _origin_pivot(got, positions, *_):
    """Every joint as far from the origin as it started (turns about the origin keep |p_k|,
    and nothing else does that in general) while the bones changed length. A simulation would
    not do: turned about the origin, CCD is chaotic, and rounding alone parts two runs."""
    scale = 1e-6 * max(1.0, float(bones(positions).sum()))
    return got.shape == positions.shape and bool(
        np.all(np.abs(_norm(got) - _norm(positions)) <= scale)
        and not np.allclose(bones(got), bones(positions), atol=scale))


def _antiparallel_skipped(got, positions, target, *_):
    """Unchanged on a chain where every e - r_i points straight away from t - r_i."""
    u, v = positions[-1] - positions[:-1], target - positions[:-1]
    straight_away = np.all(np.linalg.norm(np.cross(u, v), axis=1) <= 1e-9 * _norm(u) * _norm(v))
    return _unchanged(got, positions, target) and bool(
        straight_away and np.all(np.sum(u * v, axis=1) < 0))


def _axis_in_wrong_frame(got, positions, axes):
    """Columns perpendicular to their lever arms e - r_i (the lever is right) but not to the
    given world axes a_i (the axis is not)."""
    lever = positions[-1] - positions[:-1]
    cols = np.asarray(got).T
    scale = max(1.0, float(np.max(_norm(lever))))
    along_lever = np.abs(np.sum(cols * lever, axis=1)) <= 1e-6 * scale * scale
    along_axis = np.abs(np.sum(cols * axes, axis=1)) <= 1e-6 * scale
    return bool(np.all(along_lever) and not np.all(along_axis))


def _singular(J: np.ndarray) -> bool:
    return bool(np.linalg.cond(J @ J.T) > 1e10)


def _undamped(got, J, error, damping):
    """J⁺e where J Jᵀ can be inverted; where it cannot, a step beyond the damped bound
    |Δθ| <= |e| / 2λ (or not finite), as (J Jᵀ)⁻¹ of a singular matrix gives."""
    got = np.asarray(got, dtype=float)
    if np.allclose(got, dls_reference(J, error, damping), rtol=1e-6, atol=1e-9):
        return False  # right (with λ = 0 the damped step is J⁺e)
    if np.allclose(got, np.linalg.pinv(J) @ error, rtol=1e-6, atol=1e-9):
        return True
    if not _singular(J) or damping <= 0:
        return False
    return not np.all(np.isfinite(got)) or _norm(got) > _norm(error) / (2 * damping) * (1 + 1e-6)


def _undamped_error(error: dict[str, Any], J, e, damping) -> str | None:
    if error.get("type") != "LinAlgError" or not _singular(J):
        return None
    (m, n), rank = J.shape, np.linalg.matrix_rank(J)
    why = f"J has only {n} columns" if n < m else "a singular pose (the chain stretched)"
    return (f"here J Jᵀ ({m}×{m}) has rank {rank}: {why}, so (J Jᵀ)⁻¹ does not exist; "
            f"J Jᵀ + λ²I (λ = {damping:g}) is invertible for any λ > 0")


def _pole_ignored(got, root, mid, end, target, pole):
    problems = two_link_problems(got, root, mid, end, target, pole)
    return bool(problems) and all("plane" in p or "away from the pole" in p for p in problems)


UNCHANGED = ("the chain never moved",
             "Your function returned the positions it was given: does the loop run at all "
             "(iterate while |e - t| > tol and the count is below max_iter) and do you return "
             "the array you updated?")

MISCONCEPTIONS = (
    Misconception(
        "pole_ignored", "two_link_ik", "the pole ignored (the wrong bending plane)",
        "The law of cosines, cos α = (l₁² + d² - l₂²)/(2 l₁ d), fixes the middle joint only up "
        "to a circle about the root-target axis u; the pole picks the point: "
        "mid = root + l₁(cos α u + sin α n), n the pole direction made perpendicular to u.",
        symptom=_pole_ignored),
    Misconception(
        "antiparallel_skipped", "ccd", "a joint skipped when e - r_i and t - r_i are opposite",
        "When e - r_i and t - r_i point in opposite directions their cross product is 0 but the "
        "turn is a half turn, not none: R is the rotation by π about any axis perpendicular to "
        "e - r_i (say (e - r_i) × x̂, or × ŷ when that is 0), then p_k ← r_i + R(p_k - r_i).",
        symptom=_antiparallel_skipped),
    Misconception("unchanged", "ccd", *UNCHANGED, symptom=_unchanged),
    *pivot_mistakes("ccd", {"effector_pivot": _effector_pivot, "wrong_joint": _wrong_joint,
                            "origin_pivot": _origin_pivot}),
    Misconception("unchanged", "fabrik", *UNCHANGED, symptom=_unchanged),
    Misconception(
        "no_reanchor", "fabrik", "the root not re-anchored (no backward pass)",
        "After the forward pass (p_n ← t, then p_i ← p_{i+1} + d_i·unit(p_i - p_{i+1})) the "
        "root has drifted; the backward pass puts it back, p_0 ← b, then "
        "p_{i+1} ← p_i + d_i·unit(p_{i+1} - p_i).",
        symptom=_root_moved_lengths_kept),
    Misconception(
        "lengths_reversed", "fabrik", "bone lengths taken from the wrong end",
        "d_i = |p_{i+1} - p_i| is the bone between joints i and i+1, counted from the root; "
        "your bones come out with the lengths in reverse order (d_{n-1-i}), as when a pass "
        "indexes the lengths from the effector's end.",
        symptom=_lengths_reversed),
    Misconception(
        "sign_flipped", "jacobian", "the cross product the wrong way round",
        "Turning hinge i by dθ moves the effector by a_i × (e - r_i) dθ; a_i × (r_i - e) (or "
        "(e - r_i) × a_i) points the other way and every step goes away from the target.",
        wrong=lambda positions, axes: -jacobian_reference(positions, axes)),
    Misconception(
        "bone_lever", "jacobian", "the bone instead of the lever arm to the effector",
        "The column of joint i is a_i × (e - r_i), with e the END EFFECTOR: turning joint i "
        "swings the whole chain beyond it, not just the next joint (r_{i+1} - r_i).",
        wrong=lambda positions, axes: np.cross(axes, np.diff(positions, axis=0)).T),
    Misconception(
        "local_axes", "jacobian", "hinge axes in the wrong frame (local instead of world)",
        "J_i = a_i × (e - r_i) takes the world axis a_i = Q_i â_i, after the turns of the joints "
        "above i, which is what you are given; your columns are perpendicular to the lever arms "
        "e - r_i but not to a_i, as when a joint's local axis â_i (or another frame's) is used.",
        symptom=_axis_in_wrong_frame),
    Misconception(
        "no_damping", "dls_step", "no damping (the plain pseudo-inverse)",
        "Damped least squares adds λ² I before inverting, Δθ = Jᵀ(JJᵀ + λ²I)⁻¹ e, which keeps "
        "the step bounded (|Δθ| ≤ |e|/2λ) near singular poses; Jᵀ(JJᵀ)⁻¹e, or J⁺e, has no λ "
        "and explodes (or cannot be computed) where JJᵀ is singular.",
        symptom=_undamped, explains=_undamped_error),
    Misconception(
        "lambda_not_squared", "dls_step", "λ where λ² belongs",
        "damping is λ, and the term added is λ²I: Δθ = Jᵀ(JJᵀ + λ²I)⁻¹ e (it minimises "
        "|JΔθ - e|² + λ²|Δθ|²).",
        wrong=lambda J, error, damping: dls_reference(J, error, np.sqrt(damping))),
)

# --- pictures of a failing case ----------------------------------------------------------------


def _chain_parents(n: int) -> np.ndarray:
    return np.arange(-1, n - 1)


def chain_picture(got, expected, args) -> Picture:
    """A CCD or FABRIK answer: your chain and the reference's, from the start pose, with the
    target (the reference's pose is one right answer of many)."""
    P, target = args[0], args[1]
    return Picture("your chain and the reference solver's (one right answer of many)",
                   _chain_parents(len(P)), np.asarray(got), np.asarray(expected), start=P,
                   points=(("target", np.atleast_2d(target)),))


def two_link_picture(got, expected, args) -> Picture:
    root, mid, end, target, pole = args
    return Picture("your limb and the expected one, with the target and the pole",
                   _chain_parents(3), np.array([root, *got]), np.array([root, *expected]),
                   start=np.array([root, mid, end]),
                   points=(("target", np.atleast_2d(target)), ("pole", np.atleast_2d(pole))))


def curve_picture(got, expected, args) -> Picture:
    P, curve = args[0], args[1]
    return Picture("your last pose and path of the end effector, and the reference's",
                   _chain_parents(len(P)), np.asarray(got)[-1], np.asarray(expected)[-1],
                   start=P, points=(("curve", curve), ("your path", np.asarray(got)[:, -1])))


# --- the assignment ----------------------------------------------------------------------------

_FUNCTIONS = (
    Function("two_link_ik", ("root", "mid", "end", "target", "pole"),
             lambda *args: tuple(np.array(x) for x in two_link(*args)[:2]), TwoLinkCheck(),
             two_link_picture),
    Function("ccd", ("positions", "target", "tol", "max_iter"), _ccd, ChainCheck(),
             chain_picture),
    Function("fabrik", ("positions", "target", "tol", "max_iter"), _fabrik, ChainCheck(),
             chain_picture),
    Function("jacobian", ("positions", "axes"), jacobian_reference,
             Check(None, atol=1e-6)),
    Function("dls_step", ("J", "error", "damping"), dls_reference,
             Check(None, atol=1e-9, rtol=1e-6)),
    Function("trace_curve", ("positions", "curve", "tol", "max_iter"), trace_reference,
             CurveCheck(), curve_picture),
)


ASSIGNMENT = Assignment(
    key="a3",
    title="Inverse kinematics",
    template="a3_inverse_kinematics.py",
    functions=_FUNCTIONS,
    tests=(
        *random_edge_hidden("two_link_ik", two_link_random, two_link_edges, two_link_hidden),
        *random_edge_hidden("ccd", ccd_random, ccd_edges, ccd_hidden),
        *random_edge_hidden("fabrik", fabrik_random, fabrik_edges, fabrik_hidden),
        *random_edge_hidden("jacobian", jacobian_random, jacobian_edges, jacobian_hidden,
                            (1, 1, 1)),
        *random_edge_hidden("dls_step", dls_random, dls_edges, dls_hidden, (1, 1, 1)),
        Test("trace_curve (bonus): figure eights", "trace_curve", 1.0, trace_visible,
             bonus=True),
        Test("trace_curve (bonus): hidden curves", "trace_curve", 1.0, trace_hidden,
             hidden=True, bonus=True),
    ),
    misconceptions=MISCONCEPTIONS,
)
