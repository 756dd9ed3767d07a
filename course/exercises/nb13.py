"""Notebook 13 · rigid bodies: the angular velocity from the momentum, the torque of a force at
a point, and one quaternion step."""

from __future__ import annotations

import numpy as np

from autograder.checks import Check, QuatCheck
from autograder.spec import Case, Function, Misconception

from ..physics.rigid_body import angular_velocity, quat_euler_step
from ..physics.rigid_body import point_torque as _point_torque
from ..rotations import matrix_from_quat
from ._cases import unit_quat, vector
from .spec import Exercise


def world_omega(R: np.ndarray, I0: np.ndarray, L: np.ndarray) -> np.ndarray:
    r"""Reference of 13.world_omega: the world angular velocity of a body turned by ``R`` with
    body-frame inertia ``I₀`` and angular momentum ``L``, :math:`\omega = I^{-1} L` with
    :math:`I = R I_0 R^T` (:func:`~course.physics.rigid_body.angular_velocity`)."""
    return np.asarray(angular_velocity(L, R, I0))


def point_torque(p: np.ndarray, x: np.ndarray, f: np.ndarray) -> np.ndarray:
    r"""Reference of 13.point_torque: the torque about the centre of mass ``x`` of a force
    ``f`` applied at the point ``p``, :math:`\tau = (p - x) \times f`."""
    return np.asarray(_point_torque(p, x, f))


def quat_step(q: np.ndarray, omega: np.ndarray, h: float) -> np.ndarray:
    r"""Reference of 13.quat_step: one Euler step of :math:`\dot q = \tfrac12 [0, \omega]
    \otimes q`, renormalised (:func:`~course.physics.rigid_body.quat_euler_step`)."""
    return np.asarray(quat_euler_step(q, omega, h))


def _inertia(rng: np.random.Generator) -> np.ndarray:
    """A body-frame inertia with three different moments (a box of random half-extents)."""
    a, b, c = np.round(rng.uniform(0.2, 1.0, size=3), 2) ** 2
    return np.round(np.diag([b + c, a + c, a + b]) / 3.0, 4)


def _omega_cases(rng: np.random.Generator) -> list[Case]:
    quarter = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90° about z
    cases = [Case("turned 90° about z, I₀ = diag(1, 2, 3), L along x",
                  (quarter, np.diag([1.0, 2.0, 3.0]), np.array([1.0, 0.0, 0.0])))]
    for k in (1, 2, 3):
        cases.append(Case(f"a random body and momentum ({k})",
                          (matrix_from_quat(unit_quat(rng)), _inertia(rng), vector(rng))))
    return cases


def _torque_cases(rng: np.random.Generator) -> list[Case]:
    cases = [Case("a push along +z at a point 1 m along +x of the centre",
                  (np.array([1.0, 0.0, 0.0]), np.zeros(3), np.array([0.0, 0.0, 1.0])))]
    for k in (1, 2, 3):
        cases.append(Case(f"a random force at a random point ({k})",
                          (vector(rng), vector(rng), vector(rng, 5.0))))
    return cases


def _quat_cases(rng: np.random.Generator) -> list[Case]:
    cases = [Case("from the identity, 2 rad/s about y, h = 0.1 s",
                  (np.array([1.0, 0.0, 0.0, 0.0]), np.array([0.0, 2.0, 0.0]), 0.1))]
    for k in (1, 2, 3):
        cases.append(Case(f"a random orientation and spin ({k})",
                          (unit_quat(rng), vector(rng, 3.0),
                           float(rng.choice([0.02, 0.05, 0.1])))))
    return cases


def _mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of two quaternions (w, x, y, z)."""
    w1, v1, w2, v2 = a[0], a[1:], b[0], b[1:]
    return np.concatenate([[w1 * w2 - v1 @ v2], w1 * v2 + w2 * v1 + np.cross(v1, v2)])


def _pure(omega: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], omega])


EXERCISES = (
    Exercise(
        "world_omega",
        Function("world_omega", ("R", "I0", "L"), world_omega, Check((3,), noun="ω")),
        _omega_cases,
        hint="I₀ is the inertia in the body's own frame; the momentum L is in the world frame. "
             "Bring the inertia into the world first (it turns with the body), then solve.",
        formula="I = R I₀ Rᵀ (<code>R @ I0 @ R.T</code>); ω = I⁻¹ L "
                "(<code>np.linalg.solve(I, L)</code>).",
        mistakes=(
            Misconception("body_inertia", "world_omega", "the body-frame inertia used for ω",
                          "I₀⁻¹ L mixes frames: I₀ is the inertia in the body frame, L is in "
                          "the world. Turn the inertia with the body, I = R I₀ Rᵀ, then ω = "
                          "I⁻¹ L.",
                          wrong=lambda R, I0, L: np.linalg.solve(I0, L)),
            Misconception("inverse_turn", "world_omega", "the inertia turned the wrong way "
                          "(Rᵀ I₀ R)",
                          "Rᵀ I₀ R turns the inertia from the world into the body frame; the "
                          "world inertia of a body turned by R is R I₀ Rᵀ.",
                          wrong=lambda R, I0, L: np.linalg.solve(R.T @ I0 @ R, L)),
            Misconception("times_inertia", "world_omega", "L multiplied by I instead of solved",
                          "L = I ω, so ω = I⁻¹ L: solve with I (or multiply by its inverse), do "
                          "not multiply L by I.",
                          wrong=lambda R, I0, L: R @ I0 @ R.T @ L),
        ),
    ),
    Exercise(
        "point_torque",
        Function("point_torque", ("p", "x", "f"), point_torque, Check((3,), noun="torque")),
        _torque_cases,
        hint="The torque is the lever arm crossed with the force. Where does the lever arm start, "
             "where does it end, and which factor comes first in the cross product?",
        formula="τ = (p − x) × f (<code>np.cross(p - x, f)</code>).",
        mistakes=(
            Misconception("flipped_cross", "point_torque",
                          "the torque's sign flipped: f × (p − x), or (x − p) × f",
                          "f × (p − x) = (x − p) × f = −(p − x) × f: the torque points the other "
                          "way and the body turns backwards. The lever arm points from the centre "
                          "to where the force acts, and comes first: τ = (p − x) × f.",
                          wrong=lambda p, x, f: np.cross(f, p - x)),
            Misconception("about_origin", "point_torque", "the torque about the world origin",
                          "p × f is the torque about the origin; a free body turns about its "
                          "centre of mass, so the lever arm is p − x: τ = (p − x) × f.",
                          wrong=lambda p, x, f: np.cross(p, f)),
        ),
    ),
    Exercise(
        "quat_step",
        Function("quat_step", ("q", "omega", "h"), quat_step, QuatCheck()),
        _quat_cases,
        hint="q̇ = ½ [0, ω] ⊗ q with ω in the world frame: one Euler step, and then the result is "
             "a little too long. What must a unit quaternion be?",
        formula="q⁺ = q + (h/2) [0, ω] ⊗ q (the pure quaternion on the left: ω is in the "
                "world), then q⁺ / ‖q⁺‖.",
        mistakes=(
            Misconception("not_renormalised", "quat_step", "q⁺ not renormalised",
                          "q + (h/2) [0, ω] ⊗ q is longer than 1 by about (h‖ω‖/2)²/2; divide "
                          "by its norm every step, or the orientation stops being a rotation.",
                          wrong=lambda q, w, h: q + 0.5 * h * _mul(_pure(w), q)),
            Misconception("body_side", "quat_step", "ω multiplied on the right (a body-frame ω)",
                          "q ⊗ [0, ω] is the derivative for ω in the body frame; with the world "
                          "ω the pure quaternion goes on the left: q̇ = ½ [0, ω] ⊗ q.",
                          wrong=lambda q, w, h: (lambda r: r / np.linalg.norm(r))(
                              q + 0.5 * h * _mul(q, _pure(w)))),
            Misconception("no_half", "quat_step", "the factor ½ missing",
                          "a quaternion turns by half the angle: q̇ = ½ [0, ω] ⊗ q; without ½ "
                          "the body turns twice as fast.",
                          wrong=lambda q, w, h: (lambda r: r / np.linalg.norm(r))(
                              q + h * _mul(_pure(w), q))),
        ),
    ),
)
