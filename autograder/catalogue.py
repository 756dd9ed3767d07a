"""Mistakes any assignment can show, catalogued once for all of them.

An assignment's own catalogue (``MISCONCEPTIONS`` in ``assignments/a1.py``, ...) names the
mistakes of its own functions. The two families here are the same in every assignment, so a
mistake known in one is recognised in all:

* **conventions** — tried on every quaternion and rotation matrix a function returns (alone or
  as an item of a tuple, such as forward kinematics' orientations): the quaternion written
  scalar-last ``(x, y, z, w)``, the conjugate ``q*`` (the inverse rotation), the transposed
  matrix ``Rᵀ``; and on every angle a function is given (a parameter named ``angle``,
  ``angles`` or ``theta``): radians converted "from degrees" once more.
* **tangents** — Catmull–Rom's tangent at a key written as the textbook's uniform
  ``(p_{i+1} - p_{i-1})/2`` whatever the key times (right only one key per second): on a
  function of the tangent itself (parameters ``p_prev, p_next, t_prev, t_i, t_next``, a
  notebook's exercise) and on a spline through keys (``keys, times, t``).
* **pivots** — a step that turns a sub-chain, ``p_k ← r_i + R(p_k − r_i)`` for the joints
  ``k`` beyond joint ``i``, turns it about the wrong point: the world origin, the end effector,
  or measured at the next joint. An assignment with such a step says how its function shows
  each (:func:`pivot_mistakes`).

An assignment's own entry with the same key wins: its explanation is more specific.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .checks import Check, MatrixCheck, QuatCheck, TupleCheck
from .spec import Function, Misconception

ANGLE_PARAMS = frozenset({"angle", "angles", "theta"})

XYZW = ("quaternion written as (x, y, z, w)",
        "The course stores the scalar first, q = (w, x, y, z) = (cos θ/2, sin θ/2·u); {your} "
        "{has} w last, as (x, y, z, w) (the order of scipy and Unity).")
CONJUGATE = ("the conjugate quaternion (the inverse rotation)",
             "{Your} {is} q* = (w, -x, -y, -z), the inverse of the rotation asked for: check the "
             "sign of the vector part (sin θ/2·u) and the order of every product.")
TRANSPOSED = ("the transposed matrix (the inverse rotation)",
              "{Your} {is} Rᵀ = R⁻¹, the inverse rotation: the columns of R are the turned "
              "axes R x̂, R ŷ, R ẑ; check the signs of the sine terms across the diagonal.")
DEGREES = ("degrees for radians",
           "The angles arrive in radians already; converting them again with np.radians / "
           "np.deg2rad shrinks every turn by a factor 180/π ≈ 57.")

UNIFORM_TANGENT = (
    "the uniform tangent (p_{i+1} - p_{i-1})/2",
    "(p_{i+1} - p_{i-1})/2 is the textbook's tangent for keys one second apart. Your keys are "
    "not evenly spaced: the tangent is a velocity, m_i = (p_{i+1} - p_{i-1})/(t_{i+1} - "
    "t_{i-1}), the difference divided by the time between the two neighbours{per_u}.")
TANGENT_PARAMS = ("p_prev", "p_next", "t_prev", "t_i", "t_next")
SPLINE_PARAMS = ("keys", "times", "t")

PIVOTS = {
    "origin_pivot": ("the sub-chain turned about the world origin",
               "A joint turns the sub-chain beyond it about the joint itself: "
               "p_k ← r_i + R(p_k - r_i) for k > i; p_k ← R p_k turns it about the origin, which "
               "moves joint i's children off their bones."),
    "effector_pivot": ("rotating about the end effector",
                 "A joint turns the sub-chain beyond it about the joint itself: with R the "
                 "shortest arc from e - r_i to t - r_i, p_k ← r_i + R(p_k - r_i) for k > i; "
                 "turning about e leaves the effector where it is and stretches bone i."),
    "wrong_joint": ("the turn measured at the wrong joint",
                   "Joint i's turn is the shortest arc R from e - r_i to t - r_i, both measured "
                   "from r_i, the joint that turns: p_k ← r_i + R(p_k - r_i) for k > i; your "
                   "turns match arcs measured from the next joint, e - r_{i+1} to "
                   "t - r_{i+1}."),
}


def shared_misconceptions(fn: Function) -> tuple[Misconception, ...]:
    """The convention mistakes that can show in ``fn``'s output or angle arguments."""
    found = []
    items = _rotation_items(fn.check)
    for index, name, check in items:
        whose = ("your result", "has", "is") if index is None else (
            f"your {name}", "have", "are")
        where = "" if len(items) == 1 else f"_{name}"
        kinds = ((("xyzw", XYZW, _xyzw), ("conjugate", CONJUGATE, _conjugate))
                 if isinstance(check, QuatCheck) else (("transposed", TRANSPOSED, _transposed),))
        for key, (title, text), change in kinds:
            found.append(Misconception(
                key + where, fn.name, title,
                text.format(your=whose[0], Your=whose[0].capitalize(), has=whose[1],
                            **{"is": whose[2]}),
                wrong=_changed_output(fn.reference, index, change)))
    found.extend(tangent_mistakes(fn))
    angles = [i for i, p in enumerate(fn.params) if p in ANGLE_PARAMS]
    if angles:
        found.append(Misconception("degrees", fn.name, *DEGREES,
                                   wrong=_radians_again(fn.reference, angles)))
    return tuple(found)


def tangent_mistakes(fn: Function) -> tuple[Misconception, ...]:
    """The uniform Catmull–Rom tangent, where ``fn`` computes a tangent or a spline."""
    title, text = UNIFORM_TANGENT
    if fn.params == TANGENT_PARAMS:
        return (Misconception("uniform_tangent", fn.name, title, text.replace("{per_u}", ""),
                              wrong=lambda a, b, t0, t1, t2: (np.asarray(b) - a) / 2),)
    if fn.params == SPLINE_PARAMS:
        return (Misconception(
            "uniform_tangent", fn.name, title,
            text.replace("{per_u}", ", and on segment i the Hermite form takes h_i m_i, "
                         "h_i m_{i+1} per unit u (h_i = t_{i+1} - t_i); the end keys take "
                         "(p_1 - p_0)/(t_1 - t_0) and (p_{K-1} - p_{K-2})/(t_{K-1} - t_{K-2})"),
            wrong=_uniform_spline),)
    return ()


def _uniform_spline(keys: np.ndarray, times: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Catmull–Rom with the tangents (p_{i+1} - p_{i-1})/2 per unit u (one-sided at the
    ends), as if every key were one second from the next."""
    keys, times, t = (np.asarray(a, dtype=float) for a in (keys, times, t))
    m = np.empty_like(keys)
    m[1:-1] = (keys[2:] - keys[:-2]) / 2
    m[0], m[-1] = keys[1] - keys[0], keys[-1] - keys[-2]
    i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2)
    u = ((t - times[i]) / (times[i + 1] - times[i]))[:, None]
    out: np.ndarray = ((2 * u**3 - 3 * u**2 + 1) * keys[i] + (u**3 - 2 * u**2 + u) * m[i]
                       + (-2 * u**3 + 3 * u**2) * keys[i + 1] + (u**3 - u**2) * m[i + 1])
    return out


def pivot_mistakes(function: str,
                   symptoms: dict[str, Callable[..., bool]]) -> tuple[Misconception, ...]:
    """The pivot family for a function whose steps turn sub-chains.

    ``symptoms`` maps a key of :data:`PIVOTS` to how this function shows it, a predicate
    ``(got, *args) -> bool`` (typically: ``got`` is the chain the function's loop gives when
    every turn is about that point).
    """
    unknown = set(symptoms) - set(PIVOTS)
    if unknown:
        raise ValueError(f"pivot_mistakes: unknown pivots {sorted(unknown)}; known: "
                         f"{', '.join(PIVOTS)}")
    return tuple(Misconception(key, function, *PIVOTS[key], symptom=shows)
                 for key, shows in symptoms.items())


def _rotation_items(check: Check) -> list[tuple[int | None, str, Check]]:
    """``(index in the output tuple or None, name, check)`` of each rotation the output holds."""
    if isinstance(check, (QuatCheck, MatrixCheck)):
        return [(None, "result", check)]
    if isinstance(check, TupleCheck):
        return [(i, name, c) for i, (c, name) in enumerate(zip(check.items, check.names,
                                                                strict=True))
                if isinstance(c, (QuatCheck, MatrixCheck))]
    return []


def _xyzw(q: np.ndarray) -> np.ndarray:
    return np.roll(q, -1, axis=-1)


def _conjugate(q: np.ndarray) -> np.ndarray:
    conj: np.ndarray = np.asarray(q) * np.array([1.0, -1.0, -1.0, -1.0])
    return conj


def _transposed(R: np.ndarray) -> np.ndarray:
    return np.swapaxes(R, -1, -2)


def _changed_output(reference: Callable[..., Any], index: int | None,
                    change: Callable[[np.ndarray], np.ndarray]) -> Callable[..., Any]:
    def wrong(*args: Any) -> Any:
        out = reference(*args)
        if index is None:
            return change(np.asarray(out, dtype=float))
        return tuple(change(np.asarray(o, dtype=float)) if i == index else o
                     for i, o in enumerate(out))
    return wrong


def _radians_again(reference: Callable[..., Any], which: list[int]) -> Callable[..., Any]:
    def wrong(*args: Any) -> Any:
        return reference(*(np.radians(a) if i in which else a for i, a in enumerate(args)))
    return wrong
