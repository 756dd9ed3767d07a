"""Notebook 06 · FABRIK: the forward pass, and the answer to an unreachable target."""

from __future__ import annotations

import numpy as np

from autograder.checks import PointsCheck
from autograder.spec import Case, Function, Misconception

from .spec import Exercise


def _reach(P: np.ndarray, t: np.ndarray, d: np.ndarray, wrong_point: bool = False) -> np.ndarray:
    """The forward pass, or (``wrong_point``) the lab's variant that measures each bone's
    direction from the old position of the joint beyond it."""
    old, P = P, np.array(P, dtype=float)
    P[-1] = t
    for i in range(len(P) - 2, -1, -1):
        beyond = old[i + 1] if wrong_point else P[i + 1]
        u = P[i] - beyond
        P[i] = P[i + 1] + d[i] * u / np.linalg.norm(u)
    return P


def forward_pass(P: np.ndarray, t: np.ndarray, d: np.ndarray) -> np.ndarray:
    r"""Reference of 06.forward_pass: :math:`p_n \leftarrow t`, then for :math:`i = n-1, \dots, 0`,
    :math:`p_i \leftarrow p_{i+1} + d_i\,\widehat{(p_i - p_{i+1})}`."""
    return _reach(P, t, d)


def stretched(b: np.ndarray, t: np.ndarray, d: np.ndarray) -> np.ndarray:
    r"""Reference of 06.stretch: the chain from the base ``b`` straight towards ``t``,
    :math:`p_0 = b,\ p_{i+1} = p_i + d_i\,\widehat{(t - b)}`."""
    u = (t - b) / np.linalg.norm(t - b)
    return np.asarray(b + np.concatenate([[0.0], np.cumsum(d)])[:, None] * u, dtype=float)


def _stretched_to_target(b: np.ndarray, t: np.ndarray, d: np.ndarray) -> np.ndarray:
    """The bones scaled so that the end lands on ``t`` (lengths not kept)."""
    return np.asarray(b + (np.concatenate([[0.0], np.cumsum(d)]) / np.sum(d))[:, None] * (t - b))


def _far_targets(rng: np.random.Generator) -> list[Case]:
    cases = [Case("three bones along x, the target beyond", (np.zeros(3), np.array([5.0, 0, 0]),
                                                           np.array([1.0, 0.8, 0.6])))]
    for k in (1, 2):
        d = np.round(rng.uniform(0.3, 1.0, 4), 2)
        b = np.round(rng.normal(size=3), 2)
        direction = rng.normal(size=3)
        t = np.round(b + 1.5 * d.sum() * direction / np.linalg.norm(direction), 2)
        cases.append(Case(f"a random 4-bone chain, target out of reach ({k})", (b, t, d)))
    return cases


def _chains(rng: np.random.Generator) -> list[Case]:
    flat = np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]])
    cases = [Case("a straight 2-bone arm, target above", (flat, np.array([1.5, 1.0, 0.0]),
                                                        np.array([1.0, 1.0])))]
    for k, n in enumerate((3, 4, 5), start=1):
        d = np.round(rng.uniform(0.3, 1.0, n), 2)
        dirs = rng.normal(size=(n, 3))
        P = np.vstack([np.zeros(3), np.cumsum(d[:, None] * dirs / np.linalg.norm(
            dirs, axis=1, keepdims=True), axis=0)])
        cases.append(Case(f"a random {n}-bone chain ({k})",
                          (P, np.round(rng.normal(size=3), 2), d)))
    return cases


EXERCISES = (
    Exercise(
        "forward_pass",
        Function("forward_pass", ("P", "t", "d"), forward_pass,
                 PointsCheck(row="joint")),
        _chains,
        hint="Put the end effector on the target, then walk back towards the root: each joint "
             "slides along the line to its (already moved) successor until the bone has its "
             "length again. Work on a copy of P.",
        formula="p_n ← t; for i = n−1 … 0: p_i ← p_{i+1} + d_i (p_i − p_{i+1}) / |p_i − p_{i+1}|.",
        mistakes=(
            Misconception("old_successor", "forward_pass",
                          "the direction measured from the old successor",
                          "Each joint is placed on the line to its successor's *new* position, "
                          "p_{i+1} just computed; measuring from where p_{i+1} was before it "
                          "moved (a point not yet updated) puts the joint on the wrong line.",
                          wrong=lambda P, t, d: _reach(P, t, d, wrong_point=True)),
        ),
    ),
    Exercise(
        "stretch",
        Function("stretched", ("b", "t", "d"), stretched, PointsCheck(row="joint")),
        _far_targets,
        hint="Out of reach, every joint lies on the ray from the base towards the target, "
             "each bone at its own length: add the bones one after the other along that ray.",
        formula="u = (t − b) / |t − b|; p_0 = b, p_{i+1} = p_i + d_i u.",
        mistakes=(
            Misconception("scaled_to_target", "stretched", "the bones stretched to the target",
                          "Bones are rigid: out of reach, the chain points at the target with "
                          "every bone at its length d_i, p_{i+1} = p_i + d_i u, and the end "
                          "stops |t − b| − Σ d_i short of it.",
                          wrong=_stretched_to_target),
        ),
    ),
)
