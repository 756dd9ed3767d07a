"""Notebook 01 · rotations: composing two rotations, and rotating by a quaternion."""

from __future__ import annotations

import numpy as np

from autograder.checks import Check, MatrixCheck
from autograder.spec import Case, Function, Misconception

from ..rotations import matrix_from_axis_angle, matrix_from_quat, quat_conjugate, quat_rotate
from ._cases import unit_quat, vector
from .spec import Exercise


def compose(R_first: np.ndarray, R_second: np.ndarray) -> np.ndarray:
    r"""Reference of 01.compose: apply :math:`R_{first}`, then :math:`R_{second}`:
    :math:`R = R_{second} R_{first}`."""
    return np.asarray(R_second @ R_first, dtype=float)


def rotate_vector(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    r"""Reference of 01.quat_rotate: :math:`q\,(0, v)\,q^*`, the vector part."""
    return quat_rotate(q, v)


def _matrix_pairs(rng: np.random.Generator) -> list[Case]:
    z, x = np.eye(3)[2], np.eye(3)[0]
    cases = [Case("R_z(90°) first, then R_x(90°)", (matrix_from_axis_angle(z, np.pi / 2),
                                                   matrix_from_axis_angle(x, np.pi / 2)))]
    cases += [Case(f"two random rotations ({k})", (matrix_from_quat(unit_quat(rng)),
                                                   matrix_from_quat(unit_quat(rng))))
              for k in (1, 2, 3)]
    return cases


def _quat_vectors(rng: np.random.Generator) -> list[Case]:
    quarter_z = np.array([np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)])
    return [Case("90° about z, applied to x", (quarter_z, np.array([1.0, 0.0, 0.0]))),
            *(Case(f"a random rotation ({k})", (unit_quat(rng), vector(rng))) for k in (1, 2, 3))]


def _quat_product_by_hand(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    return quat_rotate(quat_conjugate(q), v)


EXERCISES = (
    Exercise(
        "compose",
        Function("compose", ("R_first", "R_second"), compose, MatrixCheck()),
        _matrix_pairs,
        hint="A matrix acts on the column vector to its right: R v. Apply R_first to v, then "
             "R_second to the result, and read off the single matrix that does both.",
        formula="R_second (R_first v) = (R_second R_first) v.",
        mistakes=(
            Misconception("wrong_order", "compose", "the product in the wrong order",
                          "3D rotations do not commute: 'first R_first, then R_second' is "
                          "R_second R_first (the first one stands next to the vector); "
                          "R_first R_second applies them the other way round.",
                          wrong=lambda a, b: a @ b),
        ),
    ),
    Exercise(
        "quat_rotate",
        Function("rotate_vector", ("q", "v"), rotate_vector, Check((3,), noun="vector")),
        _quat_vectors,
        hint="Write v as a pure quaternion (0, v), sandwich it between q and its conjugate, "
             "and keep the vector part. rot.quat_mul multiplies two quaternions.",
        formula="(0, v') = q (0, v) q*, with q* = (w, −x, −y, −z).",
        mistakes=(
            Misconception("conjugate_sandwich", "rotate_vector", "q* v q for q v q*",
                          "The rotation by q is q (0, v) q*; q* (0, v) q rotates by the "
                          "inverse, q*.",
                          wrong=_quat_product_by_hand),
        ),
    ),
)
