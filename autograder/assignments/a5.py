r"""Assignment a5, animation: the spec ``assignments/a5_animation.py`` is checked by.

Keyframes: ``catmull_rom`` and ``squad`` are compared with :mod:`course.keyframes` at many
times, the key times among them (where a spline must pick the right segment). The implicit
Euler step has one right answer, the minimiser of

.. math:: E(x) = \frac{1}{2h^2}\lVert x - y\rVert_M^2 + U(x),\qquad y = x_n + h v_n + h^2 g,

and is graded by what makes it right, computed here from the student's positions (never
trusted from the student): the fixed points held exactly, the gradient :math:`\nabla E` small
at the answer (it is 0 at the minimum), the velocity :math:`v^+ = (x^+ - x_n)/h`, and the
positions within a tolerance of :func:`course.physics.implicit_euler_step`'s. The cases are
small (at most 6×6 particles) so that a dense ``np.linalg.solve`` per Newton iteration passes
the time limit, and many have compressed springs, where the Hessian's
:math:`(1 - L/\lVert d\rVert)` term is negative and matters.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from itertools import islice
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from course import keyframes as kf
from course import rotations as rot
from course.physics import (
    SpringSystem,
    grid_cloth,
    implicit_euler_gradient,
    implicit_euler_objective,
)

from ..checks import PointsCheck, QuatCheck, TupleCheck, show
from ..spec import Assignment, Case, Function, Misconception, random_edge_hidden

GRAD_TOL = 1e-6  # the step's ‖∇E‖ may be this times the force scale (see force_scale)
FIXED_TOL = 1e-9  # metres a fixed particle may drift (rounding only)
VELOCITY_TOL = 1e-6  # relative: |v⁺ - (x⁺ - x)/h| against the velocities' scale
GRAVITY = np.array([0.0, -9.81, 0.0])


def time_row(times: np.ndarray, t: np.ndarray) -> Any:
    """Row ``i`` of a spline's answer, named by the time it is at: "time index 3 (t = 2.5 s,
    key 1's time)", never "time 3", which reads as t = 3 s."""
    def name(i: int) -> str:
        keys = np.flatnonzero(times == t[i])
        key = f", key {int(keys[0])}'s time" if keys.size else ""
        return f"time index {i} (t = {t[i]:g} s{key})"
    return name


class SplinePointsCheck(PointsCheck):
    """A spline's points, one row per time of ``t``, each row named by its time."""

    def judge(self, got: Any, expected: Any, args: tuple[Any, ...]) -> str | None:
        return self.compare(got, expected, time_row(args[1], args[2]))


class SplineQuatCheck(QuatCheck):
    """A rotation spline's quaternions, one row per time of ``t``, named by its time."""

    def judge(self, got: Any, expected: Any, args: tuple[Any, ...]) -> str | None:
        return self.compare(got, expected, time_row(args[1], args[2]))


#: how a SQUAD answer is compared, with the reference's and with a mistake's
SQUAD_CHECK = SplineQuatCheck(atol=1e-6, shape=None, row="time")


# --- Catmull-Rom -------------------------------------------------------------------------------


def hermite_segments(keys: np.ndarray, times: np.ndarray, t: np.ndarray, start: np.ndarray,
                     end: np.ndarray) -> np.ndarray:
    """The Hermite cubic of segment ``i`` (``t_i <= t < t_{i+1}``, the last key in the last
    segment) with end tangents ``start[i]``, ``end[i]`` per unit ``u = (t - t_i)/h_i``."""
    i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2)
    u = ((t - times[i]) / (times[i + 1] - times[i]))[:, None]
    hermite: np.ndarray = ((2 * u**3 - 3 * u**2 + 1) * keys[i] + (u**3 - 2 * u**2 + u) * start[i]
            + (-2 * u**3 + 3 * u**2) * keys[i + 1] + (u**3 - u**2) * end[i])
    return hermite


def _velocities(keys: np.ndarray, times: np.ndarray) -> np.ndarray:
    """m_i = (p_{i+1} - p_{i-1})/(t_{i+1} - t_{i-1}); one-sided at the ends."""
    m = np.empty_like(keys)
    m[1:-1] = (keys[2:] - keys[:-2]) / (times[2:] - times[:-2])[:, None]
    m[0] = (keys[1] - keys[0]) / (times[1] - times[0])
    m[-1] = (keys[-1] - keys[-2]) / (times[-1] - times[-2])
    return m


def catmull_rom_variants(keys: np.ndarray, times: np.ndarray, t: np.ndarray
                        ) -> dict[str, np.ndarray]:
    """Catmull-Rom with the tangents scaled by the wrong interval, as students write it."""
    h = np.diff(times)[:, None]
    m = _velocities(keys, times)
    unit = np.empty_like(keys)  # the textbook's (p_{i+1} - p_{i-1})/2 per unit u
    unit[1:-1] = (keys[2:] - keys[:-2]) / 2
    unit[0], unit[-1] = keys[1] - keys[0], keys[-1] - keys[-2]
    own = m.copy()  # divided by twice the key's own segment, 2 h_i, not t_{i+1} - t_{i-1}
    own[1:-1] = (keys[2:] - keys[:-2]) / (2 * h[1:])
    return {"uniform": hermite_segments(keys, times, t, unit[:-1], unit[1:]),
            "per unit u": hermite_segments(keys, times, t, m[:-1], m[1:]),
            "own segment": hermite_segments(keys, times, t, h * own[:-1], h * own[1:])}


def _wrong_interval(got: Any, keys: np.ndarray, times: np.ndarray, t: np.ndarray) -> bool:
    """One of the variants other than the uniform tangent (the shared catalogue's own)."""
    return any(np.allclose(got, w, atol=1e-6)
               for name, w in catmull_rom_variants(keys, times, t).items() if name != "uniform")


def _end_tangents(keys: np.ndarray, times: np.ndarray, t: np.ndarray, scale: float
                  ) -> np.ndarray:
    """Catmull-Rom with the end keys' tangents times ``scale``: 0 (clamped ends), or 1/2
    (the end key repeated as its own missing neighbour, p_{-1} = p_0 one segment earlier)."""
    h = np.diff(times)[:, None]
    m = _velocities(keys, times)
    m[0] *= scale
    m[-1] *= scale
    return hermite_segments(keys, times, t, h * m[:-1], h * m[1:])


def _wrong_at_keys(got: Any, keys: np.ndarray, times: np.ndarray, t: np.ndarray) -> bool:
    """Wrong (or NaN) only where t is a key time."""
    at_key = np.isin(t, times)
    right = np.all(np.isclose(got, kf.catmull_rom(keys, times, t), atol=1e-6), axis=1)
    return bool(np.all(right[~at_key]) and not np.all(right[at_key]))


def _index_past_the_end(error: dict[str, Any], keys: np.ndarray, times: np.ndarray, t: np.ndarray
                        ) -> str | None:
    if error.get("type") != "IndexError" or times[-1] not in t:
        return None
    n = len(times)
    return (f"t = {times[-1]:g} is the last key; np.searchsorted(times, t, side='right') - 1 "
            f"gives {n - 1}, a segment [t_{n - 1}, t_{n}] that does not exist: clip i to "
            f"K - 2 = {n - 2} (the last segment ends at the last key, u = 1)")


def _key_times(rng: np.random.Generator, n: int, lo: float = 0.3, hi: float = 2.0) -> np.ndarray:
    times: np.ndarray = rng.uniform(-1, 1) + np.cumsum(np.r_[0.0, rng.uniform(lo, hi, n - 1)])
    return times


def _times_with_keys(times: np.ndarray, n: int = 20) -> np.ndarray:
    """``n`` times across the keys, and every key time (where the segment index matters)."""
    return np.unique(np.r_[np.linspace(times[0], times[-1], n), times])


def _spline_case(rng: np.random.Generator, label: str, n_keys: int, dim: int) -> Case:
    times = _key_times(rng, n_keys)
    return Case(label, (rng.normal(0, 2, (n_keys, dim)), times, _times_with_keys(times)))


def catmull_random(rng: np.random.Generator) -> list[Case]:
    return [_spline_case(rng, f"{k} keys in {d}D, uneven times", k, d)
            for k, d in ((4, 2), (5, 3), (6, 2), (7, 3), (8, 1))]


def catmull_edges(rng: np.random.Generator) -> list[Case]:
    uneven = np.array([0.0, 0.1, 3.0, 3.2, 10.0])
    even = np.arange(6.0)
    return [
        Case("two keys: one segment, both tangents the secant", (rng.normal(size=(2, 3)),
                                                                 np.array([1.0, 2.5]),
                                                                 np.linspace(1, 2.5, 7))),
        Case("three keys", (rng.normal(size=(3, 2)), np.array([0.0, 0.5, 2.0]),
                            _times_with_keys(np.array([0.0, 0.5, 2.0])))),
        Case("very uneven times (0, 0.1, 3, 3.2, 10)", (rng.normal(size=(5, 2)), uneven,
                                                        _times_with_keys(uneven, 40))),
        Case("one key per second (h = 1: every scaling agrees)",
             (rng.normal(size=(6, 3)), even, _times_with_keys(even))),
        Case("the key times only", (rng.normal(size=(5, 3)), uneven, uneven.copy())),
        Case("times far from 0 (t = 100 ... 104)", (rng.normal(size=(4, 2)),
                                                    np.array([100.0, 101.0, 101.5, 104.0]),
                                                    np.linspace(100, 104, 17))),
    ]


def catmull_hidden(rng: np.random.Generator) -> list[Case]:
    return [_spline_case(rng, f"hidden spline #{i + 1}", int(rng.integers(3, 10)),
                         int(rng.integers(1, 4))) for i in range(8)]


# --- SQUAD -------------------------------------------------------------------------------------


def _log(q: np.ndarray) -> np.ndarray:
    """log q = atan2(|v|, w) v/|v| of unit quaternions (..., 4): the sign of q matters."""
    v = q[..., 1:]
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    log: np.ndarray = np.arctan2(n, q[..., :1]) * np.divide(v, n, out=np.zeros_like(v),
                                                            where=n > 1e-300)
    return log


def _exp(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.concatenate([np.cos(n), np.sinc(n / np.pi) * v], axis=-1)


def _towards(a: np.ndarray, b: np.ndarray, u: np.ndarray, shortest: bool) -> np.ndarray:
    """slerp(a, b, u) = a exp(u log(a⁻¹ b)), the shortest way (b ← -b if a·b < 0) or, with
    ``shortest=False``, the way the signs happen to point."""
    if shortest:
        b = b * np.where(np.sum(a * b, axis=-1, keepdims=True) < 0, -1.0, 1.0)
    return rot.quat_mul(a, _exp(u * _log(rot.quat_mul(rot.quat_conjugate(a), b))))


def squad_formula(q_keys: np.ndarray, times: np.ndarray, t: np.ndarray,
                  shortest: bool = True, controls: str = "time",
                  as_they_are: bool = False) -> np.ndarray:
    """Shoemake's SQUAD with the controls of :func:`course.keyframes.squad_controls`, written
    out; ``shortest=False`` skips putting the keys in one hemisphere first and every slerp
    goes the way the signs point. ``controls`` builds them as students get them wrong:
    ``"none"`` (s_i = q_i: plain SLERP between keys), ``"even"`` (Shoemake's
    -(log⁺ + log⁻)/4 on uneven times), ``"swapped"`` (the weights h_{i-1}, h_i swapped),
    ``"log_order"`` (log(q_{i±1} q_i⁻¹) for log(q_i⁻¹ q_{i±1})), ``"stored"`` (built from
    the keys as stored, before their hemisphere flip). ``as_they_are``: the inner slerp and
    the blend as the template says, a⁻¹b with the signs they have (the same as the shortest
    way on the graded cases, unless the controls are built from the keys as stored)."""
    stored = q_keys / np.linalg.norm(q_keys, axis=-1, keepdims=True)
    q = kf.same_hemisphere(stored) if shortest else stored
    c = stored if controls == "stored" else q  # the keys the controls are built from
    s = c.copy()
    if len(q) > 2 and controls != "none":
        inv = rot.quat_conjugate(c[1:-1])
        if controls == "log_order":
            after, before = (_log(rot.quat_mul(c[2:], inv)), _log(rot.quat_mul(c[:-2], inv)))
        else:
            after, before = (_log(rot.quat_mul(inv, c[2:])), _log(rot.quat_mul(inv, c[:-2])))
        h = np.diff(times)[:, None]
        w_after, w_before = h[:-1], h[1:]
        if controls == "swapped":
            w_after, w_before = w_before, w_after
        if controls == "even":
            w_after = w_before = np.ones_like(w_after)
        s[1:-1] = rot.quat_mul(c[1:-1], _exp(-(w_after * after + w_before * before)
                                             / (2 * (w_after + w_before))))
    i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2)
    u = ((t - times[i]) / (times[i + 1] - times[i]))[:, None]
    flip = shortest and not as_they_are
    return _towards(_towards(q[i], q[i + 1], u, shortest), _towards(s[i], s[i + 1], u, flip),
                    2 * u * (1 - u), flip)


def _controls_from_stored_keys(got: Any, q_keys: np.ndarray, times: np.ndarray, t: np.ndarray
                               ) -> bool:
    """SQUAD with its controls built from the keys as stored, before the hemisphere flip;
    the inner slerp and the blend the shortest way, or as they are (the template's)."""
    return any(SQUAD_CHECK.close(got, squad_formula(q_keys, times, t, controls="stored",
                                                    as_they_are=as_they_are))
               for as_they_are in (False, True))


def _rotation_keys(rng: np.random.Generator, times: np.ndarray, flips: bool, lo: float = 0.3,
                   hi: float = 1.8, wobble: float | None = None) -> np.ndarray:
    """A unit key per time, each turned lo..hi rad from the previous; with ``flips`` some are
    stored as -q (at least one), as keys from a file or an IK solver may be. Keys whose
    neighbouring controls s_i, s_{i+1} fall in opposite hemispheres are drawn again: there
    the sign conventions of the inner and outer slerps part, and either answer is fair.
    ``wobble``: the turns' axes within about that (radians) of one axis, so that big turns
    keep their controls together (drawn quickly, not by many rejections)."""
    n = len(times)
    while True:
        base = _direction(rng)

        def axis(base: np.ndarray = base) -> np.ndarray:
            if wobble is None:
                return _direction(rng)
            a = base + wobble * rng.normal(size=3)
            unit: np.ndarray = a / np.linalg.norm(a)
            return unit

        qs = [rot.quat_from_axis_angle(_direction(rng), rng.uniform(0, np.pi))]
        for _ in range(n - 1):
            qs.append(rot.quat_mul(qs[-1], rot.quat_from_axis_angle(axis(),
                                                                    rng.uniform(lo, hi))))
        q = np.array(qs)
        s = kf.squad_controls(q, times)
        if np.all(np.sum(s[1:] * s[:-1], axis=-1) > 0.1):
            break
    if flips:
        sign = np.where(rng.random(n) < 0.4, -1.0, 1.0)
        sign[int(rng.integers(1, n))] = -sign[0]
        q = q * sign[:, None]
    return q


def _direction(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    unit: np.ndarray = v / np.linalg.norm(v)
    return unit


def _squad_case(rng: np.random.Generator, label: str, n: int, flips: bool = True) -> Case:
    times = _key_times(rng, n)
    return Case(label, (_rotation_keys(rng, times, flips), times, _times_with_keys(times)))


def squad_random(rng: np.random.Generator) -> list[Case]:
    return [_squad_case(rng, f"{n} rotation keys, uneven times, some stored as -q", n)
            for n in (3, 4, 5, 6, 7)]


def squad_edges(rng: np.random.Generator) -> list[Case]:
    same = np.tile(rot.quat_from_axis_angle(_direction(rng), 1.0), (4, 1))
    uneven = np.array([0.0, 1.0, 1.5, 3.0])
    return [
        Case("two keys: SQUAD is SLERP", (_rotation_keys(rng, np.array([0.0, 1.5]), False),
                                          np.array([0.0, 1.5]), np.linspace(0, 1.5, 9))),
        _squad_case(rng, "keys already in one hemisphere", 5, flips=False),
        Case("every key the same rotation (one stored as -q)",
             (same * np.array([1, 1, -1, 1.0])[:, None], np.arange(4.0), np.linspace(0, 3, 13))),
        Case("turns of 2.1 rad (120°) between keys, one stored as -q",
             (_rotation_keys(rng, uneven, True, 2.0, 2.2, wobble=0.3), uneven,
              _times_with_keys(uneven))),
        Case("one key per second", (_rotation_keys(rng, np.arange(5.0), True), np.arange(5.0),
                                    _times_with_keys(np.arange(5.0)))),
    ]


def squad_hidden(rng: np.random.Generator) -> list[Case]:
    return [_squad_case(rng, f"hidden rotation keys #{i + 1}", int(rng.integers(3, 9)))
            for i in range(8)]


# --- the implicit Euler step -------------------------------------------------------------------


def step_reference(x: np.ndarray, v: np.ndarray, masses: np.ndarray, springs: np.ndarray,
                   rest: np.ndarray, k: np.ndarray, h: float, fixed: np.ndarray, gravity: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The minimiser of E, solved far below the grader's tolerance: :func:`dense_newton`
    (numpy only: loading scipy's sparse solver for :func:`course.physics.step` would cost
    the check 0.4 s; the tests compare the two)."""
    x_new, v_new = dense_newton(x, v, masses, springs, rest, k, h, fixed, gravity)
    v_new[fixed] = 0.0
    return x_new, v_new


def force_scale(x: np.ndarray, v: np.ndarray, masses: np.ndarray, springs: np.ndarray,
                rest: np.ndarray, k: np.ndarray, h: float, fixed: np.ndarray, gravity: np.ndarray
                ) -> float:
    """f: the free particles' weights ‖(m_i g)‖ plus the spring forces at the start ‖∇U(x)‖."""
    system = SpringSystem.create(masses, springs, rest, k, fixed, gravity)
    free = system.free
    return float(np.linalg.norm(masses[free]) * np.linalg.norm(gravity)
                 + np.linalg.norm(system.spring_gradient(x)[free]))


def spring_hessian(x: np.ndarray, springs: np.ndarray, rest: np.ndarray, k: np.ndarray,
                   missing_term: bool = False, projected: bool = False) -> np.ndarray:
    r"""∇²U, dense (3N, 3N): spring blocks :math:`H_s = k[(1 - L/l) I + (L/l)\hat d\hat d^T]`,
    or, with ``missing_term``, :math:`k\,\hat d\hat d^T` (the (1 - L/l) term dropped), or,
    ``projected``, with (1 - L/l) clamped at 0 (notebook 12's PSD projection)."""
    n = len(x)
    d = x[springs[:, 0]] - x[springs[:, 1]]
    length = np.linalg.norm(d, axis=1)
    dh = d / length[:, None]
    c = np.zeros_like(length) if missing_term else 1.0 - rest / length
    if projected:
        c = np.maximum(c, 0.0)
    blocks = k[:, None, None] * (c[:, None, None] * np.eye(3)
                                 + (1.0 - c)[:, None, None] * dh[:, :, None] * dh[:, None])
    H = np.zeros((n, n, 3, 3))
    i, j = springs[:, 0], springs[:, 1]
    np.add.at(H, (i, i), blocks)
    np.add.at(H, (j, j), blocks)
    np.add.at(H, (i, j), -blocks)
    np.add.at(H, (j, i), -blocks)
    dense: np.ndarray = H.transpose(0, 2, 1, 3).reshape(3 * n, 3 * n)
    return dense


def step_problems(got: Any, x: np.ndarray, v: np.ndarray, masses: np.ndarray,
                  springs: np.ndarray, rest: np.ndarray, k: np.ndarray, h: float,
                  fixed: np.ndarray, gravity: np.ndarray) -> list[str]:
    """What is wrong with ``(x⁺, v⁺)`` as the implicit step, worst first."""
    args = (x, v, masses, springs, rest, k, h, fixed, gravity)
    x_new, v_new = got
    out = []
    moved = np.linalg.norm(x_new[fixed] - x[fixed], axis=1) if len(fixed) else np.zeros(0)
    if np.any(moved > FIXED_TOL):
        i = int(fixed[np.argmax(moved)])
        out.append(f"fixed particle {i} moved by {moved.max():.3g} (from {show(x[i])} to "
                   f"{show(x_new[i])}); fixed points stay where they are")
    g = np.linalg.norm(implicit_euler_gradient(x_new, *args))
    f = force_scale(*args)
    if g > GRAD_TOL * f:
        out.append(f"‖∇E(x⁺)‖ = {g:.3g} at your x⁺, not ≈ 0 (at most {GRAD_TOL * f:.2g}): "
                   "x⁺ does not minimise E(x) = ‖x - y‖²_M/2h² + U(x)")
    v_want = (x_new - x) / h
    dv = float(np.max(np.abs(v_new - v_want)))
    if dv > VELOCITY_TOL * max(1.0, float(np.max(np.abs(v_want)))):
        out.append(f"v⁺ differs from (x⁺ - x)/h by up to {dv:.3g}; implicit Euler's "
                   "x⁺ = x + h v⁺ makes v⁺ = (x⁺ - x)/h")
    return out


class StepCheck(TupleCheck):
    """``(x⁺, v⁺)``, judged by the step's optimality, then against the reference."""

    def __init__(self) -> None:
        super().__init__((PointsCheck(atol=1e-6, row="particle"),
                          PointsCheck(atol=1e-4, row="particle")), ("x", "v"))

    def judge(self, got: Any, expected: Any, args: tuple[Any, ...]) -> str | None:
        problems = step_problems(got, *args)
        if problems:
            return problems[0]
        why = self.items[0].compare(got[0], expected[0])
        if why is None:
            return None
        # Another x⁺ with ∇E ≈ 0 is a right answer too if E is no higher there: for convex E,
        # E(x⁺) - E(x*) <= ‖∇E(x⁺)‖ ‖x⁺ - x*‖ (and a stationary point higher than the
        # reference's minimiser is a different, worse minimum, or a saddle).
        e_got, e_ref = (implicit_euler_objective(z, *args) for z in (got[0], expected[0]))
        slack = (np.linalg.norm(implicit_euler_gradient(got[0], *args))
                 * np.linalg.norm(got[0] - expected[0]) + 1e-12 * abs(e_ref))
        if e_got <= e_ref + slack:
            return None
        return (f"x {why}: your x⁺ is a stationary point of E but not its minimum, "
                f"E(x⁺) = {e_got:.10g} > {e_ref:.10g} at the reference's minimiser")

    def show_expected(self, expected: Any, digits: int = 3) -> str:
        return f"the minimiser of E, x⁺ = {show(expected[0], digits)}"


def _free_hessian(x_new: np.ndarray, masses: np.ndarray, springs: np.ndarray, rest: np.ndarray,
                  k: np.ndarray, h: float, fixed: np.ndarray,
                  missing_term: bool = False, projected: bool = False
                  ) -> tuple[np.ndarray, np.ndarray]:
    """∇²E = M/h² + ∇²U over the free coordinates, and the mask of those (3N,)."""
    free = np.ones(len(x_new), dtype=bool)
    free[fixed] = False
    dof = np.repeat(free, 3)
    H = spring_hessian(x_new, springs, rest, k, missing_term, projected) + np.diag(
        np.repeat(masses, 3) / h**2)
    return H[np.ix_(dof, dof)], dof


def dense_newton(x: np.ndarray, v: np.ndarray, masses: np.ndarray, springs: np.ndarray,
                 rest: np.ndarray, k: np.ndarray, h: float, fixed: np.ndarray, gravity: np.ndarray,
                 max_iter: int = 100) -> tuple[np.ndarray, np.ndarray]:
    """Newton's method on E(x) = ‖x - y‖²_M/2h² + U(x), fixed points eliminated, dense, with
    a backtracking line search: the step as a student writes it, independent of
    :mod:`course.physics`'s sparse solver (the tests compare the two)."""
    *_, xk = line_search_iterates((x, v, masses, springs, rest, k, h, fixed, gravity), max_iter)
    return xk, (xk - x) / h


def line_search_iterates(args: Sequence[Any], max_iter: int = 100, frozen: bool = False
                         ) -> Iterator[np.ndarray]:
    """The positions :func:`dense_newton` goes through: z = y (the fixed points held) first,
    then after each of at most ``max_iter`` iterations, until ‖∇E‖ is below the threshold;
    ``frozen``: with the Hessian of the start z = y kept throughout (built once, before the
    loop)."""
    x, v, masses, springs, rest, k, h, fixed, gravity = args
    system = SpringSystem.create(masses, springs, rest, k, fixed, gravity)
    y = x + h * v + h * h * gravity
    xk = y.copy()
    xk[fixed] = x[fixed]
    yield xk

    def energy(z: np.ndarray) -> float:
        return float(0.5 * np.sum(masses[:, None] * (z - y) ** 2) / h**2
                     + system.spring_energy(z))

    free = system.free
    g0 = (masses[:, None] * (xk - y) / h**2 + system.spring_gradient(xk))[free]
    size = max(float(np.abs(x).max(initial=0.0)), float(np.abs(y).max(initial=0.0)))
    mass = float(np.linalg.norm(masses[free]))
    # as course.physics.step with tol = 1e-11: relative to the force scale, never below
    # what rounding lets ‖∇E‖ reach (else the last iterations chase noise to max_iter)
    threshold = max(1e-11 * max(mass * float(np.linalg.norm(gravity)),
                                float(np.linalg.norm(g0))),
                    100 * np.finfo(float).eps * size * (mass / h**2
                                                        + float(np.linalg.norm(k))))
    H, dof = _free_hessian(xk, masses, springs, rest, k, h, fixed)
    for i in range(max_iter):
        if i and not frozen:
            H, dof = _free_hessian(xk, masses, springs, rest, k, h, fixed)
        g = (masses[:, None] * (xk - y) / h**2 + system.spring_gradient(xk)).ravel()[dof]
        if np.linalg.norm(g) <= threshold:
            break
        p = np.linalg.solve(H, -g)
        if g @ p >= 0:
            p = -g
        flat = np.zeros(3 * len(x))
        flat[dof] = p
        move = flat.reshape(-1, 3)
        alpha, e0 = 1.0, energy(xk)
        while energy(xk + alpha * move) > e0 + 1e-4 * alpha * (g @ p) + 1e-14 * abs(e0) \
                and alpha > 1e-12:
            alpha /= 2
        xk = xk + alpha * move
        yield xk


def _explicit(x: np.ndarray, v: np.ndarray, masses: np.ndarray, springs: np.ndarray,
              rest: np.ndarray, k: np.ndarray, h: float, fixed: np.ndarray, gravity: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """x⁺ = x + h v, v⁺ = v + h M⁻¹ f(x): the explicit step, fixed points held."""
    system = SpringSystem.create(masses, springs, rest, k, fixed, gravity)
    v_new = v + h * system.forces(x) / masses[:, None]
    x_new = x + h * v
    x_new[fixed], v_new[fixed] = x[fixed], 0.0
    return x_new, v_new


def _pushing_springs(got: Any, x: np.ndarray, v: np.ndarray, masses: np.ndarray,
                     springs: np.ndarray, rest: np.ndarray, k: np.ndarray, h: float,
                     fixed: np.ndarray, gravity: np.ndarray) -> bool:
    """The springs push: x⁺ moved from y along +∇U(x⁺), not -∇U(x⁺) (at the right answer
    M(x⁺ - y)/h² = -∇U(x⁺); with the force flipped, Newton's fixed point has +∇U, and where
    it does not converge the steps still go uphill in U)."""
    system = SpringSystem.create(masses, springs, rest, k, fixed, gravity)
    x_new = got[0]
    if _fixed_moved(got, x, v, masses, springs, rest, k, h, fixed, gravity):
        return False
    inertial = (masses[:, None] * (x_new - x - h * v - h * h * gravity) / h**2)[system.free]
    grad = system.spring_gradient(x_new)[system.free]
    scale = np.linalg.norm(inertial) * np.linalg.norm(grad)
    return bool(np.isfinite(scale) and scale > 0 and np.sum(inertial * grad) > 0.2 * scale)


def _flipped_newton_unsettled(x: np.ndarray, v: np.ndarray, masses: np.ndarray,
                              springs: np.ndarray, rest: np.ndarray, k: np.ndarray, h: float,
                              fixed: np.ndarray, gravity: np.ndarray) -> bool:
    """Newton's method on the flipped equation M(z - y)/h² - ∇U(z) = 0 (full steps from y,
    its Jacobian M/h² - ∇²U) does not settle within 100 iterations: with the force's sign
    flipped this step has no definite answer (on the h = 1 s cloth every iterate is chaos
    that rounding decides), so a wrong output there neither shows nor refutes the flip."""
    system = SpringSystem.create(masses, springs, rest, k, fixed, gravity)
    free = system.free
    dof = np.repeat(free, 3)
    y = x + h * v + h * h * gravity
    z = y.copy()
    z[fixed] = x[fixed]
    threshold = GRAD_TOL * force_scale(x, v, masses, springs, rest, k, h, fixed, gravity)
    inertia = np.diag(np.repeat(masses, 3) / h**2)
    for _ in range(100):
        g = (masses[:, None] * (z - y) / h**2 - system.spring_gradient(z)).ravel()[dof]
        if not np.all(np.isfinite(g)):
            return True
        if np.linalg.norm(g) <= threshold:
            return False
        H = (inertia - spring_hessian(z, springs, rest, k))[np.ix_(dof, dof)]
        flat = np.zeros(3 * len(x))
        flat[dof] = np.linalg.lstsq(H, -g, rcond=None)[0]
        z = z + flat.reshape(-1, 3)
    return True


def _fixed_moved(got: Any, x: np.ndarray, v: np.ndarray, masses: np.ndarray,
                 springs: np.ndarray, rest: np.ndarray, k: np.ndarray, h: float,
                 fixed: np.ndarray, gravity: np.ndarray) -> bool:
    return bool(len(fixed)) and bool(np.max(np.abs(got[0][fixed] - x[fixed])) > FIXED_TOL)


def _stalled_without_the_term(got: Any, *args: Any) -> bool:  # args: a StepArgs
    """The answer is not optimal where a Newton iteration whose Hessian lacks the
    (1 - L/l) term stalls: from it, the true Newton step lands on the minimiser while the
    step with k d̂d̂ᵀ blocks is far shorter (it creeps along the modes that compressed springs
    soften) or far longer (it overshoots across stretched ones, and the line search cuts it),
    or the answer is still where compressed springs make ∇²E indefinite."""
    return _stalled(got, args, "missing_term")


def _stalled(got: Any, args: Any, how: str) -> bool:
    x, v, masses, springs, rest, k, h, fixed, gravity = args
    x_new = got[0]
    if _fixed_moved(got, *args) or not step_problems(got, *args):
        return False
    g = implicit_euler_gradient(x_new, *args)
    H, dof = _free_hessian(x_new, masses, springs, rest, k, h, fixed)
    H_wrong, _ = _free_hessian(x_new, masses, springs, rest, k, h, fixed, **{how: True})
    g = g.ravel()[dof]
    if np.linalg.eigvalsh(H)[0] <= 0:
        # stopped where compressed springs make E non-convex (its true Hessian indefinite,
        # k d̂d̂ᵀ blind to it); the template's Newton leaves such places within 12 iterations
        length = np.linalg.norm(x_new[springs[:, 0]] - x_new[springs[:, 1]], axis=1)
        return bool(np.any(length < rest))
    true_step, wrong_step = np.linalg.solve(H, -g), np.linalg.solve(H_wrong, -g)
    error = (step_reference(*args)[0] - x_new).ravel()[dof]
    ratio = np.linalg.norm(wrong_step) / np.linalg.norm(true_step)
    return bool(np.linalg.norm(true_step - error) <= 0.5 * np.linalg.norm(error)
                and not 0.5 <= ratio <= 1.5)


def _symplectic(x: np.ndarray, v: np.ndarray, masses: np.ndarray, springs: np.ndarray,
                rest: np.ndarray, k: np.ndarray, h: float, fixed: np.ndarray, gravity: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """v⁺ = v + h M⁻¹ f(x), x⁺ = x + h v⁺: symplectic Euler, fixed points held."""
    system = SpringSystem.create(masses, springs, rest, k, fixed, gravity)
    v_new = v + h * system.forces(x) / masses[:, None]
    v_new[fixed] = 0.0
    x_new = x + h * v_new
    x_new[fixed] = x[fixed]
    return x_new, v_new


def _no_gravity(x: np.ndarray, v: np.ndarray, masses: np.ndarray, springs: np.ndarray,
                rest: np.ndarray, k: np.ndarray, h: float, fixed: np.ndarray, gravity: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """The right step of a world without gravity: y = x + h v, the h² g left out."""
    return step_reference(x, v, masses, springs, rest, k, h, fixed, np.zeros(3))


def _solved_then_reset(x: np.ndarray, v: np.ndarray, masses: np.ndarray, springs: np.ndarray,
                       rest: np.ndarray, k: np.ndarray, h: float, fixed: np.ndarray,
                       gravity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every particle solved for (the fixed ones fall with the rest), then the fixed ones put
    back: the free particles hang from pins that were not there during the solve."""
    if not len(fixed):
        return step_reference(x, v, masses, springs, rest, k, h, fixed, gravity)
    x_new, _ = step_reference(x, v, masses, springs, rest, k, h, np.zeros(0, np.int64), gravity)
    x_new[fixed] = x[fixed]
    return x_new, (x_new - x) / h


def newton_iterates(args: Sequence[Any], iterations: int, frozen: bool = False,
                    hessian: str = "true") -> list[np.ndarray]:
    """The positions after each of ``iterations`` full Newton steps from y (no line search),
    fixed points eliminated; ``frozen``: with the Hessian of the start z = y throughout;
    ``hessian="projected"``: compressed springs' blocks clamped to PSD (notebook 12)."""
    x, v, masses, springs, rest, k, h, fixed, gravity = args
    system = SpringSystem.create(masses, springs, rest, k, fixed, gravity)
    y = x + h * v + h * h * gravity
    z = y.copy()
    z[fixed] = x[fixed]
    out, solve = [], None
    for _ in range(iterations):
        if not np.all(np.isfinite(z)):
            break
        g = (masses[:, None] * (z - y) / h**2 + system.spring_gradient(z)).ravel()
        if solve is None or not frozen:
            H, dof = _free_hessian(z, masses, springs, rest, k, h, fixed,
                                   projected=hessian == "projected")
            solve = np.linalg.inv(H)
        flat = np.zeros(3 * len(x))
        flat[dof] = -solve @ g[dof]
        z = z + flat.reshape(-1, 3)
        out.append(z.copy())
    return out


def _one_newton_step(*args: Any) -> tuple[np.ndarray, np.ndarray]:
    x_new = newton_iterates(args, 1)[-1]
    return x_new, (x_new - args[0]) / args[6]


def _newton_start(*args: Any) -> tuple[np.ndarray, np.ndarray]:
    """x⁺ = y, where Newton's method starts (the fixed points held): the loop's result
    thrown away."""
    z = next(line_search_iterates(args))
    return z, (z - args[0]) / args[6]


def _an_iterate(got: Any, args: Sequence[Any], iterates: Callable[[], Iterable[np.ndarray]],
                tolerance: Callable[[np.ndarray], float]) -> bool:
    """Not optimal, the fixed points held, and within ``tolerance(z)`` of one of the
    ``iterates`` z of a mistaken Newton."""
    if _fixed_moved(got, *args) or not step_problems(got, *args):
        return False
    x_new = got[0]
    with np.errstate(all="ignore"):
        return any(np.max(np.abs(x_new - z)) <= tolerance(z) for z in iterates())


def _frozen_hessian(got: Any, *args: Any) -> bool:
    """One of the first 100 iterates of Newton's method (full steps) with the Hessian of the
    start z = y kept throughout (built once, before the loop), to 1e-6 of its size (where
    the iteration diverges, rounding grows with it)."""
    return _an_iterate(got, args, lambda: newton_iterates(args, 100, frozen=True)[1:],
                       lambda z: 1e-6 * max(1.0, float(np.max(np.abs(z)))))


def _frozen_hessian_line_search(got: Any, *args: Any) -> bool:
    """One of the iterates 2 to 100 of the template's Newton (its line search and descent
    test; the first is one Newton step) with the Hessian of the start z = y kept throughout,
    to a thousandth of the iterate's distance from the minimiser: a slow iteration passes
    near any answer that is nearly right, and where it wanders (the line search's case)
    rounding parts two implementations by some 1e-5 of that distance after 50 iterations."""
    best = step_reference(*args)[0]
    return _an_iterate(got, args,
                       lambda: islice(line_search_iterates(args, 100, frozen=True), 2, None),
                       lambda z: 1e-3 * float(np.max(np.abs(z - best))))


def _needs_line_search(got: Any, *args: Any) -> bool:
    """Not optimal, on a case where full Newton steps from y do not settle within 50
    iterations (the line search's case), with the fixed points held and v⁺ = (x⁺ - x)/h."""
    problems = step_problems(got, *args)
    if _fixed_moved(got, *args) or not problems or not problems[0].startswith("‖∇E"):
        return False
    with np.errstate(all="ignore"):
        z = newton_iterates(args, 50)[-1]
        g = np.linalg.norm(implicit_euler_gradient(z, *args))
    return not bool(g <= GRAD_TOL * force_scale(*args))


# A time step's arguments: x, v, masses, springs, rest, k, h, fixed, gravity.
StepArgs = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, float,
                 np.ndarray, np.ndarray]


def _args(x: ArrayLike, v: ArrayLike, masses: ArrayLike,
          springs: np.ndarray | Sequence[Sequence[int]], rest: ArrayLike, k: ArrayLike, h: float,
          fixed: ArrayLike) -> StepArgs:
    return (np.asarray(x, float), np.asarray(v, float), np.asarray(masses, float),
            np.asarray(springs, np.int64), np.asarray(rest, float),
            np.broadcast_to(np.asarray(k, float), (len(springs),)).copy(), float(h),
            np.asarray(fixed, np.int64), GRAVITY.copy())


def _cloth(rng: np.random.Generator, rows: int, cols: int, *, squeeze: float = 1.0,
           stiffness: float = 200.0,
           h: float = 1 / 60, pinned: str = "top corners", speed: float = 0.3) -> StepArgs:
    """A small hanging cloth, its positions scaled by ``squeeze`` about its top edge's middle
    (< 1: every spring compressed), nudged by 1 mm and moving at random velocities."""
    cloth = grid_cloth(rows, cols, size=0.5, mass=0.1 * rows * cols, stiffness=stiffness,
                       plane="xy", pinned=pinned)
    s = cloth.system
    x = cloth.positions * squeeze + rng.normal(0, 1e-3, cloth.positions.shape)
    x[s.fixed] = cloth.positions[s.fixed] * squeeze
    v = rng.normal(0, speed, x.shape)
    v[s.fixed] = 0.0
    return _args(x, v, s.masses, s.springs, s.rest, s.k, h, s.fixed)


def well_posed(args: StepArgs) -> bool:
    """E is convex at the reference's answer (one minimiser to agree on), and the template's
    plain Newton (:func:`dense_newton`) reaches it, far below the grader's tolerance, within
    12 iterations (a quarter of the 50 the template's solver may take, as in a3)."""
    x_ref, _ = step_reference(*args)
    H, _ = _free_hessian(x_ref, *args[2:8])
    if np.linalg.eigvalsh(H)[0] <= 0:
        return False
    with np.errstate(all="ignore"):
        x_new, _ = dense_newton(*args, max_iter=12)
    g = np.linalg.norm(implicit_euler_gradient(x_new, *args))
    return bool(g <= 1e-3 * GRAD_TOL * force_scale(*args)
                and np.max(np.abs(x_new - x_ref)) <= 1e-8)


def _cloth_cases(rng: np.random.Generator, label: str, count: int, squeeze: tuple[float, float],
                 stiffness: tuple[float, float]) -> list[Case]:
    out: list[Case] = []
    while len(out) < count:
        rows, cols = (int(n) for n in rng.integers(2, 7, 2))
        sq = float(rng.uniform(*squeeze))
        args = _cloth(rng, rows, cols, squeeze=sq, stiffness=float(rng.uniform(*stiffness)),
                      h=float(rng.choice([1 / 30, 1 / 60, 1 / 100])))
        if well_posed(args):
            how = "at rest length" if sq == 1 else f"squeezed to {sq:.0%}"
            out.append(Case(f"{label} #{len(out) + 1}: a {rows}×{cols} cloth {how}", args))
    return out


def step_random(rng: np.random.Generator) -> list[Case]:
    return (_cloth_cases(rng, "hanging cloth", 3, (1.0, 1.0), (50, 500))
            + _cloth_cases(rng, "compressed cloth", 4, (0.75, 0.85), (150, 300)))


def step_edges(rng: np.random.Generator) -> list[Case]:
    one = _args([[0.0, 0.0, 0.0], [0.0, -2.0, 0.0]], np.zeros((2, 3)), [1.0, 1.0], [[0, 1]],
                [1.0], 50.0, 1 / 30, [0])
    chain = _args(np.c_[np.arange(5.0), np.zeros(5), np.zeros(5)], rng.normal(0, 1, (5, 3)),
                  np.full(5, 0.2), np.c_[np.arange(4), np.arange(1, 5)], np.full(4, 1.0), 80.0,
                  1 / 60, [])
    squeezed = np.c_[np.arange(6.0) * 0.7, np.zeros(6), np.zeros(6)]
    buckle = _args(squeezed, rng.normal(0, 0.2, (6, 3)), np.full(6, 0.1),
                   np.c_[np.arange(5), np.arange(1, 6)], np.full(5, 1.0), 100.0, 1 / 50, [0, 5])
    return [
        Case("one spring, one end pinned, stretched to twice its rest length", one),
        Case("a chain of 5 flying free (no fixed points)", chain),
        Case("a chain squeezed to 70% between two pins (every spring compressed)", buckle),
        Case("a big time step h = 0.05 (explicit Euler would blow up here)",
             _cloth(rng, 4, 4, stiffness=300.0, h=0.05)),
        Case("all four corners pinned", _cloth(rng, 4, 4, pinned="all corners")),
        Case("a 6×6 cloth squeezed to 80%", _cloth(rng, 6, 6, squeeze=0.8, stiffness=250.0)),
        Case(LINE_SEARCH_CASE, flat_cloth_big_step()),
    ]


LINE_SEARCH_CASE = ("a flat 6×6 cloth let go with h = 1 s (where does it hang? Newton needs "
                    "its line search)")


def flat_cloth_big_step() -> StepArgs:
    """Notebook 12's "what the line search buys": a flat cloth, at rest, pinned at two
    corners, one step of h = 1 s (nearly the static problem). From y, 9.81 m below, the full
    Newton steps overshoot and never settle; halving α gets there in about 20 iterations."""
    cloth = grid_cloth(6, 6, size=0.5, mass=3.6, stiffness=200.0, plane="xz")
    s = cloth.system
    return _args(cloth.positions, np.zeros_like(cloth.positions), s.masses, s.springs, s.rest,
                 s.k, 1.0, s.fixed)


def step_hidden(rng: np.random.Generator) -> list[Case]:
    return (_cloth_cases(rng, "hidden cloth", 3, (1.0, 1.0), (50, 1000))
            + _cloth_cases(rng, "hidden compressed cloth", 3, (0.75, 0.9), (100, 300)))


# --- the catalogue of known mistakes -----------------------------------------------------------

MISCONCEPTIONS = (
    Misconception(
        "wrong_interval", "catmull_rom", "tangents scaled by the wrong time interval",
        "m_i = (p_{i+1} - p_{i-1})/(t_{i+1} - t_{i-1}) is a velocity dp/dt, divided by the time "
        "between the two neighbours; on the segment [t_i, t_{i+1}] the Hermite form takes it "
        "per unit u as h_i m_i, h_i m_{i+1} (h_i = t_{i+1} - t_i).",
        symptom=_wrong_interval),
    Misconception(
        "zero_end_tangents", "catmull_rom", "zero tangents at the first and last keys",
        "Your curve stops dead at the end keys (m_0 = m_{K-1} = 0). The end keys have one "
        "neighbour each, and take the one-sided slope: m_0 = (p_1 - p_0)/(t_1 - t_0), "
        "m_{K-1} = (p_{K-1} - p_{K-2})/(t_{K-1} - t_{K-2}).",
        wrong=lambda keys, times, t: _end_tangents(keys, times, t, 0.0)),
    Misconception(
        "halved_end_tangents", "catmull_rom", "the end tangents halved (the end key repeated)",
        "At the first and last keys your tangent is half the one-sided slope, as when the end "
        "key stands in for its missing neighbour in the central difference: "
        "(p_1 - p_0)/(t_1 - t_{-1}) with t_{-1} = t_0 - h_0. The end keys take the one-sided "
        "slope itself: m_0 = (p_1 - p_0)/(t_1 - t_0), m_{K-1} = (p_{K-1} - p_{K-2})/"
        "(t_{K-1} - t_{K-2}).",
        wrong=lambda keys, times, t: _end_tangents(keys, times, t, 0.5)),
    Misconception(
        "segment_at_key", "catmull_rom", "the wrong segment at a key",
        "The segment of t is the i with t_i <= t < t_{i+1}, i = searchsorted(times, t, "
        "side='right') - 1, clipped to 0 ... K - 2 so that the last key t_{K-1} is the end "
        "(u = 1) of the last segment; your values go wrong exactly at key times.",
        symptom=_wrong_at_keys, explains=_index_past_the_end),
    Misconception(
        "no_shortest_path", "squad", "no shortest path (keys not put in one hemisphere)",
        "q and -q are the same rotation, but log(q_i⁻¹ q_{i+1}) of keys with q_i·q_{i+1} < 0 "
        "is the long way round (more than 180°); flip every key into its predecessor's "
        "hemisphere first, q_i ← -q_i when q_i·q_{i-1} < 0, then build the controls and slerp.",
        wrong=lambda q, times, t: squad_formula(q, times, t, shortest=False)),
    Misconception(
        "controls_from_stored_keys", "squad",
        "the inner controls built from the keys as stored (before the hemisphere flip)",
        "Your slerps between the keys go the short way, but your controls s_i were built from "
        "the keys as they came, some stored as -q: log(q_i⁻¹ q_{i+1}) of two keys with "
        "q_i·q_{i+1} < 0 is the long way round (more than 180°), so s_i pulls the curve the "
        "wrong way. Put the keys in one hemisphere FIRST (q_i ← -q_i when q_i·q_{i-1} < 0), "
        "then build s_i = q_i exp(-(h_{i-1} log(q_i⁻¹q_{i+1}) + h_i log(q_i⁻¹q_{i-1}))/"
        "(2(h_{i-1} + h_i))) from the flipped keys.",
        symptom=_controls_from_stored_keys),
    Misconception(
        "plain_slerp", "squad", "plain SLERP between the keys (no inner control points)",
        "Your curve is slerp(q_i, q_{i+1}, u) on each segment: it turns at a constant rate "
        "and then jerks at every key. SQUAD blends it towards slerp(s_i, s_{i+1}, u) by "
        "2u(1 - u), with the inner controls s_i = q_i exp(-(h_{i-1} log(q_i⁻¹q_{i+1}) + h_i "
        "log(q_i⁻¹q_{i-1}))/(2(h_{i-1} + h_i))) (s_0 = q_0, s_{K-1} = q_{K-1}).",
        wrong=lambda q, times, t: squad_formula(q, times, t, controls="none")),
    Misconception(
        "control_log_order", "squad", "the inner control's log taken in the wrong order",
        "Your controls use log(q_{i+1} q_i⁻¹) and log(q_{i-1} q_i⁻¹): the turns to the "
        "neighbours in the WORLD frame. s_i = q_i exp(...) multiplies on the right, so the "
        "turns must be in q_i's own frame: log(q_i⁻¹ q_{i+1}) and log(q_i⁻¹ q_{i-1}) "
        "(quaternion products do not commute).",
        wrong=lambda q, times, t: squad_formula(q, times, t, controls="log_order")),
    Misconception(
        "control_weights_swapped", "squad", "the weights h_{i-1}, h_i of the controls swapped",
        "Each log is weighted by the OTHER segment's length: h_{i-1} log(q_i⁻¹q_{i+1}) + h_i "
        "log(q_i⁻¹q_{i-1}), over 2(h_{i-1} + h_i). Yours weights log(q_i⁻¹q_{i+1}) by h_i "
        "(the segment it spans), which only agrees when h_{i-1} = h_i.",
        wrong=lambda q, times, t: squad_formula(q, times, t, controls="swapped")),
    Misconception(
        "even_controls", "squad", "Shoemake's controls for evenly spaced keys on uneven times",
        "s_i = q_i exp(-(log(q_i⁻¹q_{i+1}) + log(q_i⁻¹q_{i-1}))/4) assumes one key per "
        "second (h_{i-1} = h_i). Your keys are unevenly spaced: weight each log by the other "
        "segment's length, s_i = q_i exp(-(h_{i-1} log(q_i⁻¹q_{i+1}) + h_i log(q_i⁻¹q_{i-1}))"
        "/(2(h_{i-1} + h_i))).",
        wrong=lambda q, times, t: squad_formula(q, times, t, controls="even")),
    Misconception(
        "explicit", "implicit_euler_step", "an explicit step called implicit",
        "Implicit Euler takes the force at the END of the step, v⁺ = v + h M⁻¹ f(x⁺), "
        "x⁺ = x + h v⁺: solve ∇E(x⁺) = M(x⁺ - y)/h² + ∇U(x⁺) = 0 by Newton; x⁺ = x + h v, "
        "v⁺ = v + h M⁻¹ f(x) uses the force at the start (explicit Euler, unstable for stiff "
        "springs).",
        wrong=_explicit),
    Misconception(
        "symplectic", "implicit_euler_step", "a symplectic Euler step called implicit",
        "Yours is symplectic Euler, v⁺ = v + h M⁻¹ f(x), x⁺ = x + h v⁺: the force at the "
        "START of the step. Implicit Euler takes it at the END, v⁺ = v + h M⁻¹ f(x⁺): solve "
        "∇E(x⁺) = M(x⁺ - y)/h² + ∇U(x⁺) = 0 by Newton's method, starting at z = y.",
        wrong=_symplectic),
    Misconception(
        "gravity_missing", "implicit_euler_step", "gravity left out of y",
        "Your x⁺ is the right step of a world without gravity: y = x + h v + h² g (the "
        "inertial position includes the fall under gravity, h² g); you used y = x + h v.",
        wrong=_no_gravity),
    Misconception(
        "fixed_solved_then_reset", "implicit_euler_step",
        "fixed particles solved for, then put back",
        "You solved for every particle, the fixed ones too (they fell with the cloth), and put "
        "the fixed ones back afterwards: the others were solved hanging from pins that were not "
        "there. Drop the fixed particles' rows and columns from ∇E and ∇²E BEFORE solving, and "
        "keep them at x_i during the whole Newton loop (start z = y, then z_i = x_i for them).",
        wrong=_solved_then_reset),
    Misconception(
        "one_newton_step", "implicit_euler_step", "a single Newton step",
        "Your x⁺ is one Newton step from y, z = y - (∇²E)⁻¹∇E(y): E is not quadratic (the "
        "springs' energy is not), so one step does not reach its minimum. Repeat the Newton "
        "step (with the line search) until ‖∇E‖ is below the stopping threshold, at most 50 "
        "times.",
        wrong=_one_newton_step),
    Misconception(
        "result_thrown_away", "implicit_euler_step",
        "the Newton loop's result thrown away (x⁺ = y, where Newton starts)",
        "Your x⁺ is y = x + h v + h² g, the point Newton's method starts from (the fixed "
        "particles held): your iterations ran, but what they computed never reached the value "
        "you return. E.g. x_new = z before the loop, then z = z + αΔz makes a NEW array and "
        "x_new still holds y; or the loop updates a copy that is then dropped. Return the z "
        "of the last iteration, and v⁺ = (x⁺ - x)/h from it.",
        wrong=_newton_start),
    Misconception(
        "frozen_hessian", "implicit_euler_step",
        "the Hessian built once, at the start, with a fixed number of iterations",
        "Your x⁺ is what Newton's method gives when ∇²E is built once, at z = y, before the "
        "loop, and the loop runs a fixed number of times: ∇²E changes with z (each spring's "
        "block depends on d = z_i - z_j), so rebuild it at every iteration, and stop on the "
        "test ‖∇E‖ <= threshold (at most 50 iterations), not after a fixed count.",
        symptom=_frozen_hessian),
    Misconception(
        "frozen_hessian_line_search", "implicit_euler_step",
        "the Hessian built once, at the start of the step (z = y), and reused",
        "Your Newton loop is the template's (line search, stopping test, at most 50 "
        "iterations), but its ∇²E is the one at z = y, built before the loop: each spring's "
        "block H_s = k_s[(1 - L_s/‖d_s‖) I + (L_s/‖d_s‖) d̂_s d̂_sᵀ] depends on d_s = z_i - z_j, "
        "so once z moves, ∇²E Δz = -∇E with the old ∇²E is no longer Newton's step: the "
        "iteration converges only linearly (or not at all), and 50 iterations do not reach "
        "the minimum. Rebuild ∇²E at the current z in every iteration, as ∇E.",
        symptom=_frozen_hessian_line_search),
    Misconception(
        "force_sign", "implicit_euler_step", "the spring force with the wrong sign",
        "∂U/∂x_i = k (1 - L/‖d‖) d with d = x_i - x_j (and the opposite for x_j); the force "
        "is its negative, pulling a stretched spring's ends together. At the right x⁺, "
        "M(x⁺ - y)/h² = -∇U(x⁺); yours moved along +∇U(x⁺), as when the sign is flipped "
        "(Newton then solves M(x - y)/h² - ∇U(x) = 0, or runs uphill in U).",
        symptom=_pushing_springs, undefined=_flipped_newton_unsettled),
    Misconception(
        "fixed_moved", "implicit_euler_step", "fixed points moved",
        "Fixed particles are not unknowns: drop their rows and columns from ∇E and ∇²E (solve "
        "for the free particles only) and keep x⁺_i = x_i, v⁺_i = 0 for them; gravity and "
        "the springs must not move them.",
        symptom=_fixed_moved),
    Misconception(
        "no_line_search", "implicit_euler_step", "Newton without its line search",
        "On this case, full Newton steps from y overshoot and never settle (a big h, a start "
        "far from the answer); your x⁺ is not the minimiser. Halve α from 1 until "
        "E(z + αΔz) <= E(z) + 1e-4 α ∇E·Δz + 1e-14 |E(z)| (or α < 2⁻³⁰), then "
        "z ← z + αΔz.",
        symptom=_needs_line_search),
    Misconception(
        "hessian_missing_term", "implicit_euler_step",
        "the Hessian without its (1 - L/‖d‖) term (or with it clamped at 0)",
        "Spring s's Hessian block is H_s = k[(1 - L/‖d‖) I + (L/‖d‖) d̂d̂ᵀ]; k d̂d̂ᵀ alone drops "
        "the (1 - L/‖d‖)(I - d̂d̂ᵀ) part, which is negative for a compressed spring "
        "(‖d‖ < L) and positive for a stretched one: Newton then misjudges the stiffness "
        "across the springs and crawls (or overshoots) instead of converging, and your "
        "answer is not yet the minimiser. Notebook 12's projection (the compressed springs' "
        "(1 - L/‖d‖) clamped at 0) does the same on compressed springs: it converges only "
        "linearly and 50 iterations are not enough. a5 wants the true Hessian, negative term "
        "kept, with Δz = -∇E whenever ∇E·Δz >= 0 (not a descent direction).",
        symptom=_stalled_without_the_term),
)


# --- the assignment ----------------------------------------------------------------------------

_FUNCTIONS = (
    Function("catmull_rom", ("keys", "times", "t"), lambda *a: kf.catmull_rom(*a),
             SplinePointsCheck(atol=1e-6, row="time")),
    Function("squad", ("q_keys", "times", "t"), lambda *a: kf.squad(*a),
             SQUAD_CHECK),
    Function("implicit_euler_step",
             ("x", "v", "masses", "springs", "rest", "k", "h", "fixed", "gravity"),
             step_reference, StepCheck(),
             timeout_hint="most likely a Newton loop that never meets its stopping test "
                          "(near the minimum, rounding in E can make the Armijo test fail for "
                          "every α, or ‖∇E‖ never gets below a fixed 1e-9): cap the iterations "
                          "at 50, stop halving α below 2⁻³⁰, allow 1e-14 |E(z)| in the Armijo "
                          "test, and stop at a threshold relative to the force scale (see the "
                          "template's docstring)"),
)


ASSIGNMENT = Assignment(
    key="a5",
    title="Keyframes and implicit Euler",
    template="a5_animation.py",
    functions=_FUNCTIONS,
    tests=(
        *random_edge_hidden("catmull_rom", catmull_random, catmull_edges, catmull_hidden),
        *random_edge_hidden("squad", squad_random, squad_edges, squad_hidden),
        *random_edge_hidden("implicit_euler_step", step_random, step_edges, step_hidden, (2, 2, 2)),
    ),
    misconceptions=MISCONCEPTIONS,
)
