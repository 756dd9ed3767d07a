"""Notebook 10 · retargeting: the rest-pose correction of one bone, and the corrected local
rotation."""

from __future__ import annotations

import numpy as np

from autograder.checks import QuatCheck
from autograder.spec import Case, Function, Misconception

from ..rotations import (
    quat_between,
    quat_conjugate,
    quat_from_axis_angle,
    quat_identity,
    quat_mul,
)
from ._cases import unit_quat, vector
from .spec import Exercise

_Z = np.array([0.0, 0.0, 1.0])


def rest_correction(l_target: np.ndarray, l_source: np.ndarray) -> np.ndarray:
    r"""Reference of 10.rest_correction: the shortest arc :math:`C` with
    :math:`C\,\hat l^{\,B} = \hat l^{\,A}`, turning the target's rest bone onto the source's."""
    return quat_between(l_target, l_source)


def _angle_not_halved(l_target: np.ndarray, l_source: np.ndarray) -> np.ndarray:
    """The turn built as (cos θ, sin θ n): twice the angle."""
    u, v = l_target / np.linalg.norm(l_target), l_source / np.linalg.norm(l_source)
    axis = np.cross(u, v)
    if np.linalg.norm(axis) < 1e-12:
        return quat_identity()
    return quat_from_axis_angle(axis / np.linalg.norm(axis),
                                2 * np.arccos(np.clip(u @ v, -1.0, 1.0)))


def _bone_cases(rng: np.random.Generator) -> list[Case]:
    down45 = np.array([np.cos(np.pi / 4), -np.sin(np.pi / 4), 0.0])
    cases = [Case("the left arm: T-pose bone along x, A-pose bone 45° down",
                  (np.array([1.0, 0.0, 0.0]), 6.0 * down45)),
             Case("the same direction, other lengths (a leg)",
                  (np.array([0.0, -2.0, 0.1]), np.array([0.0, -3.0, 0.15])))]
    for k in (1, 2):
        cases.append(Case(f"two random bones ({k})", (vector(rng), vector(rng))))
    return cases


def corrected_local(C_parent: np.ndarray, R_i: np.ndarray, C_i: np.ndarray) -> np.ndarray:
    r"""Reference of 10.corrected_local: :math:`R'_i = C_{p(i)}^{-1}\,R_i\,C_i`."""
    return quat_mul(quat_conjugate(C_parent), quat_mul(R_i, C_i))


def _correction_cases(rng: np.random.Generator) -> list[Case]:
    down45 = quat_from_axis_angle(_Z, -np.pi / 4)
    return [Case("the left arm: the parent uncorrected, C_i 45° about z",
                 (quat_identity(), unit_quat(rng), down45)),
            Case("the forearm: parent and joint both corrected by 45° about z",
                 (down45, unit_quat(rng), down45)),
            *(Case(f"random corrections and rotation ({k})",
                   (unit_quat(rng), unit_quat(rng), unit_quat(rng))) for k in (1, 2, 3))]


EXERCISES = (
    Exercise(
        "rest_correction",
        Function("rest_correction", ("l_target", "l_source"), rest_correction, QuatCheck()),
        _bone_cases,
        hint="C_i must turn the TARGET's rest bone onto the SOURCE's, by the smallest angle: "
             "about the axis perpendicular to both, by the angle between them. Which direction "
             "goes first? And a quaternion holds half the angle.",
        formula="C = shortest arc from l̂_target to l̂_source: "
                "<code>rot.quat_between(l_target, l_source)</code>, or "
                "(cos θ/2, sin θ/2 n) with n = l̂_t × l̂_s / |l̂_t × l̂_s|, θ = ∠(l_t, l_s).",
        mistakes=(
            Misconception("source_onto_target", "rest_correction",
                          "the source's bone turned onto the target's",
                          "C_i turns the target's rest bone onto the source's, "
                          "C_i l̂_target = l̂_source, so that Q_i C_i points the target's bone "
                          "where the source's points; yours is the inverse turn.",
                          wrong=lambda lt, ls: quat_between(ls, lt)),
            Misconception("angle_not_halved", "rest_correction",
                          "the whole angle in the quaternion, not half of it",
                          "A turn by θ about n is the quaternion (cos θ/2, sin θ/2 n); "
                          "(cos θ, sin θ n) turns by 2θ.",
                          wrong=_angle_not_halved),
        ),
    ),
    Exercise(
        "corrected_local",
        Function("corrected_local", ("C_parent", "R_i", "C_i"), corrected_local, QuatCheck()),
        _correction_cases,
        hint="The target's global orientation is the source's followed by the rest correction, "
             "Q'_i = Q_i C_i, and likewise for the parent. Write R'_i = Q'_parent⁻¹ Q'_i and "
             "let the source's own R_i = Q_parent⁻¹ Q_i appear.",
        formula="R'_i = C_p⁻¹ R_i C_i: the joint's correction on the RIGHT of R_i, the inverse "
                "of the parent's on the left (<code>rot.quat_conjugate</code>, "
                "<code>rot.quat_mul</code>).",
        mistakes=(
            Misconception("wrong_side", "corrected_local",
                          "the correction on the wrong side (C_i R_i instead of R_i C_i)",
                          "The correction acts in the joint's rest frame, before the motion: "
                          "Q'_i = Q_i C_i, so R'_i = C_p⁻¹ R_i C_i, C_i on the RIGHT of R_i; "
                          "C_p⁻¹ C_i R_i turns the bone by the motion first and corrects after.",
                          wrong=lambda Cp, R, C: quat_mul(quat_conjugate(Cp), quat_mul(C, R))),
            Misconception("parent_not_undone", "corrected_local",
                          "the parent's correction not undone",
                          "The parent's correction is already in the parent's global "
                          "orientation Q_p C_p; the child must take it off again: "
                          "R'_i = C_p⁻¹ R_i C_i, not R_i C_i.",
                          wrong=lambda Cp, R, C: quat_mul(R, C)),
            Misconception("inverses_swapped", "corrected_local",
                          "the inverse on the joint's correction instead of the parent's",
                          "Q'_i = Q_i C_i for every joint, so "
                          "R'_i = (Q_p C_p)⁻¹ Q_i C_i = C_p⁻¹ R_i C_i: the parent's correction is "
                          "inverted, the joint's is not.",
                          wrong=lambda Cp, R, C: quat_mul(Cp, quat_mul(R, quat_conjugate(C)))),
        ),
    ),
)
