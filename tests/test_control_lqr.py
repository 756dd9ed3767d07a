"""LQR by the Riccati recursion (course.control.lqr): the fixed point against scipy's DARE
solver, the finite horizon converging to the infinite one, closed forms (the scalar system,
the double integrator's continuous limit), policy evaluation, and what a bad argument or an
unstabilisable system says. hypothesis with derandomize=True; fixed seeds elsewhere."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from course.control import (
    double_integrator,
    gain_value_matrices,
    linear_inverted_pendulum,
    lqr_finite_horizon,
    lqr_infinite_horizon,
    quadratic_cost,
    riccati_step,
    rollout_linear,
)

PROPERTY = settings(max_examples=40, derandomize=True, deadline=None, database=None)


@st.composite
def lq_problems(draw: st.DrawFn) -> tuple[np.ndarray, ...]:
    """A random controllable (A, B), Q positive definite, R positive definite."""
    n = draw(st.integers(1, 4))
    m = draw(st.integers(1, 2))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A *= draw(st.floats(0.3, 1.3)) / max(np.max(np.abs(np.linalg.eigvals(A))), 1e-9)
    B = rng.standard_normal((n, m))
    controllability = np.hstack([np.linalg.matrix_power(A, k) @ B for k in range(n)])
    assume(np.linalg.svd(controllability, compute_uv=False)[-1] > 1e-2)
    L = rng.standard_normal((n, n))
    M = rng.standard_normal((m, m))
    return A, B, L @ L.T + 0.1 * np.eye(n), M @ M.T + 0.1 * np.eye(m)


@PROPERTY
@given(lq_problems())
def test_riccati_fixed_point_is_scipys_dare_solution(problem: tuple[np.ndarray, ...]) -> None:
    A, B, Q, R = problem
    result = lqr_infinite_horizon(A, B, Q, R)
    assert result.converged, result.reason
    P = scipy.linalg.solve_discrete_are(A, B, Q, R)
    scale = np.max(np.abs(P))
    np.testing.assert_allclose(result.P, P, atol=1e-8 * scale)
    K = np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
    np.testing.assert_allclose(result.K, K, atol=1e-7 * max(1.0, np.max(np.abs(K))))
    assert result.spectral_radius < 1  # the LQR gain stabilises


@PROPERTY
@given(lq_problems(), st.floats(0.5, 0.99))
def test_a_discount_is_the_scaled_system(problem: tuple[np.ndarray, ...], gamma: float) -> None:
    A, B, Q, R = problem
    result = lqr_infinite_horizon(A, B, Q, R, discount=gamma)
    assert result.converged, result.reason
    r = math.sqrt(gamma)
    P = scipy.linalg.solve_discrete_are(r * A, r * B, Q, R)
    np.testing.assert_allclose(result.P, P, atol=1e-8 * np.max(np.abs(P)))
    K = np.linalg.solve(R / gamma + B.T @ P @ B, B.T @ P @ A)  # the docstring's form
    np.testing.assert_allclose(result.K, K, atol=1e-7 * max(1.0, np.max(np.abs(K))))


@PROPERTY
@given(lq_problems(), st.sampled_from([1.0, 0.9]))
def test_doubling_reaches_scipys_dare_solution(problem: tuple[np.ndarray, ...],
                                               gamma: float) -> None:
    A, B, Q, R = problem
    result = lqr_infinite_horizon(A, B, Q, R, discount=gamma, method="doubling")
    assert result.converged, result.reason
    r = math.sqrt(gamma)
    P = scipy.linalg.solve_discrete_are(r * A, r * B, Q, R)
    np.testing.assert_allclose(result.P, P, atol=1e-8 * np.max(np.abs(P)))
    K = np.linalg.solve(R / gamma + B.T @ P @ B, B.T @ P @ A)
    np.testing.assert_allclose(result.K, K, atol=1e-7 * max(1.0, np.max(np.abs(K))))
    assert result.spectral_radius < 1


def test_each_doubling_step_doubles_the_recursion() -> None:
    """After k doubling steps P is the recursion's after 2^k - 1 steps from P = Q, so a slow
    closed loop (the double integrator at dt = 1 ms: ~10^4 plain steps) takes ~20."""
    rng = np.random.default_rng(7)
    A, B = rng.standard_normal((4, 4)), rng.standard_normal((4, 2))
    Q, R = np.eye(4), np.diag([1.0, 3.0])
    P = Q.copy()
    for k in range(1, 6):
        for _ in range(2 ** (k - 1)):  # 2^k - 1 steps in all
            P, _ = riccati_step(P, A, B, Q, R)
        doubled = lqr_infinite_horizon(A, B, Q, R, method="doubling", max_iterations=k)
        np.testing.assert_allclose(doubled.P, P, rtol=1e-10, atol=1e-10 * np.max(np.abs(P)))
    slow = double_integrator(dt=0.001)
    plain = lqr_infinite_horizon(slow.A, slow.B, np.eye(2), [[1.0]], tol=1e-10)
    fast = lqr_infinite_horizon(slow.A, slow.B, np.eye(2), [[1.0]], tol=1e-10,
                                method="doubling")
    assert plain.converged and fast.converged, (plain.reason, fast.reason)
    assert fast.iterations < 30 < 1000 < plain.iterations
    np.testing.assert_allclose(fast.K, plain.K, rtol=1e-6)


def test_doubling_reports_divergence_and_refuses_P0() -> None:
    result = lqr_infinite_horizon([[1.0, 0.0], [0.0, 2.0]], [[1.0], [0.0]], np.eye(2), [[1.0]],
                                  method="doubling")
    assert not result.converged and result.reason.startswith("diverged")
    with pytest.raises(ValueError, match="P0: the doubling method starts from Q"):
        lqr_infinite_horizon(np.eye(2), np.ones((2, 1)), np.eye(2), [[1.0]], P0=np.eye(2),
                             method="doubling")
    with pytest.raises(ValueError, match="method: expected one of"):
        lqr_infinite_horizon(np.eye(2), np.ones((2, 1)), np.eye(2), [[1.0]],
                             method="newton")  # type: ignore[arg-type]


def test_finite_horizon_converges_to_the_infinite_horizon() -> None:
    system = linear_inverted_pendulum(dt=0.02)
    Q, R = np.diag([10.0, 1.0]), np.array([[0.1]])
    infinite = lqr_infinite_horizon(system.A, system.B, Q, R)
    finite = lqr_finite_horizon(system.A, system.B, Q, R, horizon=400)
    # Far from the horizon the gains are the stationary one; near it they differ.
    gap = np.max(np.abs(finite.K - infinite.K), axis=(1, 2))
    assert gap[0] < 1e-9 * np.max(np.abs(infinite.K))
    assert gap[-1] > 1e-2 * np.max(np.abs(infinite.K))
    # the gap shrinks going backwards (up to rounding once it is at the stationary gain)
    assert np.all(np.diff(gap) >= -1e-9 * np.max(np.abs(infinite.K)))
    # Started from the DARE's P the recursion stays there: the horizon disappears.
    still = lqr_finite_horizon(system.A, system.B, Q, R, horizon=20, Q_final=infinite.P)
    np.testing.assert_allclose(still.K, np.broadcast_to(infinite.K, still.K.shape), atol=1e-9)


@settings(max_examples=60, derandomize=True, deadline=None, database=None)
@given(st.floats(-2, 2), st.floats(0.1, 3), st.floats(0.01, 10), st.floats(0.01, 10))
def test_scalar_system_closed_form(a: float, b: float, q: float, r: float) -> None:
    """x⁺ = a x + b u, cost q x² + r u²: the DARE is the quadratic
    b² p² + (r - q b² - a² r) p - q r = 0, whose positive root is P, and K = a b p/(r + b² p)."""
    c = r - q * b * b - a * a * r
    p = (-c + math.sqrt(c * c + 4 * b * b * q * r)) / (2 * b * b)
    result = lqr_infinite_horizon([[a]], [[b]], [[q]], [[r]])
    assert result.converged, result.reason
    assert result.P[0, 0] == pytest.approx(p, rel=1e-9)
    assert result.K[0, 0] == pytest.approx(a * b * p / (r + b * b * p), rel=1e-8, abs=1e-12)


def test_double_integrator_tends_to_the_continuous_closed_form() -> None:
    """p̈ = u with cost ∫ (q₁p² + q₂v² + r u²) dt has the gain
    K = (√(q₁/r), √(q₂/r + 2√(q₁/r))); the discrete LQR with Q = dt Q_c, R = dt R_c tends to
    it as dt → 0, with an error of order dt."""
    q1, q2, r = 4.0, 1.0, 0.25
    closed = np.array([math.sqrt(q1 / r), math.sqrt(q2 / r + 2 * math.sqrt(q1 / r))])
    errors = []
    for dt in (0.02, 0.01, 0.005):
        system = double_integrator(dt=dt)
        result = lqr_infinite_horizon(system.A, system.B, dt * np.diag([q1, q2]),
                                      [[dt * r]])
        assert result.converged, result.reason
        errors.append(np.max(np.abs(result.K[0] - closed)) / np.max(closed))
    assert errors[-1] < 0.01
    assert errors[0] / errors[1] == pytest.approx(2, rel=0.1)  # first order in dt
    assert errors[1] / errors[2] == pytest.approx(2, rel=0.1)


def test_riccati_step_is_the_lectures_formula() -> None:
    rng = np.random.default_rng(3)
    A, B = rng.standard_normal((3, 3)), rng.standard_normal((3, 2))
    Q, R, P1 = np.eye(3), 2 * np.eye(2), np.diag([1.0, 2.0, 3.0])
    P, K = riccati_step(P1, A, B, Q, R)
    inv = np.linalg.inv(R + B.T @ P1 @ B)
    np.testing.assert_allclose(K, inv @ B.T @ P1 @ A, atol=1e-12)
    np.testing.assert_allclose(P, Q + A.T @ P1 @ A - A.T @ P1 @ B @ inv @ B.T @ P1 @ A,
                               atol=1e-10)
    assert K.shape == (2, 3)


def test_the_value_matrix_is_the_rollout_cost_and_the_gain_is_optimal() -> None:
    system = double_integrator(dt=0.1)
    Q, R, T = np.diag([1.0, 0.5]), np.array([[0.2]]), 30
    lqr = lqr_finite_horizon(system.A, system.B, Q, R, T, Q_final=5 * Q)
    x0 = np.array([1.0, -0.5])
    x, u = rollout_linear(system.A, system.B, lqr.K, x0, T)
    assert quadratic_cost(x, u, Q, R, 5 * Q) == pytest.approx(lqr.cost(x0), rel=1e-12)
    # Policy evaluation of the optimal gains gives back the Riccati P.
    np.testing.assert_allclose(gain_value_matrices(system.A, system.B, Q, R, lqr.K, T, 5 * Q),
                               lqr.P, atol=1e-10)
    # Any other gain costs more, whichever way it is perturbed.
    rng = np.random.default_rng(0)
    for _ in range(5):
        other = lqr.K + 0.05 * rng.standard_normal(lqr.K.shape)
        x, u = rollout_linear(system.A, system.B, other, x0, T)
        assert quadratic_cost(x, u, Q, R, 5 * Q) > lqr.cost(x0)
    # The control is -K x: the sign flipped doubles back and costs far more.
    x, u = rollout_linear(system.A, system.B, -lqr.K, x0, T)
    assert quadratic_cost(x, u, Q, R, 5 * Q) > 10 * lqr.cost(x0)


def test_time_varying_dynamics() -> None:
    rng = np.random.default_rng(1)
    T = 5
    A = np.eye(2) + 0.1 * rng.standard_normal((T, 2, 2))
    B = rng.standard_normal((T, 2, 1))
    result = lqr_finite_horizon(A, B, np.eye(2), [[1.0]], T)
    P = np.eye(2)
    for t in range(T - 1, -1, -1):
        P, K = riccati_step(P, A[t], B[t], np.eye(2), [[1.0]])
        np.testing.assert_allclose(result.K[t], K, atol=1e-12)


def test_an_unstabilisable_system_says_it_diverged() -> None:
    # The second state grows by 2 each step and no control reaches it.
    result = lqr_infinite_horizon([[1.0, 0.0], [0.0, 2.0]], [[1.0], [0.0]], np.eye(2), [[1.0]])
    assert not result.converged
    assert result.reason.startswith("diverged")
    assert "stabilisable" in result.reason


def test_too_few_iterations_says_so() -> None:
    system = double_integrator(dt=0.001)
    result = lqr_infinite_horizon(system.A, system.B, np.eye(2), [[1.0]], max_iterations=10)
    assert not result.converged and result.iterations == 10
    assert "not converged" in result.reason and "max_iterations" in result.reason


@pytest.mark.parametrize(("args", "message"), [
    (([[1.0, 0.1], [0.0, 1.0]], [[0.0], [0.1], [0.2]], np.eye(2), [[1.0]]),
     r"B: expected shape \(2, m\) to match A"),
    (([[1.0, 0.1]], [[0.0]], np.eye(2), [[1.0]]), r"A: expected a square matrix, got shape"),
    (([[1.0, 0.1], [0.0, 1.0]], [[0.0], [0.1]], np.eye(3), [[1.0]]),
     r"Q: expected a matrix of shape \(2, 2\)"),
    (([[1.0, 0.1], [0.0, 1.0]], [[0.0], [0.1]], np.eye(2), [[0.0]]),
     "R: must be positive definite"),
    (([[1.0, 0.1], [0.0, 1.0]], [[0.0], [0.1]], [[1.0, 1.0], [0.0, 1.0]], [[1.0]]),
     "Q: a cost matrix must be symmetric"),
    (([[1.0, 0.1], [0.0, 1.0]], [[0.0], [0.1]], -np.eye(2), [[1.0]]),
     "Q: must be positive semi-definite"),
    (([[1.0, np.nan], [0.0, 1.0]], [[0.0], [0.1]], np.eye(2), [[1.0]]), "A: contains NaN"),
])
def test_bad_arguments_are_named(args: tuple[object, ...], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        lqr_infinite_horizon(*args)  # type: ignore[arg-type]


def test_bad_horizon_gain_and_discount() -> None:
    system = double_integrator()
    with pytest.raises(ValueError, match="horizon: expected an integer >= 1"):
        lqr_finite_horizon(system.A, system.B, np.eye(2), [[1.0]], horizon=0)
    with pytest.raises(ValueError, match="discount: expected a number in"):
        lqr_infinite_horizon(system.A, system.B, np.eye(2), [[1.0]], discount=1.5)
    with pytest.raises(ValueError, match=r"K: expected a gain of shape \(1, 2\)"):
        rollout_linear(system.A, system.B, np.zeros((2, 1)), [1.0, 0.0], 5)
    with pytest.raises(ValueError, match=r"A, B: expected \(n, n\) and \(n, m\), or \(5,"):
        lqr_finite_horizon(np.zeros((4, 2, 2)), np.zeros((4, 2, 1)), np.eye(2), [[1.0]], 5)
