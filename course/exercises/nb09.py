"""Notebook 09 · whole-body IK: the joint path from the fixed joint to the end effector, and a
world turn written back as a local rotation."""

from __future__ import annotations

import numpy as np

from autograder.checks import IndexCheck, QuatCheck
from autograder.spec import Case, Function, Misconception

from ..fk import tree_path
from ..rotations import quat_conjugate, quat_from_axis_angle, quat_identity, quat_mul
from ._cases import unit_quat
from .spec import Exercise

#: A small character: 0 hips, 1 spine, 2 head, 3 left arm, 4 left hand, 5 left leg,
#: 6 left foot, 7 right leg, 8 right foot.
_BODY = np.array([-1, 0, 1, 1, 3, 0, 5, 0, 7], dtype=np.int64)


def path_to(parents: np.ndarray, start: int, end: int) -> np.ndarray:
    r"""Reference of 09.path_to: the joints from ``start`` up to the lowest common ancestor,
    then down to ``end`` (both included), :func:`course.fk.tree_path`."""
    return np.array(tree_path(np.asarray(parents), int(start), int(end)), dtype=np.int64)


def _up(parents: np.ndarray, j: int) -> list[int]:
    out = [int(j)]
    while parents[out[-1]] >= 0:
        out.append(int(parents[out[-1]]))
    return out


def _downward_only(parents: np.ndarray, start: int, end: int) -> np.ndarray:
    """Only the part below the common ancestor, walked down to ``end``."""
    path = list(path_to(parents, start, end))
    top = min(path)
    return np.array(path[path.index(top):], dtype=np.int64)


def _through_joint_0(parents: np.ndarray, start: int, end: int) -> np.ndarray:
    """Up to joint 0 and down again, whatever the common ancestor."""
    up, down = _up(parents, start), _up(parents, end)
    return np.array(up + down[:-1][::-1], dtype=np.int64)


def _path_cases(rng: np.random.Generator) -> list[Case]:
    cases = [Case("left foot (6) to left hand (4): up to the hips, then down", (_BODY, 6, 4)),
             Case("left hand (4) to head (2): the common ancestor is the spine", (_BODY, 4, 2)),
             Case("left hand (4) to the hips (0): up only", (_BODY, 4, 0)),
             Case("start = end: a path of one joint", (_BODY, 3, 3))]
    for k in (1, 2):
        n = int(rng.integers(6, 10))
        parents = np.array([-1, *(int(rng.integers(0, i)) for i in range(1, n))], dtype=np.int64)
        a, b = (int(x) for x in rng.choice(np.arange(1, n), 2, replace=False))
        cases.append(Case(f"a random tree of {n} joints, {a} to {b} ({k})", (parents, a, b)))
    return cases


def written_back(Q_parent: np.ndarray, Q_i: np.ndarray, D: np.ndarray) -> np.ndarray:
    r"""Reference of 09.write_back: the joint's world orientation turned by the world turn
    ``D``, :math:`Q'_i = D\,Q_i`, written back as a local rotation,
    :math:`R'_i = Q_{parent}^{-1}\,D\,Q_i`."""
    return quat_mul(quat_conjugate(Q_parent), quat_mul(D, Q_i))


def _world_as_local(Q_parent: np.ndarray, Q_i: np.ndarray, D: np.ndarray) -> np.ndarray:
    """The world turn multiplied onto the old local rotation, D R_i."""
    return quat_mul(D, quat_mul(quat_conjugate(Q_parent), Q_i))


def _write_back_cases(rng: np.random.Generator) -> list[Case]:
    quarter_z = quat_from_axis_angle(np.array([0.0, 0.0, 1.0]), np.pi / 2)
    return [Case("the parent not turned", (quat_identity(), unit_quat(rng), quarter_z)),
            Case("the parent turned 90° about z", (quarter_z, unit_quat(rng), unit_quat(rng))),
            *(Case(f"a random pose and turn ({k})", (unit_quat(rng), unit_quat(rng),
                                                     unit_quat(rng)))
              for k in (1, 2, 3))]


EXERCISES = (
    Exercise(
        "path_to",
        Function("path_to", ("parents", "start", "end"), path_to, IndexCheck(noun="joint")),
        _path_cases,
        hint="List the ancestors of each joint, up to joint 0. The first joint of start's list "
             "that is also in end's list is where the path turns round: climb to it, then "
             "walk down end's list backwards.",
        formula="up_s = [start, p(start), …, 0], up_e likewise; top = the first of up_s in up_e; "
                "path = up_s up to top (included) + up_e before top, reversed.",
        mistakes=(
            Misconception("downward_only", "path_to",
                          "the tree walked only downward (the start's side dropped)",
                          "The path from the fixed joint goes UP from it to the lowest common "
                          "ancestor, then DOWN to the end effector; yours starts at the common "
                          "ancestor, as when only children are followed.",
                          wrong=_downward_only),
            Misconception("through_joint_0", "path_to",
                          "the path taken through joint 0 instead of the common ancestor",
                          "The path turns round at the LOWEST common ancestor (the first "
                          "ancestor of the start that is also one of the end's): from the left "
                          "hand to the head it turns at the spine, it does not go down to the "
                          "hips and back.",
                          wrong=_through_joint_0),
        ),
    ),
    Exercise(
        "write_back",
        Function("written_back", ("Q_parent", "Q_i", "D"), written_back, QuatCheck()),
        _write_back_cases,
        hint="D turns the joint in the WORLD: it changes the joint's global orientation. The "
             "clip stores local rotations: peel the parent off the new global orientation, as "
             "in notebook 02.",
        formula="Q'_i = D Q_i, then R'_i = Q_parent⁻¹ Q'_i (<code>rot.quat_conjugate</code> "
                "inverts a unit quaternion).",
        mistakes=(
            Misconception("world_as_local", "written_back",
                          "a world-frame turn applied to a local rotation",
                          "D is found in world coordinates, so it turns the joint's WORLD "
                          "orientation, Q'_i = D Q_i, and R'_i = Q_parent⁻¹ D Q_i. Yours is "
                          "D R_i = D Q_parent⁻¹ Q_i: the world turn multiplied onto the local "
                          "rotation, right only while the parent is not turned.",
                          wrong=_world_as_local),
            Misconception("turn_on_the_right", "written_back", "the world turn on the right",
                          "Q_i D turns by D in the joint's own frame; a world turn acts last, on "
                          "the left: Q'_i = D Q_i.",
                          wrong=lambda Qp, Qi, D: quat_mul(quat_conjugate(Qp), quat_mul(Qi, D))),
            Misconception("global_as_local", "written_back",
                          "the new global orientation stored as the local rotation",
                          "D Q_i is the joint's global orientation; the clip stores it relative "
                          "to the parent: R'_i = Q_parent⁻¹ (D Q_i).",
                          wrong=lambda Qp, Qi, D: quat_mul(D, Qi)),
        ),
    ),
)
