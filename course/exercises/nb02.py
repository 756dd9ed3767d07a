"""Notebook 02 · forward kinematics: one line of the recursion, and back to local."""

from __future__ import annotations

import numpy as np

from autograder.checks import Check, QuatCheck
from autograder.spec import Case, Function, Misconception

from ..rotations import quat_conjugate, quat_from_axis_angle, quat_identity, quat_mul, quat_rotate
from ._cases import unit_quat, vector
from .spec import Exercise


def child_position(p_parent: np.ndarray, Q_parent: np.ndarray, l_i: np.ndarray) -> np.ndarray:
    r"""Reference of 02.fk_step: :math:`p_i = p_{parent} + Q_{parent}\,l_i`."""
    return p_parent + quat_rotate(Q_parent, l_i)


def child_orientation(Q_parent: np.ndarray, R_i: np.ndarray) -> np.ndarray:
    r"""Reference of 02.fk_orientation: :math:`Q_i = Q_{parent}\,R_i`."""
    return quat_mul(Q_parent, R_i)


def local_rotation(Q_parent: np.ndarray, Q_i: np.ndarray) -> np.ndarray:
    r"""Reference of 02.local_rotation: :math:`R_i = Q_{parent}^{-1}\,Q_i`."""
    return quat_mul(quat_conjugate(Q_parent), Q_i)


def _pose_cases(rng: np.random.Generator) -> list[Case]:
    quarter_y = quat_from_axis_angle(np.array([0.0, 1.0, 0.0]), np.pi / 2)
    return [Case("the parent not turned", (vector(rng), quat_identity(), vector(rng))),
            Case("the parent turned 90° about y", (np.zeros(3), quarter_y,
                                                     np.array([1.0, 0.0, 0.0]))),
            *(Case(f"a random pose ({k})", (vector(rng), unit_quat(rng), vector(rng)))
              for k in (1, 2, 3))]


def _rotation_pairs(rng: np.random.Generator) -> list[Case]:
    return [Case(f"two random rotations ({k})", (unit_quat(rng), unit_quat(rng)))
            for k in (1, 2, 3, 4)]


EXERCISES = (
    Exercise(
        "fk_step",
        Function("child_position", ("p_parent", "Q_parent", "l_i"), child_position,
                 Check((3,), noun="position")),
        _pose_cases,
        hint="The offset l_i is written in the parent's frame. Before you can add it to a "
             "world position, it has to be turned into the world.",
        formula="p_i = p_parent + Q_parent l_i, where Q_parent l_i is "
                "<code>rot.quat_rotate(Q_parent, l_i)</code>.",
        mistakes=(
            Misconception("unrotated_offset", "child_position",
                          "the offset added without turning it",
                          "l_i is measured in the parent's frame: turn it into the world by "
                          "the parent's global orientation first, p_i = p_parent + Q_parent l_i.",
                          wrong=lambda p, Q, off: p + off),
            Misconception("inverse_rotation", "child_position",
                          "the offset turned by the inverse rotation",
                          "Q_parent⁻¹ l_i turns the offset the wrong way; the world offset is "
                          "Q_parent l_i = q l q*, the quaternion on the left.",
                          wrong=lambda p, Q, off: p + quat_rotate(quat_conjugate(Q), off)),
            Misconception("rotated_position", "child_position",
                          "the parent's position turned as well",
                          "Only the bone turns with the parent: p_i = p_parent + Q_parent l_i; "
                          "Q_parent (p_parent + l_i) also swings the parent's own position "
                          "about the origin.",
                          wrong=lambda p, Q, off: quat_rotate(Q, p + off)),
        ),
    ),
    Exercise(
        "fk_orientation",
        Function("child_orientation", ("Q_parent", "R_i"), child_orientation, QuatCheck()),
        _rotation_pairs,
        hint="The child first turns by its own local rotation, then is carried along by "
             "everything above it. In a product of rotations, which one acts first?",
        formula="Q_i = Q_parent R_i (the one on the right acts first), "
                "<code>rot.quat_mul(a, b)</code> is the product a b.",
        mistakes=(
            Misconception("swapped_order", "child_orientation",
                          "the product in the wrong order",
                          "Rotations do not commute: Q_i = Q_parent R_i, the local rotation on "
                          "the right (it acts first, in the parent's frame); R_i Q_parent "
                          "turns about the world's axes instead.",
                          wrong=lambda Q, R: quat_mul(R, Q)),
        ),
    ),
    Exercise(
        "local_rotation",
        Function("local_rotation", ("Q_parent", "Q_i"), local_rotation, QuatCheck()),
        _rotation_pairs,
        hint="Start from Q_i = Q_parent R_i and solve it for R_i: multiply both sides by "
             "the inverse of Q_parent — on which side?",
        formula="R_i = Q_parent⁻¹ Q_i, and for a unit quaternion the inverse is the "
                "conjugate, <code>rot.quat_conjugate(Q_parent)</code>.",
        mistakes=(
            Misconception("inverse_on_the_right", "local_rotation",
                          "the parent's inverse on the wrong side",
                          "From Q_i = Q_parent R_i, R_i = Q_parent⁻¹ Q_i (multiply on the "
                          "left); Q_i Q_parent⁻¹ is a different rotation unless they commute.",
                          wrong=lambda Q, Qi: quat_mul(Qi, quat_conjugate(Q))),
            Misconception("no_inverse", "local_rotation",
                          "the parent's rotation not inverted",
                          "Undoing the parent takes its inverse, R_i = Q_parent⁻¹ Q_i; "
                          "Q_parent Q_i applies it a second time.",
                          wrong=lambda Q, Qi: quat_mul(Q, Qi)),
        ),
    ),
)
