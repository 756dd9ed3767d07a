r"""Assignment a4, IK on a character: the spec ``assignments/a4_character.py`` is checked by.

Three functions: ``path_to`` (the joint path through the tree from the fixed joint to the end
effector, up through the common ancestor and down again), ``ik_local`` (IK on a whole
skeleton, any method, answered as **local** rotations) and ``retarget_rest`` (local rotations
for another rest pose of the same hierarchy, :math:`R'_i = C_{p(i)}^{-1} R_i C_i`).

IK has many right answers, so ``ik_local`` is graded by what its rotations achieve, never by
comparing angles: unit quaternions, every joint off the path keeping its local rotation, the
fixed joint unmoved in world space (its position, and its orientation when the path leaves it
upwards: a planted foot), and the forward-kinematics residual of the end effector within a
tolerance scaled to the skeleton. The answer holds no root position: joint 0 goes wherever
keeps the fixed joint in place. ``retarget_rest`` is graded by the global bone directions its
rotations give the target skeleton (the twist of a one-bone correction is free). Mistakes
with no single wrong output are recognised by their symptoms: the answer is right once read
as world-frame turns, or as world orientations (all of it, or the path's joints); the fixed
joint turned or slid as with joint 0 held; the answer is the template's CCD with each arc
measured at the next joint (the pivot family's wrong joint; the origin and effector pivots
cannot show in rotations, whose bones forward kinematics keeps); for ``retarget_rest``, the
bone directions of a mistaken formula.
Reference: :func:`course.fk.tree_path`, :func:`course.ik.solve`,
:func:`course.retarget.retarget_rest`.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from typing import Any, NamedTuple

import numpy as np

from course import rotations as rot
from course.fk import forward_kinematics as ref_fk
from course.fk import local_from_global, tree_path
from course.ik import solve
from course.retarget import rest_corrections, retarget_rest, with_rest_pose
from course.skeleton import Skeleton

from ..catalogue import pivot_mistakes
from ..checks import IndexCheck, QuatCheck, show
from ..spec import Assignment, Case, Function, Misconception, Picture, Test, Uses

REACH_TOL = 1e-3  # times the path's length: how far the end effector may stop from the target
HOLD_TOL = 1e-6  # times the path's length (or radians): how far the fixed joint may move
ROTATION_TOL = 1e-6  # a kept local rotation, a unit norm, a bone direction (radians)
ITERATIONS = 100


def _norm(v: np.ndarray) -> np.ndarray:
    norm: np.ndarray = np.linalg.norm(v, axis=-1)
    return norm


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle between unit quaternions (either sign), radians."""
    dot = np.abs(np.sum(a * b, axis=-1)) / (_norm(a) * _norm(b))
    angle: np.ndarray = 2 * np.arccos(np.clip(dot, -1.0, 1.0))
    return angle


def _names(parents: np.ndarray) -> list[str]:
    return [f"joint{j}" for j in range(len(parents))]


def goes_up(parents: np.ndarray, fixed: int, effector: int) -> bool:
    """Whether the path leaves the fixed joint upwards (the effector is not below it)."""
    return fixed not in tree_path(parents, effector, 0)


# --- judging an IK answer ----------------------------------------------------------------------


def path_length(parents: np.ndarray, offsets: np.ndarray, fixed: int, effector: int) -> float:
    path = tree_path(np.asarray(parents), fixed, effector)
    return float(sum(_norm(offsets[max(a, b)]) for a, b in zip(path, path[1:], strict=False)))


class IKCase(NamedTuple):
    """The arguments of one ``ik_local`` call, in the template's order: a case's ``args``,
    which the student's function and the reference take positionally."""

    parents: np.ndarray
    offsets: np.ndarray
    local_quats: np.ndarray
    root_position: np.ndarray
    fixed: int
    effector: int
    target: np.ndarray
    iterations: int

    @property
    def path(self) -> list[int]:
        """The joints that may turn, from the fixed joint to the end effector."""
        return tree_path(np.asarray(self.parents), self.fixed, self.effector)

    @property
    def scale(self) -> float:
        """The path's length, the unit of the case's tolerances."""
        return path_length(self.parents, self.offsets, self.fixed, self.effector)

    def fk(self, quats: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World positions and orientations for the local rotations ``quats``, joint 0 at
        the root position."""
        return ref_fk(self.parents, self.offsets, quats, self.root_position)


def ik_problems(got: Any, case: IKCase) -> list[str]:
    """What is wrong with ``got`` as an ``ik_local`` answer to ``case``, worst first."""
    got = np.asarray(got, dtype=float)
    out = []
    norms = _norm(got)
    bad = np.flatnonzero(np.abs(norms - 1) > ROTATION_TOL)
    if bad.size:
        return [f"joint {bad[0]} is not a unit quaternion (|q| = {norms[bad[0]]:.4g}); rotations "
                "need |q| = 1"]
    parents, local_quats, fixed, effector = (case.parents, case.local_quats, case.fixed,
                                             case.effector)
    path = case.path
    off = np.array([j for j in range(len(parents)) if j not in path], dtype=int)
    turned = off[_angle(got[off], local_quats[off]) > ROTATION_TOL] if off.size else off
    if turned.size:
        j = int(turned[0])
        out.append(f"joint {j} is off the path {path} but its local rotation changed (by "
                   f"{_angle(got[j], local_quats[j]):.3g} rad"
                   + (f"; {turned.size} such joints" if turned.size > 1 else "")
                   + "); only the joints on the path turn, the others keep R_j and move "
                   "rigidly with their parents")
    scale = max(case.scale, 1e-12)
    P0, Q0 = case.fk(local_quats)
    P, Q = case.fk(got)
    shift = P0[fixed] - P[fixed]
    if goes_up(parents, fixed, effector):
        turn = float(_angle(Q[fixed], Q0[fixed]))
        if turn > HOLD_TOL:
            out.append(f"the fixed joint {fixed} turned by {turn:.3g} rad in the world; the path "
                       "leaves it upwards, so it keeps its world orientation Q_fixed (a planted "
                       "foot does not turn)")
    elif _norm(shift) > HOLD_TOL * scale:
        out.append(f"the fixed joint {fixed} moved by {float(_norm(shift)):.3g}; it stays where "
                   "it is")
    miss = float(_norm(P[effector] + shift - case.target))
    if miss > REACH_TOL * scale:
        out.append(f"with the fixed joint {fixed} kept in place, the end effector (joint "
                   f"{effector}) stopped {miss:.3g} from the target (tolerance "
                   f"{REACH_TOL * scale:.3g}, {REACH_TOL:g} × the path's length {scale:.4g})")
    return out


class IKLocalCheck(QuatCheck):
    """An ``ik_local`` answer ``(J, 4)``, judged by what it achieves, not by the reference's
    angles."""

    def __init__(self) -> None:
        super().__init__(shape=None)

    def judge(self, got: Any, expected: Any, args: tuple[Any, ...]) -> str | None:
        problems = ik_problems(got, IKCase(*args))
        return problems[0] if problems else None

    def show_expected(self, expected: Any, digits: int = 3) -> str:
        return ("unit quaternions that put the end effector on the target, the fixed joint "
                "unmoved and the joints off the path unchanged")


def bone_directions(parents: np.ndarray, offsets: np.ndarray, quats: np.ndarray) -> np.ndarray:
    """Global unit direction of each bone (parent to joint) with a length, (J, 3); zero rows
    where the bone has none (joint 0 and zero offsets)."""
    P, _ = ref_fk(parents, offsets, rot.quat_normalize(np.asarray(quats, float)), np.zeros(3))
    d = np.zeros_like(P)
    d[1:] = P[1:] - P[np.asarray(parents)[1:]]
    n = _norm(d)
    return np.where(n[:, None] > 1e-12, d / np.where(n > 1e-12, n, 1.0)[:, None], 0.0)


def retarget_problems(got: Any, parents: np.ndarray, offsets_from: np.ndarray,
                      offsets_to: np.ndarray, local_quats: np.ndarray) -> list[str]:
    got = np.asarray(got, dtype=float)
    norms = _norm(got)
    bad = np.flatnonzero(np.abs(norms - 1) > ROTATION_TOL)
    if bad.size:
        return [f"joint {bad[0]} is not a unit quaternion (|q| = {norms[bad[0]]:.4g})"]
    want = bone_directions(parents, offsets_from, local_quats)
    have = bone_directions(parents, offsets_to, got)
    err = np.arccos(np.clip(np.sum(want * have, axis=1), -1.0, 1.0))
    err[~np.any(want, axis=1)] = 0.0
    wrong = np.flatnonzero(err > ROTATION_TOL)
    if not wrong.size:
        return []
    j = int(wrong[0])
    return [f"the bone to joint {j} points along {show(have[j])}, the source's along "
            f"{show(want[j])} ({np.degrees(err[j]):.3g}° apart"
            + (f"; {wrong.size} bones in all" if wrong.size > 1 else "") + ")"]


class RetargetCheck(QuatCheck):
    """Local rotations ``(J, 4)`` for the target rest pose, judged by the global bone
    directions they give (the twist of a one-bone correction is free)."""

    def __init__(self) -> None:
        super().__init__(shape=None)

    def judge(self, got: Any, expected: Any, args: tuple[Any, ...]) -> str | None:
        problems = retarget_problems(got, *args)
        return problems[0] if problems else None


# --- skeletons, poses and targets --------------------------------------------------------------

#: A small character: (name, parent, offset in its parent's frame), centimetre-like units.
CHARACTER = (
    ("Hips", -1, (0, 0, 0)),
    ("LeftUpLeg", 0, (9, -4, 0)), ("LeftLeg", 1, (0, -42, 0)), ("LeftFoot", 2, (0, -40, 0)),
    ("LeftToe", 3, (0, -6, 12)),
    ("RightUpLeg", 0, (-9, -4, 0)), ("RightLeg", 5, (0, -42, 0)), ("RightFoot", 6, (0, -40, 0)),
    ("RightToe", 7, (0, -6, 12)),
    ("Spine", 0, (0, 12, 0)), ("Chest", 9, (0, 22, 0)), ("Head", 10, (0, 24, 2)),
    ("LeftArm", 10, (17, 16, 0)), ("LeftForeArm", 12, (28, 0, 0)), ("LeftHand", 13, (25, 0, 0)),
    ("RightArm", 10, (-17, 16, 0)), ("RightForeArm", 15, (-28, 0, 0)),
    ("RightHand", 16, (-25, 0, 0)),
)


def character(rng: np.random.Generator | None = None) -> tuple[list[str], np.ndarray,
                                                               np.ndarray]:
    """The small character's names, parents and offsets (T pose), each bone scaled by a
    random 0.8-1.25 if ``rng`` is given."""
    names = [n for n, _, _ in CHARACTER]
    parents = np.array([p for _, p, _ in CHARACTER], dtype=np.int64)
    offsets = np.array([o for _, _, o in CHARACTER], dtype=float)
    if rng is not None:
        offsets *= rng.uniform(0.8, 1.25, (len(names), 1))
    return names, parents, offsets


def random_parents(rng: np.random.Generator, n: int) -> np.ndarray:
    """A random tree of ``n`` joints, parents before children: each joint hangs from one of
    the three joints listed before it (limbs of a few joints that branch)."""
    return np.array([-1] + [int(rng.integers(max(0, j - 3), j)) for j in range(1, n)],
                    dtype=np.int64)


def random_quats(rng: np.random.Generator, n: int, spread: float) -> np.ndarray:
    axes = rng.normal(size=(n, 3))
    return rot.quat_from_axis_angle(axes / _norm(axes)[:, None], rng.uniform(-spread, spread, n))


def _solve_reference(parents: np.ndarray, offsets: np.ndarray, local_quats: np.ndarray,
                     root_position: np.ndarray, fixed: int, effector: int, target: np.ndarray,
                     iterations: int, method: str = "dls") -> np.ndarray:
    skeleton = Skeleton(_names(parents), parents, offsets)
    tol = 0.1 * REACH_TOL * path_length(parents, offsets, fixed, effector)
    result = solve(skeleton, local_quats, root_position, {int(effector): target}, method=method,
                   root=int(fixed), tol=tol, max_iter=int(iterations), reach_start=False)
    return np.array(result.local_rotations)


def _reaches(case: IKCase) -> bool:
    """Whether the reference (DLS) and CCD, the method the template suggests, both solve the
    case within a quarter of its iterations (so a correct solver that differs in its details
    has room to spare)."""
    quick = case._replace(iterations=max(1, case.iterations // 4))
    return not any(ik_problems(_solve_reference(*quick, method=m), case)
                   for m in ("dls", "ccd"))


def ik_case(rng: np.random.Generator, parents: np.ndarray, offsets: np.ndarray, fixed: int,
            effector: int, label: str, spread: float = 0.5, reach: float = 0.3) -> Case | None:
    """A start pose (random turns up to ``spread`` rad), a root position, and a target moved
    ``reach`` × the path's length from the end effector, which the reference reaches; None
    if 20 draws found none (a tree with a stubby path)."""
    scale = path_length(parents, offsets, fixed, effector)
    for _ in range(20):
        quats = random_quats(rng, len(parents), spread) * rng.choice([-1.0, 1.0], (len(parents),
                                                                                    1))
        root = rng.normal(0, scale / 4, 3)
        P, _ = ref_fk(parents, offsets, quats, root)
        d = rng.normal(size=3)
        target = P[effector] + rng.uniform(0.3, 1.0) * reach * scale * d / _norm(d)
        case = IKCase(np.asarray(parents, dtype=np.int64), np.asarray(offsets, float), quats,
                      root, int(fixed), int(effector), target, ITERATIONS)
        if _reaches(case):
            return Case(label, case)
    return None


def random_ik_problem(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, int, int]:
    """A random tree and a (fixed, effector) pair whose path either starts at an ancestor of
    the effector or passes through joint 0, with at least two joints to turn."""
    while True:
        parents = random_parents(rng, int(rng.integers(5, 11)))
        offsets = rng.normal(0, 1, (len(parents), 3))
        offsets[0] = 0
        effector = int(rng.integers(1, len(parents)))
        fixed = int(rng.integers(0, len(parents)))
        path = tree_path(parents, fixed, effector)
        if len(path) >= 4 and (0 in path or fixed in tree_path(parents, effector, 0)) and \
                effector not in tree_path(parents, fixed, 0):
            return parents, offsets, fixed, effector


def random_ik_cases(rng: np.random.Generator, count: int, label: str) -> list[Case]:
    out: list[Case] = []
    while len(out) < count:
        parents, offsets, fixed, effector = random_ik_problem(rng)
        case = ik_case(rng, parents, offsets, fixed, effector,
                       f"{label} #{len(out) + 1} ({len(parents)} joints), fixed joint {fixed}, "
                       f"end effector {effector}")
        if case is not None:
            out.append(case)
    return out


def _character_case(rng: np.random.Generator, parents: np.ndarray, offsets: np.ndarray,
                    fixed: int, effector: int, label: str, spread: float = 0.5) -> Case:
    for _ in range(10):  # the character's paths are long: one draw in 20 nearly always does
        case = ik_case(rng, parents, offsets, fixed, effector, label, spread)
        if case is not None:
            return case
    raise RuntimeError(f"no reachable target found for {label!r}")


def ik_random(rng: np.random.Generator) -> list[Case]:
    return random_ik_cases(rng, 5, "random tree")


def ik_character(rng: np.random.Generator) -> list[Case]:
    names, parents, offsets = character()
    at = {n: j for j, n in enumerate(names)}
    pairs = (("LeftFoot", "LeftHand", "the left foot planted, the left hand reaching"),
             ("LeftFoot", "RightHand", "the left foot planted, the right hand reaching"),
             ("Hips", "RightHand", "the hips fixed (joint 0), the right hand reaching"),
             ("LeftArm", "LeftHand", "the shoulder fixed, the hand reaching (a downward path)"),
             ("RightFoot", "Head", "the right foot planted, the head reaching"),
             ("LeftToe", "RightFoot", "a toe planted, the other foot reaching"))
    return [_character_case(rng, parents, offsets, at[f], at[e], label) for f, e, label in pairs]


def ik_hidden(rng: np.random.Generator) -> list[Case]:
    out = random_ik_cases(rng, 6, "hidden tree")
    names, parents, offsets = character(rng)
    feet = [names.index("LeftFoot"), names.index("RightFoot")]
    hands = [names.index("LeftHand"), names.index("RightHand")]
    for i in range(4):
        out.append(_character_case(rng, parents, offsets, int(rng.choice(feet)),
                                   int(rng.choice(hands)),
                                   f"hidden character #{i + 1}: a foot planted, a hand reaching",
                                   spread=0.3))
    return out


# --- path_to -----------------------------------------------------------------------------------


def path_reference(parents: np.ndarray, start: int, end: int) -> np.ndarray:
    return np.array(tree_path(np.asarray(parents), int(start), int(end)), dtype=np.int64)


def _path_case(label: str, parents: np.ndarray, start: int, end: int) -> Case:
    return Case(label, (np.asarray(parents, dtype=np.int64), int(start), int(end)))


def path_visible(rng: np.random.Generator) -> list[Case]:
    names, parents, _ = character()
    at = {n: j for j, n in enumerate(names)}
    out = [_path_case(f"the character, {a} to {b}", parents, at[a], at[b])
           for a, b in (("LeftFoot", "LeftHand"), ("Hips", "RightHand"), ("LeftHand", "RightHand"),
                        ("RightToe", "Head"), ("LeftArm", "LeftHand"))]
    for i in range(4):
        parents = random_parents(rng, int(rng.integers(4, 16)))
        a, b = rng.integers(0, len(parents), 2)
        out.append(_path_case(f"random tree #{i + 1} ({len(parents)} joints), {a} to {b}",
                              parents, a, b))
    return out


def path_edges(rng: np.random.Generator) -> list[Case]:
    names, parents, _ = character()
    at = {n: j for j, n in enumerate(names)}
    return [
        _path_case("start = end: a path of one joint", parents, at["Chest"], at["Chest"]),
        _path_case("the end above the start: up only (LeftHand to Hips)", parents,
                   at["LeftHand"], at["Hips"]),
        _path_case("the start above the end: down only (Hips to LeftToe)", parents, at["Hips"],
                   at["LeftToe"]),
        _path_case("one joint", np.array([-1]), 0, 0),
        _path_case("a chain, from the tip to the root", np.arange(-1, 6), 6, 0),
    ]


def path_hidden(rng: np.random.Generator) -> list[Case]:
    out: list[Case] = []
    for i in range(10):
        parents = random_parents(rng, int(rng.integers(2, 30)))
        a, b = rng.integers(0, len(parents), 2)
        out.append(_path_case(f"hidden tree #{i + 1}", parents, a, b))
    return out


def downward_only(parents: np.ndarray, start: int, end: int) -> np.ndarray:
    """The path from the common ancestor down to ``end``: the start's side dropped."""
    path = tree_path(np.asarray(parents), int(start), int(end))
    top = min(path)  # the common ancestor: parents come before children
    return np.array(path[path.index(top):], dtype=np.int64)


def _ancestors(parents: np.ndarray, j: int) -> list[int]:
    out = [int(j)]
    while parents[out[-1]] >= 0:
        out.append(int(parents[out[-1]]))
    return out


def path_variant(how: str) -> Callable[[np.ndarray, int, int], np.ndarray]:
    """``path_to`` as students get it wrong: ``"to_root"`` (up to joint 0 and down again, not
    stopping at the lowest common ancestor), ``"reversed"`` (from the end to the start),
    ``"ancestor_twice"`` (the common ancestor ending the way up and starting the way down),
    ``"ancestor_dropped"`` (on neither)."""
    def wrong(parents: np.ndarray, start: int, end: int) -> np.ndarray:
        parents = np.asarray(parents)
        up, down = _ancestors(parents, start), _ancestors(parents, end)
        top = next(j for j in up if j in down)
        rise, fall = up[:up.index(top)], down[:down.index(top)][::-1]
        path = {"to_root": up + down[::-1][1:],
                "reversed": (rise + [top] + fall)[::-1],
                "ancestor_twice": rise + [top, top] + fall,
                "ancestor_dropped": rise + fall}[how]
        return np.array(path, dtype=np.int64)
    return wrong


# --- retarget_rest -----------------------------------------------------------------------------


def _retarget_case(label: str, parents: np.ndarray, offsets_from: np.ndarray,
                   offsets_to: np.ndarray, quats: np.ndarray) -> Case:
    return Case(label, (np.asarray(parents, dtype=np.int64), np.asarray(offsets_from, float),
                        np.asarray(offsets_to, float), np.asarray(quats, float)))


def rest_pair(rng: np.random.Generator, parents: np.ndarray, offsets: np.ndarray,
              spread: float = 1.0) -> np.ndarray:
    """The offsets of the same hierarchy in another rest pose: a random pose baked in."""
    sk = Skeleton(_names(parents), parents, offsets)
    return np.array(with_rest_pose(sk, random_quats(rng, len(parents), spread)).offsets)


def _random_tree(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    parents = random_parents(rng, n)
    offsets = rng.normal(0, 1, (n, 3))
    offsets[1:] += 0.3 * np.sign(offsets[1:])  # no bone shorter than 0.3: each has a direction
    return parents, offsets


def _t_and_a(rng: np.random.Generator | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from course.retarget import a_pose_from_t_pose

    names, parents, offsets = character(rng)
    t_pose = Skeleton(names, parents, offsets)
    return parents, offsets, np.array(a_pose_from_t_pose(t_pose).offsets)


def retarget_visible(rng: np.random.Generator) -> list[Case]:
    parents, t_off, a_off = _t_and_a()
    out = [_retarget_case("the character, A pose to T pose", parents, a_off, t_off,
                          random_quats(rng, len(parents), 1.0)),
           _retarget_case("the character, T pose to A pose", parents, t_off, a_off,
                          random_quats(rng, len(parents), 1.0))]
    for i, n in enumerate((3, 6, 10)):
        parents, offsets = _random_tree(rng, n)
        out.append(_retarget_case(f"random tree #{i + 1} ({n} joints), another rest pose",
                                  parents, offsets, rest_pair(rng, parents, offsets),
                                  random_quats(rng, n, np.pi)))
    return out


def retarget_edges(rng: np.random.Generator) -> list[Case]:
    chain = np.arange(-1, 4)
    offsets = np.tile([0.0, 1.0, 0.0], (5, 1))
    turn = np.tile([1.0, 0, 0, 0], (5, 1))
    turn[0] = rot.quat_from_axis_angle(np.array([0.0, 0, 1]), np.pi / 2)
    root_only = np.array(with_rest_pose(Skeleton(_names(chain), chain, offsets), turn).offsets)
    parents, offsets_tree = _random_tree(rng, 7)
    quats = random_quats(rng, 5, 1.0)
    return [
        _retarget_case("the same rest pose: nothing to correct", chain, offsets, offsets, quats),
        _retarget_case("only the root's bones differ (a quarter turn about z)", chain, offsets,
                       root_only, quats),
        _retarget_case("the identity pose: the source's rest pose on the target", parents,
                       offsets_tree, rest_pair(rng, parents, offsets_tree),
                       np.tile([1.0, 0, 0, 0], (7, 1))),
        _retarget_case("a half turn between the rest poses (opposite bone directions)", chain,
                       offsets, -offsets, quats),
    ]


def retarget_hidden(rng: np.random.Generator) -> list[Case]:
    parents, t_off, a_off = _t_and_a(rng)
    out = [_retarget_case("hidden character, A pose to T pose", parents, a_off, t_off,
                          random_quats(rng, len(parents), 1.2))]
    for i in range(8):
        n = int(rng.integers(2, 16))
        parents, offsets = _random_tree(rng, n)
        out.append(_retarget_case(f"hidden tree #{i + 1}", parents, offsets,
                                  rest_pair(rng, parents, offsets, np.pi),
                                  random_quats(rng, n, np.pi)))
    return out


def _corrections(parents: np.ndarray, offsets_from: np.ndarray, offsets_to: np.ndarray,
                 swapped: bool = False) -> np.ndarray:
    names = _names(parents)
    source, target = (Skeleton(names, parents, offsets_from), Skeleton(names, parents, offsets_to))
    return np.array(rest_corrections(target, source) if swapped else
                    rest_corrections(source, target))


def corrected(parents: np.ndarray, quats: np.ndarray, C: np.ndarray, right_side: bool = True
              ) -> np.ndarray:
    """:math:`R'_i = C_{p(i)}^{-1} R_i C_i` (``R'_0 = R_0 C_0``), or with ``right_side=False``
    the sides swapped, :math:`C_i R_i C_{p(i)}^{-1}`."""
    parents = np.asarray(parents)
    inv_parent = np.concatenate([[[1.0, 0, 0, 0]], rot.quat_conjugate(C[parents[1:]])])
    if right_side:
        return rot.quat_mul(inv_parent, rot.quat_mul(quats, C))
    return rot.quat_mul(C, rot.quat_mul(quats, inv_parent))


def _in_degrees(C: np.ndarray) -> np.ndarray:
    """Each correction turned by its angle in degrees, the angle in [0, π] (w >= 0) as
    arccos of a dot product gives it."""
    axis, angle = rot.axis_angle_from_quat(C * np.where(C[..., :1] < 0, -1.0, 1.0))
    return rot.quat_from_axis_angle(axis, np.degrees(angle))


def _first_bone_corrections(parents: np.ndarray, offsets_from: np.ndarray,
                            offsets_to: np.ndarray) -> np.ndarray:
    """C_i as the shortest arc for the FIRST child bone only, even where the children point
    two ways (the hips, the chest): the other bones come out twisted about the first."""
    parents = np.asarray(parents)
    C = np.tile([1.0, 0, 0, 0], (len(parents), 1))
    for j in range(len(parents)):
        kids = np.flatnonzero(parents == j)
        if kids.size:
            c = kids[0]
            C[j] = rot.quat_between(offsets_to[c], offsets_from[c])
        elif j:
            C[j] = C[parents[j]]
    return C


#: ``retarget_rest``'s signature: (parents, offsets_from, offsets_to, local_quats) -> rotations
Retarget = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def _retarget_variant(**how: bool) -> Retarget:
    def wrong(parents: np.ndarray, offsets_from: np.ndarray, offsets_to: np.ndarray,
              quats: np.ndarray) -> np.ndarray:
        if how.get("copied"):
            return np.array(quats, dtype=float)
        C = (_first_bone_corrections(parents, offsets_from, offsets_to) if how.get("first_bone")
             else _corrections(parents, offsets_from, offsets_to, how.get("swapped", False)))
        if how.get("degrees"):
            C = _in_degrees(C)
        if how.get("left"):  # C_p⁻¹ C_i R_i: both corrections on the left
            parents_ = np.asarray(parents)
            inv_parent = np.concatenate([[[1.0, 0, 0, 0]],
                                         rot.quat_conjugate(C[parents_[1:]])])
            return rot.quat_mul(inv_parent, rot.quat_mul(C, quats))
        return corrected(parents, quats, C, how.get("right_side", True))
    return wrong


def _same_bones_as(variant: Retarget) -> Callable[..., bool]:
    """A retarget symptom: wrong bone directions, and the same ones as ``variant`` gives (so
    the twist a student picks for a one-bone correction does not matter), to 1e-4: an angle
    taken as arccos of a dot product near 1 is good to ~1e-8 rad, times 57 in degrees."""
    def shows(got: Any, parents: np.ndarray, offsets_from: np.ndarray, offsets_to: np.ndarray,
              quats: np.ndarray) -> bool:
        if not retarget_problems(got, parents, offsets_from, offsets_to, quats):
            return False
        mine = bone_directions(parents, offsets_to, got)
        theirs = bone_directions(parents, offsets_to, variant(parents, offsets_from, offsets_to,
                                                              quats))
        return bool(np.all(np.abs(mine - theirs) <= 1e-4))  # loose: arccos near 1 rounds
    return shows


# --- the catalogue of known mistakes -----------------------------------------------------------


def _of_case(symptom: Callable[[Any, IKCase], bool]) -> Callable[..., bool]:
    """``symptom(got, case)`` as the grader calls a symptom, ``(got, *args)``."""
    @functools.wraps(symptom)
    def called(got: Any, *args: Any) -> bool:
        return symptom(got, IKCase(*args))
    return called


def _joint0_held(got: Any, case: IKCase) -> bool:
    """Solved as if joint 0 were held, not the fixed joint (a solver whose turns all swing
    the subtree below the pivot): wrong, and the fixed joint turned in the world (held
    joint 0 or not, a solver that holds it turns it with its leg), or, in plain forward
    kinematics (joint 0 at ``root_position``), the fixed joint moved and the effector is
    closer to the target than at the start and than with the fixed joint put back."""
    fixed, effector, target = case.fixed, case.effector, case.target
    if fixed == 0 or not goes_up(case.parents, fixed, effector):
        return False
    if not ik_problems(got, case):
        return False
    P0, Q0 = case.fk(case.local_quats)
    P, Q = case.fk(rot.quat_normalize(np.asarray(got, float)))
    if _angle(Q[fixed], Q0[fixed]) > HOLD_TOL:
        return True
    moved = P[fixed] - P0[fixed]
    plain = _norm(P[effector] - target)
    return bool(_norm(moved) > REACH_TOL * case.scale and plain < _norm(P0[effector] - target)
                and plain < _norm(P[effector] - moved - target))


def _world_turns_as_local(got: Any, case: IKCase) -> bool:
    """Right once read as the lab report wrote it back: each answer R'_j = D_j R_j is a world
    turn D_j applied to a local rotation; applied to the world orientation instead,
    Q'_j = D_j Q_j, then R_j = Q'_{p(j)}^{-1} Q'_j, the rotations are a right answer."""
    got = rot.quat_normalize(np.asarray(got, float))
    _, Q = case.fk(case.local_quats)
    turns = rot.quat_mul(got, rot.quat_conjugate(case.local_quats))
    fixed_up = np.array(local_from_global(case.parents, rot.quat_mul(turns, Q)))
    return not ik_problems(fixed_up, case)


def _world_returned(got: Any, case: IKCase, joints: list[int] | None = None) -> bool:
    """Right once read as world orientations: R_i = Q_{p(i)}^{-1} Q_i of the answer is a
    right answer (and the answer itself is not); with ``joints``, only those rows read as
    world orientations, the others as the local rotations they are."""
    got = rot.quat_normalize(np.asarray(got, float))
    if not ik_problems(got, case):
        return False
    world = got.copy()
    if joints is not None:  # the other rows are local: Q_j = Q_{p(j)} R_j, parents first
        for j in sorted(set(range(1, len(got))) - set(joints)):
            world[j] = rot.quat_mul(world[case.parents[j]], got[j])
    return not ik_problems(np.array(local_from_global(case.parents, world)), case)


def _world_written_as_local(got: Any, case: IKCase) -> bool:
    """A joint's new world orientation written as its local rotation: right once the path's
    rows are read as world orientations (written back at the end), or the rotations after
    some sweep of CCD that sets R_a ← D Q_a inside the loop."""
    return _world_returned(got, case, case.path) or _local_turns_in_loop(got, case, True)


class _WorldTurns:
    """The template's turn: ``D`` applied in world space about ``p_a`` to the part of the
    body beyond ``a`` seen from the fixed joint (``a``'s subtree on the way down, all but it
    on the way up), ``p_k ← p_a + D (p_k - p_a)``, ``Q_k ← D Q_k``; the local rotations are
    read off at the end, ``R_i = Q_{p(i)}^{-1} Q_i``. The common ancestor entered from below
    is no pivot: its edges up and down are one rigid body."""

    def __init__(self, case: IKCase) -> None:
        self.parents, self.path = np.asarray(case.parents), case.path
        self.P, self.Q = (np.array(a) for a in case.fk(case.local_quats))
        self.beyond: dict[int, np.ndarray] = {}  # a pivot's index: the joints its turn moves
        for k, (a, b) in enumerate(zip(self.path[:-1], self.path[1:], strict=True)):
            down = self.parents[b] == a
            if down and k and self.parents[self.path[k - 1]] == a:
                continue
            below = np.array([a in tree_path(self.parents, j, 0)
                              for j in range(len(self.parents))])
            self.beyond[k] = below if down else ~below
        self.pivots = list(self.beyond)

    def turn(self, k: int, D: np.ndarray) -> None:
        a, moving = self.path[k], self.beyond[k]
        self.P[moving] = self.P[a] + rot.quat_rotate(D, self.P[moving] - self.P[a])
        self.Q[moving] = rot.quat_mul(D, self.Q[moving])

    def rotations(self) -> np.ndarray:
        return np.array(local_from_global(self.parents, self.Q))


class _LocalTurns:
    """The lab report's bug inside the loop: the world turn multiplied onto the pivot's local
    rotation, ``R_a ← D R_a``, or with ``onto_world`` onto its world orientation and written
    as the local rotation, ``R_a ← D Q_a``; then forward kinematics from joint 0 (held at
    the root position). Every joint of the path but the end effector is a pivot."""

    def __init__(self, case: IKCase, onto_world: bool = False) -> None:
        self.case, self.path, self.onto_world = case, case.path, onto_world
        self.R = np.array(case.local_quats, dtype=float)
        self.P, self.Q = case.fk(self.R)
        self.pivots = list(range(len(self.path) - 1))

    def turn(self, k: int, D: np.ndarray) -> None:
        a = self.path[k]
        self.R[a] = rot.quat_mul(D, (self.Q if self.onto_world else self.R)[a])
        self.P, self.Q = self.case.fk(self.R)

    def rotations(self) -> np.ndarray:
        R: np.ndarray = self.R.copy()
        return R


def ccd_sweeps(case: IKCase, turns: _WorldTurns | _LocalTurns, lever: int = 0,
               tol: float = 0.0) -> Iterator[np.ndarray]:
    """The template's CCD written out, with the two rules its mistakes change: where each
    arc is measured, and how its turn is applied.

    Each sweep visits the pivots from the end effector back to the fixed joint; at the pivot
    ``a = path[k]`` the turn ``D`` is the shortest arc from ``e - p_m`` to ``t - p_m``,
    measured at ``m = path[k + lever]``.

    Parameters
    ----------
    case : IKCase
    turns : _WorldTurns or _LocalTurns
        The pose to turn, changed in place: its joint positions ``P``, where the arcs are
        measured; its ``pivots``, indices into the path; and how a turn applies, the
        template's way about the pivot or multiplied onto a local rotation (the "world as
        local" mistake).
    lever : int
        0: the arc measured at the pivot, as the template says. 1: at the next joint of the
        path (the pivot family's wrong joint; a pivot whose next joint is the end effector
        then has no turn).
    tol : float
        Stop before a sweep once the end effector is within ``tol`` of the target (0: run
        every one of the case's iterations).

    Yields
    ------
    ndarray, shape (J, 4)
        The local rotations after each sweep.
    """
    path, effector, target = case.path, case.effector, case.target
    for _ in range(case.iterations):
        if _norm(turns.P[effector] - target) < tol:
            return
        for k in turns.pivots[::-1]:
            m = path[min(k + lever, len(path) - 1)]
            u, v = turns.P[effector] - turns.P[m], target - turns.P[m]
            if m == effector or _norm(u) < 1e-12 or _norm(v) < 1e-12:
                continue
            turns.turn(k, rot.quat_between(u, v))
        yield turns.rotations()


def _same_rotations(got: np.ndarray, model: np.ndarray) -> bool:
    """Every joint's rotation as the model's, either sign, loosely (1e-2): a CCD that does
    not converge wanders, and over many sweeps rounding alone parts two implementations of
    the same steps by up to ~1e-3."""
    return bool(np.all(np.minimum(np.abs(got - model).max(-1), np.abs(got + model).max(-1))
                       <= 1e-2))


def _local_turns_in_loop(got: Any, case: IKCase, onto_world: bool = False) -> bool:
    """Wrong, and the rotations after some sweep of CCD with each world turn multiplied on
    the local rotation inside the loop (``onto_world``: on the world orientation, written
    as the local rotation)."""
    g = np.asarray(got, dtype=float)
    if not ik_problems(g, case):
        return False
    return any(_same_rotations(g, w) for w in ccd_sweeps(case, _LocalTurns(case, onto_world)))


def _wrong_joint(got: Any, case: IKCase) -> bool:
    """Wrong, and the rotations of the template's CCD with each arc measured at the next
    joint, stopped as the template says (the effector within 1e-5 × the path's length)."""
    g = np.asarray(got, dtype=float)
    if not ik_problems(g, case):
        return False
    turns = _WorldTurns(case)
    for _ in ccd_sweeps(case, turns, lever=1, tol=1e-5 * case.scale):
        pass
    return _same_rotations(g, turns.rotations())


MISCONCEPTIONS = (
    Misconception(
        "downward_only", "path_to", "the tree walked only downward (the start's side dropped)",
        "The path from the fixed joint to the end effector goes UP from the fixed joint to the "
        "lowest common ancestor, then DOWN to the effector (LeftFoot, LeftLeg, LeftUpLeg, Hips, "
        "Spine, ...); yours starts at the common ancestor, as when only children are followed.",
        wrong=downward_only),
    Misconception(
        "to_root", "path_to", "the path taken through the root, past the common ancestor",
        "Your path walks from the start all the way up to joint 0 and back down to the end. "
        "It should turn at the LOWEST common ancestor, the first joint the two walks to the "
        "root share (Chest for the two hands, not Hips): stop the way up there and begin the "
        "way down from it; the joints above it are not between the two.",
        wrong=path_variant("to_root")),
    Misconception(
        "reversed", "path_to", "the path listed backwards (end first)",
        "Your path starts at the end effector and ends at the fixed joint: the joints are "
        "right, the order is not. path_to(parents, start, end) lists start first and end last "
        "(the way up from start, then the way down to end); reverse the walk from end.",
        wrong=path_variant("reversed")),
    Misconception(
        "ancestor_twice", "path_to", "the common ancestor listed twice",
        "Your path has the lowest common ancestor twice in a row: once at the top of the way "
        "up and again at the start of the way down. List it once: up from start to the "
        "ancestor (included), then down to end WITHOUT the ancestor, "
        "up[:up.index(top) + 1] + down[:down.index(top)][::-1].",
        wrong=path_variant("ancestor_twice")),
    Misconception(
        "ancestor_dropped", "path_to", "the common ancestor left out",
        "Your path goes from the last joint of the way up straight to the first of the way "
        "down, skipping the lowest common ancestor itself: consecutive joints of a path are "
        "parent and child, and the two sides only meet through the ancestor. Include it once, "
        "between the way up and the way down.",
        wrong=path_variant("ancestor_dropped")),
    Misconception(
        "world_as_local", "ik_local", "a world-frame turn applied to a local rotation",
        "A turn D found in world coordinates (the shortest arc from e - r_i to t - r_i) turns "
        "the joint's WORLD orientation, Q'_i = D Q_i; its local rotation is then "
        "R'_i = Q'_{p(i)}^{-1} Q'_i = Q_{p(i)}^{-1} D Q_{p(i)} R_i. Your rotations are right "
        "once read as D R_i: the world turn multiplied onto the local one (R_i ← D R_i, at "
        "the end or inside the loop).",
        symptom=_of_case(lambda got, case: _world_turns_as_local(got, case)
                         or _local_turns_in_loop(got, case))),
    Misconception(
        "world_returned", "ik_local", "world orientations returned instead of local rotations",
        "You returned the joints' WORLD orientations Q_i; ik_local returns LOCAL rotations, "
        "each relative to its parent: R_0 = Q_0, R_i = Q_{p(i)}^{-1} Q_i. Yours are right once "
        "read back that way.",
        symptom=_of_case(_world_returned)),
    Misconception(
        "world_written_as_local", "ik_local",
        "a joint's world orientation written as its local rotation",
        "Your R_i on the path are the joints' new WORLD orientations Q'_i = D Q_i (written "
        "into R_i inside the loop, or copied at the end): forward kinematics then puts the "
        "parent's orientation on top of them once more, Q'_{p(i)} Q'_i. A local rotation is "
        "relative to the parent, R_i = Q'_{p(i)}^{-1} Q'_i (R_0 = Q'_0): multiply by the "
        "parent's inverse world orientation before writing it into R_i.",
        symptom=_of_case(_world_written_as_local)),
    *pivot_mistakes("ik_local", {"wrong_joint": _of_case(_wrong_joint)}),
    Misconception(
        "path_to_wrong", "ik_local", "the wrong path from your path_to, walked by ik_local",
        "ik_local turns the joints on path_to(parents, fixed, effector), and for these cases "
        "your path_to returns a wrong path (its own tests above say how): the joints turned, "
        "or the order they are turned in, come out wrong with it. Fix path_to first and check "
        "again; whatever ik_local still gets wrong will then show here.",
        caused_by="path_to"),
    Misconception(
        "root_moved", "ik_local", "joint 0 held in place, not the fixed joint",
        "With a foot as the fixed joint the body turns about the foot: a turn of an edge on "
        "the foot's side (Q_p = Q_c R_c^{-1}, p_p = p_c - Q_p l_c) moves everything beyond it, "
        "joint 0 included, and the foot neither slides nor turns. Your pose was solved as if joint "
        "0 were held: the planted foot turned (or slid) with the leg.",
        symptom=_of_case(_joint0_held)),
    Misconception(
        "copied", "retarget_rest", "the rotations copied unchanged",
        "You returned the source's local rotations as they are. They were made for the "
        "source's rest pose: on a skeleton whose rest bones point elsewhere (A pose vs T pose) "
        "the same R_i point the bones wrongly. Correct each by the rest-pose difference, "
        "R'_i = C_{p(i)}^{-1} R_i C_i, with C_i turning the target's rest bones below joint i "
        "onto the source's.",
        symptom=_same_bones_as(_retarget_variant(copied=True))),
    Misconception(
        "both_left", "retarget_rest", "both corrections on the left (C_p⁻¹ C_i R_i)",
        "Yours is C_{p(i)}^{-1} C_i R_i: the correction C_i acts in the joint's rest frame, "
        "BEFORE the motion R_i, so it goes on the right: R'_i = C_{p(i)}^{-1} R_i C_i.",
        symptom=_same_bones_as(_retarget_variant(left=True))),
    Misconception(
        "first_bone_only", "retarget_rest",
        "a correction that maps one child bone and twists the others",
        "Your C_i is the shortest arc for one child bone only; where a joint's children point "
        "two ways (the hips: both legs and the spine; the chest: the arms and the neck) that "
        "arc leaves the other bones twisted about the first. Use the rotation that takes "
        "both directions: an orthonormal frame from two child bones in each skeleton, "
        "C = F_from F_to^T.",
        symptom=_same_bones_as(_retarget_variant(first_bone=True))),
    Misconception(
        "wrong_side", "retarget_rest", "the correction on the wrong side (C R instead of R C)",
        "The correction acts in the joint's rest frame, before the motion: Q'_i = Q_i C_i, so "
        "R'_i = C_{p(i)}^{-1} R_i C_i (C on the RIGHT of R_i, the parent's inverse on the left); "
        "yours is C_i R_i C_{p(i)}^{-1}: the parent's inverse and the correction swapped.",
        symptom=_same_bones_as(_retarget_variant(right_side=False))),
    Misconception(
        "wrong_skeleton", "retarget_rest", "the correction from the other skeleton's offsets",
        "C_i turns the TARGET's rest bones onto the SOURCE's, C_i l̂_c(to) = l̂_c(from): your "
        "corrections turn the source's onto the target's (C_i^{-1}), the offsets swapped.",
        symptom=_same_bones_as(_retarget_variant(swapped=True))),
    Misconception(
        "degrees", "retarget_rest", "the correction angle in degrees",
        "The angle between the rest bones, θ = arccos(l̂(to)·l̂(from)), is in radians, which "
        "q = (cos θ/2, sin θ/2·u) takes; in degrees it turns by θ·180/π.",
        symptom=_same_bones_as(_retarget_variant(degrees=True))),
)

# --- pictures of a failing case ----------------------------------------------------------------


def ik_picture(got: Any, expected: Any, args: tuple[Any, ...]) -> Picture | None:
    case = IKCase(*args)
    q = np.asarray(got, dtype=float)
    if q.shape != case.local_quats.shape or np.any(_norm(q) < 1e-9):
        return None
    P0, _ = case.fk(case.local_quats)

    def pose(r: np.ndarray) -> np.ndarray:
        P, _ = case.fk(rot.quat_normalize(r))
        placed: np.ndarray = P + (P0[case.fixed] - P[case.fixed])
        return placed

    return Picture("your pose and the reference's, the fixed joint kept in place (the "
                   "reference is one right answer of many)", case.parents, pose(q),
                   pose(expected), start=P0,
                   points=(("target", np.atleast_2d(case.target)),
                           ("fixed joint", np.atleast_2d(P0[case.fixed]))))


def retarget_picture(got: Any, expected: Any, args: tuple[Any, ...]) -> Picture | None:
    parents, offsets_from, offsets_to, quats = args
    q = np.asarray(got, dtype=float)
    if q.shape != quats.shape or np.any(_norm(q) < 1e-9):
        return None
    source, _ = ref_fk(parents, offsets_from, quats, np.zeros(3))
    mine, _ = ref_fk(parents, offsets_to, rot.quat_normalize(q), np.zeros(3))
    right, _ = ref_fk(parents, offsets_to, expected, np.zeros(3))
    return Picture("the target skeleton posed by your rotations and by the reference's (the "
                   "source's pose faint)", parents, mine, right, start=source)


# --- the assignment ----------------------------------------------------------------------------

_FUNCTIONS = (
    Function("path_to", ("parents", "start", "end"), path_reference, IndexCheck(noun="joint")),
    Function("ik_local", ("parents", "offsets", "local_quats", "root_position", "fixed",
                          "effector", "target", "iterations"), _solve_reference, IKLocalCheck(),
             ik_picture, uses=(Uses("path_to", lambda parents, offsets, quats, root, fixed,
                                    effector, target, iterations: (parents, fixed, effector)),)),
    Function("retarget_rest", ("parents", "offsets_from", "offsets_to", "local_quats"),
             lambda *args: np.array(retarget_rest(*args)), RetargetCheck(), retarget_picture),
)

ASSIGNMENT = Assignment(
    key="a4",
    title="IK on a character and rest poses",
    template="a4_character.py",
    functions=_FUNCTIONS,
    tests=(
        Test("path_to: the character and random trees", "path_to", 1.0, path_visible),
        Test("path_to: edge cases", "path_to", 1.0, path_edges),
        Test("path_to: hidden trees", "path_to", 1.0, path_hidden, hidden=True),
        Test("ik_local: the character", "ik_local", 2.0, ik_character),
        Test("ik_local: random trees", "ik_local", 1.0, ik_random),
        Test("ik_local: hidden cases", "ik_local", 3.0, ik_hidden, hidden=True),
        Test("retarget_rest: A and T poses, random rest poses", "retarget_rest", 1.0,
             retarget_visible),
        Test("retarget_rest: edge cases", "retarget_rest", 1.0, retarget_edges),
        Test("retarget_rest: hidden cases", "retarget_rest", 2.0, retarget_hidden, hidden=True),
    ),
    misconceptions=MISCONCEPTIONS,
)
