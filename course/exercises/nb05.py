"""Notebook 05 · CCD: one step, for a ball joint and for a hinge."""

from __future__ import annotations

import numpy as np

from autograder.catalogue import pivot_mistakes
from autograder.checks import Check, QuatCheck
from autograder.spec import Case, Function, Misconception

from ..rotations import quat_between
from ._cases import vector
from .spec import Exercise


def ccd_rotation(r_i: np.ndarray, e: np.ndarray, t: np.ndarray) -> np.ndarray:
    r"""Reference of 05.ccd_rotation: the shortest arc taking :math:`e - r_i` onto
    :math:`t - r_i`."""
    return quat_between(e - r_i, t - r_i)


def hinge_angle(axis: np.ndarray, r_i: np.ndarray, e: np.ndarray, t: np.ndarray) -> float:
    r"""Reference of 05.hinge_angle: the signed turn about the unit ``axis`` that best aims
    :math:`e - r_i` at :math:`t - r_i`, both projected onto the plane perpendicular to it."""
    u, v = e - r_i, t - r_i
    u, v = u - (u @ axis) * axis, v - (v @ axis) * axis
    return float(np.arctan2(axis @ np.cross(u, v), u @ v))


def _joint_cases(rng: np.random.Generator) -> list[Case]:
    cases = [Case("the notebook's wrist", (np.array([1.0, 0.5, 0.0]), np.array([2.2, 1.4, 0.0]),
                                          np.array([-0.6, 1.7, 0.0])))]
    cases += [Case(f"random points in 3D ({k})", (vector(rng), vector(rng), vector(rng)))
              for k in (1, 2, 3)]
    return cases


def _hinge_cases(rng: np.random.Generator) -> list[Case]:
    z = np.array([0.0, 0.0, 1.0])
    cases = [Case("a planar arm, turn left", (z, np.zeros(3), np.array([1.0, 0.0, 0.0]),
                                             np.array([0.0, 2.0, 0.0]))),
             Case("a planar arm, turn right", (z, np.zeros(3), np.array([1.0, 0.0, 0.0]),
                                              np.array([1.0, -1.0, 0.0]))),
             Case("a target off the plane", (z, np.zeros(3), np.array([1.0, 0.0, 0.0]),
                                            np.array([1.0, 1.0, 3.0])))]
    for k in (1, 2):
        axis = vector(rng)
        cases.append(Case(f"a random hinge ({k})", (axis / np.linalg.norm(axis), vector(rng),
                                                    vector(rng), vector(rng))))
    return cases


def _origin_arc(got: np.ndarray, r_i: np.ndarray, e: np.ndarray, t: np.ndarray) -> bool:
    return QuatCheck().close(got, quat_between(e, t))


def _unprojected(axis: np.ndarray, r_i: np.ndarray, e: np.ndarray, t: np.ndarray) -> float:
    u, v = e - r_i, t - r_i
    return float(np.arccos(np.clip(u @ v / np.linalg.norm(u) / np.linalg.norm(v), -1, 1)))


EXERCISES = (
    Exercise(
        "ccd_rotation",
        Function("ccd_rotation", ("r_i", "e", "t"), ccd_rotation, QuatCheck()),
        _joint_cases,
        hint="Joint i can only swing the end effector around itself. Measure both directions "
             "from the joint: where the effector is, and where it should be.",
        formula="R = the shortest arc from e − r_i to t − r_i: axis (e − r_i) × (t − r_i), "
                "angle arccos of their normalised dot product; "
                "<code>rot.quat_between(u, v)</code> builds it.",
        mistakes=pivot_mistakes("ccd_rotation", {"origin_pivot": _origin_arc}),
    ),
    Exercise(
        "hinge_angle",
        Function("hinge_angle", ("axis", "r_i", "e", "t"), hinge_angle,
                 Check((), noun="angle")),
        _hinge_cases,
        hint="A hinge only sees the part of each direction that lies in its plane: remove "
             "the component along the axis first. The angle needs a sign, so arccos alone "
             "is not enough.",
        formula="u = (e − r_i) − ((e − r_i)·a) a, v likewise from t − r_i; "
                "φ = atan2(a · (u × v), u · v).",
        mistakes=(
            Misconception("unsigned", "hinge_angle", "the angle without its sign",
                          "arccos gives |φ| only; the turn about the hinge axis a is signed: "
                          "φ = atan2(a · (u × v), u · v) turns right for a negative φ.",
                          wrong=lambda a, r, e, t: abs(hinge_angle(a, r, e, t))),
            Misconception("unprojected", "hinge_angle", "the directions not projected",
                          "A hinge turns only about a: project e − r_i and t − r_i onto the "
                          "plane perpendicular to a before measuring the angle between them.",
                          wrong=_unprojected),
        ),
    ),
)
