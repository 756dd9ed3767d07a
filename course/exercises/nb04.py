"""Notebook 04 · two-link IK: the law of cosines gives both angles."""

from __future__ import annotations

import numpy as np

from autograder.checks import Check
from autograder.spec import Case, Function, Misconception

from .spec import Exercise


def _cosine_rule(a: float, b: float, c: float) -> float:
    """The angle between sides ``a`` and ``b`` of a triangle whose third side is ``c``."""
    return float(np.arccos(np.clip((a**2 + b**2 - c**2) / (2 * a * b), -1.0, 1.0)))


def inner_angle(l1: float, l2: float, d: float) -> float:
    r"""Reference of 04.inner_angle: :math:`\cos\beta = (l_1^2 + l_2^2 - d^2) / (2 l_1 l_2)`."""
    return _cosine_rule(l1, l2, d)


def root_angle(l1: float, l2: float, d: float) -> float:
    r"""Reference of 04.root_angle: :math:`\cos\alpha = (l_1^2 + d^2 - l_2^2) / (2 l_1 d)`."""
    return _cosine_rule(l1, d, l2)


def _triangles(rng: np.random.Generator) -> list[Case]:
    cases = [Case("the notebook's arm, d = 1.14", (1.0, 0.6, 1.14)),
             Case("a straight arm (d = l1 + l2)", (1.0, 0.5, 1.5)),
             Case("equal bones, folded to d = 0.5", (0.8, 0.8, 0.5))]
    for k in (1, 2):
        l1, l2 = np.round(rng.uniform(0.4, 1.2, 2), 2)
        d = round(float(rng.uniform(abs(l1 - l2) + 0.05, l1 + l2 - 0.05)), 2)
        cases.append(Case(f"a random triangle ({k})", (float(l1), float(l2), d)))
    return cases


_DEGREES = ("degrees for radians", "np.arccos returns radians, as every angle in the course; "
            "np.degrees is only for printing.")

EXERCISES = (
    Exercise(
        "inner_angle",
        Function("inner_angle", ("l1", "l2", "d"), inner_angle, Check((), noun="angle")),
        _triangles,
        hint="The triangle root–middle–target has sides l1, l2 and d. β sits between the two "
             "bones, opposite the side d.",
        formula="d² = l1² + l2² − 2 l1 l2 cos β, so β = arccos((l1² + l2² − d²) / (2 l1 l2)) "
                "(clip the cosine into [−1, 1] against rounding).",
        mistakes=(
            Misconception("bend_for_inner", "inner_angle", "the elbow's bend for the inner angle",
                          "β is the inner angle between the two bones (π for a straight arm); "
                          "π − β is how far the joint bends away from straight, θ2.",
                          wrong=lambda l1, l2, d: np.pi - inner_angle(l1, l2, d)),
            Misconception("root_for_inner", "inner_angle", "the angle at the root",
                          "The angle opposite d is β = arccos((l1² + l2² − d²) / (2 l1 l2)); "
                          "(l1² + d² − l2²) / (2 l1 d) is the cosine of α, at the root.",
                          wrong=lambda l1, l2, d: root_angle(l1, l2, d)),
            Misconception("degrees_out", "inner_angle", *_DEGREES,
                          wrong=lambda l1, l2, d: np.degrees(inner_angle(l1, l2, d))),
        ),
    ),
    Exercise(
        "root_angle",
        Function("root_angle", ("l1", "l2", "d"), root_angle, Check((), noun="angle")),
        _triangles,
        hint="Same triangle, other corner: α sits at the root, between the first bone (l1) and "
             "the line to the target (d). Which side is opposite it?",
        formula="l2² = l1² + d² − 2 l1 d cos α, so α = arccos((l1² + d² − l2²) / (2 l1 d)).",
        mistakes=(
            Misconception("target_corner", "root_angle", "the angle at the target",
                          "α, at the root, lies opposite the forearm l2: cos α = (l1² + d² − "
                          "l2²) / (2 l1 d); swapping l1 and l2 gives the corner at the target.",
                          wrong=lambda l1, l2, d: root_angle(l2, l1, d)),
            Misconception("inner_for_root", "root_angle", "the inner angle β",
                          "β = arccos((l1² + l2² − d²) / (2 l1 l2)) is the angle between the "
                          "bones; α is the one at the root, opposite l2.",
                          wrong=inner_angle),
            Misconception("degrees_out", "root_angle", *_DEGREES,
                          wrong=lambda l1, l2, d: np.degrees(root_angle(l1, l2, d))),
        ),
    ),
)
