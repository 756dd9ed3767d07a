"""Notebook 12 · mass–spring systems: the force of one spring, and one symplectic Euler
step."""

from __future__ import annotations

import numpy as np

from autograder.checks import Check
from autograder.spec import Case, Function, Misconception

from ..physics import SpringSystem, step
from ._cases import vector
from .spec import Exercise


def spring_force(x_i: np.ndarray, x_j: np.ndarray, k: float, L: float) -> np.ndarray:
    r"""Reference of 12.spring_force: the force on particle :math:`i` of one spring,
    :math:`f_i = -\nabla_{x_i} U = -k\,(1 - L/\lVert d\rVert)\,d`, :math:`d = x_i - x_j`
    (:meth:`~course.physics.SpringSystem.forces` without gravity)."""
    system = SpringSystem.create([1.0, 1.0], [[0, 1]], [L], k, gravity=(0.0, 0.0, 0.0))
    return np.asarray(system.forces(np.stack([x_i, x_j]))[0])


def symplectic_step(x: np.ndarray, v: np.ndarray, f: np.ndarray, m: float,
                    h: float) -> np.ndarray:
    r"""Reference of 12.symplectic_step: one symplectic Euler step of a particle of mass
    :math:`m` under the force :math:`f = f(x)`, :math:`v^+ = v + h f/m`, :math:`x^+ = x + h v^+`;
    returns ``np.array([x⁺, v⁺])``. (:func:`~course.physics.step` on a particle whose only
    force is a constant field ``f/m``: its one spring is at rest length.)"""
    anchor = x + np.array([1.0, 0.0, 0.0])
    system = SpringSystem.create([m, 1.0], [[0, 1]], [1.0], 1.0, fixed=[1], gravity=f / m)
    x_new, v_new, _ = step(system, np.stack([x, anchor]), np.stack([v, np.zeros(3)]), h,
                           "symplectic")
    return np.array([x_new[0], v_new[0]])


def _spring_cases(rng: np.random.Generator) -> list[Case]:
    cases = [Case("stretched along x: length 2, rest 1.5",
                  (np.array([2.0, 0.0, 0.0]), np.zeros(3), 10.0, 1.5)),
             Case("compressed along y: length 0.5, rest 1",
                  (np.array([0.0, 0.5, 0.0]), np.zeros(3), 4.0, 1.0))]
    for k in (1, 2):
        x_i, x_j = vector(rng), vector(rng)
        length = float(np.linalg.norm(x_i - x_j))
        rest = round(length * float(rng.choice([0.6, 1.3])), 2)
        cases.append(Case(f"a random spring ({k})",
                          (x_i, x_j, float(np.round(rng.uniform(5, 50), 1)), rest)))
    return cases


def _step_cases(rng: np.random.Generator) -> list[Case]:
    cases = [Case("falling at 1 m/s, gravity on 0.5 kg, h = 0.1 s",
                  (np.array([0.0, 1.0, 0.0]), np.array([0.0, -1.0, 0.0]),
                   np.array([0.0, -4.905, 0.0]), 0.5, 0.1))]
    for k in (1, 2, 3):
        cases.append(Case(f"a random particle ({k})",
                          (vector(rng), vector(rng), vector(rng, 5.0),
                           float(np.round(rng.uniform(0.2, 3.0), 2)),
                           float(rng.choice([0.01, 0.05, 0.1])))))
    return cases


EXERCISES = (
    Exercise(
        "spring_force",
        Function("spring_force", ("x_i", "x_j", "k", "L"), spring_force,
                 Check((3,), noun="force")),
        _spring_cases,
        hint="The force is minus the gradient of U = ½ k (l − L)²: it points along d = x_i − "
             "x_j, and a stretched spring (l > L) pulls i back towards j.",
        formula="d = x_i − x_j, l = ‖d‖ (<code>np.linalg.norm(d)</code>); "
                "f_i = −k (1 − L/l) d.",
        mistakes=(
            Misconception("flipped_sign", "spring_force", "the force's sign flipped",
                          "+k (1 − L/l) d is the gradient ∇U, which pushes a stretched spring "
                          "further apart; the force is −∇U = −k (1 − L/l) d.",
                          wrong=lambda a, b, k, L: k * (1 - L / np.linalg.norm(a - b)) * (a - b)),
            Misconception("unnormalised", "spring_force",
                          "the stretch times d instead of its direction",
                          "k (l − L) is the force's size; multiply it by the unit direction "
                          "d / l, not by d: f_i = −k (l − L) d / l = −k (1 − L/l) d.",
                          wrong=lambda a, b, k, L: -k * (np.linalg.norm(a - b) - L) * (a - b)),
        ),
    ),
    Exercise(
        "symplectic_step",
        Function("symplectic_step", ("x", "v", "f", "m", "h"), symplectic_step,
                 Check((2, 3), noun="state")),
        _step_cases,
        hint="Two updates, and their order matters: which one goes first, and does the second "
             "use the old or the new value of the first?",
        formula="v⁺ = v + h f / m first, then x⁺ = x + h v⁺ (the new velocity); return "
                "<code>np.array([x_new, v_new])</code>.",
        mistakes=(
            Misconception("explicit_order", "symplectic_step",
                          "x updated with the old velocity (explicit Euler)",
                          "x⁺ = x + h v with the old v is explicit Euler, which gains energy "
                          "every step; symplectic Euler moves x with the new velocity, "
                          "x⁺ = x + h v⁺.",
                          wrong=lambda x, v, f, m, h: np.array([x + h * v, v + h * f / m])),
            Misconception("no_mass", "symplectic_step", "the force used as an acceleration",
                          "Newton's law: the acceleration is M⁻¹ f = f / m; v⁺ = v + h f / m.",
                          wrong=lambda x, v, f, m, h: np.array([x + h * (v + h * f),
                                                                v + h * f])),
        ),
    ),
)
