"""Notebook 08 · the IK race: how far a joint turned between two frames."""

from __future__ import annotations

import numpy as np

from autograder.checks import Check
from autograder.spec import Case, Function, Misconception

from ..rotations import quat_angle, quat_conjugate, quat_mul
from ._cases import unit_quat
from .check import Exercise


def frame_turn(q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    r"""Reference of 08.frame_turn: the angle of :math:`q_0^{-1} q_1`, in :math:`[0, \pi]`."""
    return quat_angle(q0, q1)


def _signed_turn(q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """2 acos(w) without taking |w|: q and −q come out 2π apart."""
    d = quat_mul(quat_conjugate(q0), q1)
    return np.asarray(2 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), d[..., 0]))


def _frames(rng: np.random.Generator) -> list[Case]:
    q0 = np.array([unit_quat(rng) for _ in range(4)])
    small = np.array([np.cos(0.05), np.sin(0.05), 0.0, 0.0])
    q1 = quat_mul(q0, small)
    q1[2] *= -1  # the same rotation, stored with the other sign
    return [Case("four joints, each turned 0.1 rad about x (one stored as −q)", (q0, q1)),
            Case("four joints, random turns", (q0, np.array([unit_quat(rng) for _ in range(4)])))]


EXERCISES = (
    Exercise(
        "frame_turn",
        Function("frame_turn", ("q0", "q1"), frame_turn, Check(None, noun="angles")),
        _frames,
        hint="The turn from frame to frame is the rotation q0⁻¹ q1. Its angle follows from its "
             "scalar part — but remember that q and −q are the same rotation.",
        formula="d = q0* q1 (per joint), θ = 2 atan2(‖(d_x, d_y, d_z)‖, |d_w|), in [0, π].",
        mistakes=(
            Misconception("double_cover", "frame_turn", "q and −q counted as different turns",
                          "q and −q are the same rotation; without |d_w| a quaternion that "
                          "only flipped sign shows a turn of nearly 2π. Take "
                          "θ = 2 atan2(‖v‖, |w|).",
                          wrong=_signed_turn),
            Misconception("half_angle", "frame_turn", "the half angle",
                          "A unit quaternion stores cos θ/2 and sin θ/2: the turn is twice "
                          "atan2(‖v‖, |w|).",
                          wrong=lambda q0, q1: quat_angle(q0, q1) / 2),
        ),
    ),
)
