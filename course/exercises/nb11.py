"""Notebook 11 · keyframes: one cubic Hermite segment, and the Catmull–Rom tangent at an
inner key."""

from __future__ import annotations

import numpy as np

from autograder.checks import Check
from autograder.spec import Case, Function, Misconception

from ..keyframes import catmull_rom, hermite
from ._cases import vector
from .spec import Exercise


def catmull_rom_tangent(p_prev: np.ndarray, p_next: np.ndarray, t_prev: float, t_i: float,
                        t_next: float) -> np.ndarray:
    r"""Reference of 11.catmull_rom_tangent: the velocity of :func:`~course.keyframes.catmull_rom`
    (``knots="time"``) at an inner key,
    :math:`m_i = (p_{i+1} - p_{i-1}) / (t_{i+1} - t_{i-1})`."""
    keys = np.stack([p_prev, (p_prev + p_next) / 2, p_next])  # the inner key's value is not used
    return catmull_rom(keys, np.array([t_prev, t_i, t_next]), t_i, derivative=1)


def hermite_segment(p0: np.ndarray, p1: np.ndarray, m0: np.ndarray, m1: np.ndarray, h: float,
                    u: float) -> np.ndarray:
    r"""Reference of 11.hermite_segment: :func:`~course.keyframes.hermite` on one segment of
    length :math:`h` at :math:`t = u h`,
    :math:`(2u^3-3u^2+1)p_0 + (u^3-2u^2+u)h m_0 + (-2u^3+3u^2)p_1 + (u^3-u^2)h m_1`."""
    return hermite(np.stack([p0, p1]), np.stack([m0, m1]), np.array([0.0, h]), u * h)


def _hermite_unscaled(p0: np.ndarray, p1: np.ndarray, m0: np.ndarray, m1: np.ndarray, h: float,
                      u: float) -> np.ndarray:
    """The tangents used per unit of u, without the segment's length h."""
    return hermite_segment(p0, p1, m0 / h, m1 / h, h, u)


def _hermite_flipped_h11(p0: np.ndarray, p1: np.ndarray, m0: np.ndarray, m1: np.ndarray,
                         h: float, u: float) -> np.ndarray:
    """H₁₁ = u² − u³ (the end tangent's weight with the wrong sign)."""
    return hermite_segment(p0, p1, m0, -m1, h, u)


def _tangent_cases(rng: np.random.Generator) -> list[Case]:
    cases = [Case("three keys a second apart", (np.array([0.0, 0.0, 0.0]),
                                                 np.array([2.0, 1.0, 0.0]), 0.0, 1.0, 2.0)),
             Case("uneven times: a short gap, then a long one",
                  (np.array([1.0, 0.0, 0.0]), np.array([0.0, 3.0, 0.0]), 0.0, 0.2, 1.5))]
    for k in (1, 2):
        t = np.round(np.cumsum(rng.uniform(0.2, 1.5, 3)), 2)
        cases.append(Case(f"random keys and times ({k})",
                          (vector(rng), vector(rng), *map(float, t))))
    return cases


def _segment_cases(rng: np.random.Generator) -> list[Case]:
    cases = [Case("a half-second segment, at its middle",
                  (np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 2.0, 0.0]),
                   np.array([0.0, -2.0, 0.0]), 0.5, 0.5))]
    for k in (1, 2, 3):
        cases.append(Case(f"a random segment ({k})",
                          (vector(rng), vector(rng), vector(rng), vector(rng),
                           float(np.round(rng.uniform(0.3, 2.0), 2)),
                           float(np.round(rng.uniform(0.1, 0.9), 2)))))
    return cases


EXERCISES = (
    Exercise(
        "hermite_segment",
        Function("hermite_segment", ("p0", "p1", "m0", "m1", "h", "u"), hermite_segment,
                 Check((3,), noun="point")),
        _segment_cases,
        hint="Four basis polynomials in u weigh the two end points and the two end tangents. "
             "The tangents are per second, u runs from 0 to 1 over h seconds: what turns a "
             "velocity into a change per unit of u?",
        formula="h(u) = (2u³−3u²+1) p0 + (u³−2u²+u) h m0 + (−2u³+3u²) p1 + (u³−u²) h m1.",
        mistakes=(
            Misconception("tangents_not_scaled", "hermite_segment",
                          "the tangents not multiplied by the segment's length h",
                          "m0 and m1 are velocities dp/dt; the basis is in u = (t − t_i)/h, so "
                          "the tangent terms are h m0 and h m1.",
                          wrong=_hermite_unscaled),
            Misconception("h11_sign", "hermite_segment",
                          "the end tangent's weight with the wrong sign",
                          "H₁₁ = u³ − u², negative inside the segment: it pulls the curve "
                          "back along m1 so that it arrives at p1 with velocity m1.",
                          wrong=_hermite_flipped_h11),
        ),
    ),
    Exercise(
        "catmull_rom_tangent",
        Function("catmull_rom_tangent", ("p_prev", "p_next", "t_prev", "t_i", "t_next"),
                 catmull_rom_tangent, Check((3,), noun="tangent")),
        _tangent_cases,
        hint="The tangent is a velocity, a change of position per unit of time. Which two keys "
             "does Catmull–Rom difference, and how much time passes between them?",
        formula="m_i = (p_next − p_prev) / (t_next − t_prev): the central difference over "
                "both segments (the key's own value p_i is not used).",
        mistakes=(
            Misconception("one_interval", "catmull_rom_tangent",
                          "the difference divided by one segment's length",
                          "p_next − p_prev spans two segments: divide by the time between the "
                          "two neighbours, t_next − t_prev, not by t_next − t_i.",
                          wrong=lambda a, b, t0, t1, t2: (b - a) / (t2 - t1)),
            Misconception("not_divided", "catmull_rom_tangent",
                          "the difference not divided by the time",
                          "p_next − p_prev is a displacement; the tangent m_i = dp/dt is a "
                          "velocity: divide by t_next − t_prev.",
                          wrong=lambda a, b, t0, t1, t2: b - a),
        ),
    ),
)
