"""Notebook 07 · Jacobian IK: one column of J, one damped least-squares step."""

from __future__ import annotations

import numpy as np

from autograder.checks import Check
from autograder.spec import Case, Function, Misconception

from ..ik import chain_jacobian, dls_step
from ._cases import vector
from .spec import Exercise


def jacobian_column(r_i: np.ndarray, a_i: np.ndarray, e: np.ndarray) -> np.ndarray:
    r"""Reference of 07.jacobian_column: :math:`J_i = a_i \times (e - r_i)`."""
    return chain_jacobian(r_i[None], a_i[None], e)[:, 0]


def damped_step(J: np.ndarray, de: np.ndarray, lam: float) -> np.ndarray:
    r"""Reference of 07.dls_step: :math:`\Delta\theta = J^T(JJ^T + \lambda^2 I)^{-1}\Delta e`."""
    return dls_step(J, de, lam)


def _column_cases(rng: np.random.Generator) -> list[Case]:
    z = np.array([0.0, 0.0, 1.0])
    cases = [Case("a planar hinge at the origin", (np.zeros(3), z, np.array([2.0, 0.0, 0.0]))),
             Case("the axis along the lever arm", (np.zeros(3), np.array([1.0, 0.0, 0.0]),
                                                  np.array([2.0, 0.0, 0.0])))]
    for k in (1, 2, 3):
        a = vector(rng)
        cases.append(Case(f"a random joint ({k})", (vector(rng), a / np.linalg.norm(a),
                                                    vector(rng))))
    return cases


def _step_cases(rng: np.random.Generator) -> list[Case]:
    straight = np.array([[0.0, 0.0], [2.0, 1.0], [0.0, 0.0]])  # a straight 2-link arm along x
    cases = [Case("a straight arm: J has rank 1", (straight, np.array([-0.1, 0.05, 0.0]), 0.1))]
    for k, (n, lam) in enumerate([(2, 0.5), (4, 0.1), (6, 1.0)], start=1):
        J = np.round(rng.normal(size=(3, n)), 2)
        cases.append(Case(f"a random {3}×{n} Jacobian ({k})", (J, vector(rng, 0.3), lam)))
    return cases


EXERCISES = (
    Exercise(
        "jacobian_column",
        Function("jacobian_column", ("r_i", "a_i", "e"), jacobian_column,
                 Check((3,), noun="column")),
        _column_cases,
        hint="Column i is the velocity of the end effector when joint i alone turns at unit "
             "speed about its axis. A point turning about a line through r_i moves "
             "perpendicular to both the axis and its lever arm.",
        formula="J_i = a_i × (e − r_i), the lever arm measured from the joint; "
                "<code>np.cross(a, b)</code> is a × b.",
        mistakes=(
            Misconception("reversed_cross", "jacobian_column", "the cross product reversed",
                          "(e − r_i) × a_i = −a_i × (e − r_i): the column points the other way, "
                          "and the joint would turn away from the target.",
                          wrong=lambda r, a, e: np.cross(e - r, a)),
            Misconception("origin_lever", "jacobian_column", "the lever arm from the origin",
                          "A joint turns the end effector about itself: the lever arm is "
                          "e − r_i, measured from the joint's position, not from the origin.",
                          wrong=lambda r, a, e: np.cross(a, e)),
        ),
    ),
    Exercise(
        "dls_step",
        Function("damped_step", ("J", "de", "lam"), damped_step, Check(None, noun="step")),
        _step_cases,
        hint="Damped least squares minimises |J Δθ − Δe|² + λ²|Δθ|². Set its gradient to zero; "
             "the system to solve is as small as Δe (3 × 3). Use np.linalg.solve, not inv.",
        formula="Δθ = Jᵀ (J Jᵀ + λ² I)⁻¹ Δe — λ squared (λ is a length, as Δe).",
        mistakes=(
            Misconception("unsquared_damping", "damped_step", "λ where λ² belongs",
                          "The penalty is λ²|Δθ|², so the matrix is J Jᵀ + λ² I; adding λ I "
                          "damps by √λ instead.",
                          wrong=lambda J, de, lam: dls_step(J, de, np.sqrt(lam))),
            Misconception("no_damping", "damped_step", "the undamped pseudo-inverse step",
                          "λ = 0 is the pseudo-inverse step J⁺Δe, which explodes as a singular "
                          "value goes to 0; DLS adds λ² I inside the inverse.",
                          wrong=lambda J, de, lam: np.linalg.pinv(J) @ de),
            Misconception("transpose_only", "damped_step", "the Jacobian transpose alone",
                          "Jᵀ Δe is the gradient direction (the transpose method) without the "
                          "inverse (J Jᵀ + λ² I)⁻¹ that scales it.",
                          wrong=lambda J, de, lam: J.T @ de),
        ),
    ),
)
