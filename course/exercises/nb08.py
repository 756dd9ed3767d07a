"""Notebook 08 · the IK race: the statistics of the iteration counts, and how far a joint
turned between two frames."""

from __future__ import annotations

import numpy as np

from autograder.checks import Check
from autograder.spec import Case, Function, Misconception

from ..rotations import quat_angle, quat_conjugate, quat_mul
from ._cases import unit_quat
from .spec import Exercise


def iteration_stats(iterations: np.ndarray) -> np.ndarray:
    """Reference of 08.iteration_stats: the mean, the median and the 90th percentile (numpy's
    default, linear interpolation) of the iteration counts."""
    return np.array([np.mean(iterations), np.median(iterations), np.percentile(iterations, 90)])


def _counts(rng: np.random.Generator) -> list[Case]:
    tail = np.array([3, 4, 4, 5, 5, 6, 7, 9, 40, 310])
    return [Case("ten targets, one far in the tail", (tail,)),
            Case("an odd number of targets", (np.array([12, 2, 7, 3, 95]),)),
            *(Case(f"60 random counts with a long tail ({k})",
                   (np.ceil(rng.lognormal(2.0, 1.2, 60)).astype(int),)) for k in (1, 2))]


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
        "iteration_stats",
        Function("iteration_stats", ("iterations",), iteration_stats,
                 Check((3,), noun="statistics")),
        _counts,
        hint="The mean is pulled up by a few slow targets; the median is the middle of the "
             "sorted counts; the 90th percentile is the count that 90 % of the targets do not "
             "exceed. numpy has a function for each — mind what the percentile function wants.",
        formula="(<code>np.mean(iterations)</code>, <code>np.median(iterations)</code>, "
                "<code>np.percentile(iterations, 90)</code>): the percentile in percent, 90.",
        mistakes=(
            Misconception("fraction_for_percent", "iteration_stats",
                          "the percentile given as a fraction",
                          "np.percentile takes percent: np.percentile(x, 90); with 0.9 it "
                          "returns the 0.9th percentile, nearly the fastest target "
                          "(np.quantile is the one that takes 0.9).",
                          wrong=lambda its: np.array([np.mean(its), np.median(its),
                                                      np.percentile(its, 0.9)])),
            Misconception("mean_for_median", "iteration_stats", "the mean as the median",
                          "The median is the middle of the sorted counts (np.median); a long "
                          "tail pulls the mean far above it.",
                          wrong=lambda its: np.array([np.mean(its), np.mean(its),
                                                      np.percentile(its, 90)])),
            Misconception("worst_for_tail", "iteration_stats",
                          "the worst case as the 90th percentile",
                          "The 90th percentile is the count 90 % of the targets stay within "
                          "(np.percentile(x, 90)); the worst case, np.max, is a single target.",
                          wrong=lambda its: np.array([np.mean(its), np.median(its),
                                                      np.max(its)])),
        ),
    ),
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
