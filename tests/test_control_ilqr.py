"""iLQR (course.control.ilqr): on a linear system with a quadratic cost its backward pass is
the finite-horizon LQR and it lands on LQR's optimum; on the pendulum it swings up from
hanging with the cost falling at every accepted iteration; how it reports stopping."""

from __future__ import annotations

import numpy as np
import pytest

from course.control import (
    CartPole,
    ILQRResult,
    Pendulum,
    QuadraticCost,
    backward_pass,
    double_integrator,
    lqr_finite_horizon,
    pendulum_swing_up,
    rollout_open_loop,
    solve_ilqr,
)


def test_on_a_linear_system_the_backward_pass_is_lqr() -> None:
    system = double_integrator(dt=0.1)
    Q, R, Qf, T = np.diag([1.0, 0.1]), np.array([[0.01]]), 10 * np.eye(2), 40
    cost = QuadraticCost.make(Q, R, Qf)
    x0 = np.array([1.0, 0.0])
    u = np.zeros((T, 1))
    x = rollout_open_loop(system, x0, u)
    A = np.broadcast_to(system.A, (T, 2, 2))
    B = np.broadcast_to(system.B, (T, 2, 1))
    passed = backward_pass(A, B, x, u, cost, mu=0.0)
    assert passed is not None
    _, K, _, _ = passed
    lqr = lqr_finite_horizon(system.A, system.B, Q, R, T, Qf)
    np.testing.assert_allclose(K, lqr.K, atol=1e-9)  # same K, same sign: u = -K x

    result = solve_ilqr(system, x0, u, cost, mu0=0.0)
    assert result.converged, result.reason
    assert result.cost == pytest.approx(lqr.cost(x0), rel=1e-9)
    assert len(result.cost_history) <= 3  # one Newton step solves a quadratic problem


PENDULUM = Pendulum(dt=0.02)


@pytest.fixture(scope="module")
def swing_up() -> ILQRResult:
    return pendulum_swing_up(PENDULUM, duration=4.0, effort=1.0)


def test_the_pendulum_swings_up_with_the_cost_falling(swing_up: ILQRResult) -> None:
    pendulum, result = PENDULUM, swing_up
    assert result.converged, result.reason
    history = np.array(result.cost_history)
    assert np.all(np.diff(history) < 0)  # monotone: only decreasing steps are accepted
    assert history[-1] < 0.2 * history[0]
    theta, omega = result.x[-1]
    assert abs(theta) < 0.05 and abs(omega) < 0.05  # balanced on top
    assert result.x[0, 0] == pytest.approx(np.pi)
    # It has to pump: the torque stays below m g l, which could lift it straight up.
    assert np.max(np.abs(result.u)) < pendulum.mass * pendulum.gravity * pendulum.length
    # The returned trajectory is what the controls do from x0.
    np.testing.assert_allclose(rollout_open_loop(pendulum, result.x[0], result.u), result.x,
                               atol=1e-12)
    assert result.K.shape == (200, 1, 2) and result.k.shape == (200, 1)


def test_the_feedback_gains_hold_the_trajectory_against_a_push(swing_up: ILQRResult) -> None:
    pendulum, result = PENDULUM, swing_up
    x = result.x[0] + np.array([0.0, 0.3])  # starts swinging
    for t in range(result.u.shape[0]):
        u = result.u[t] - result.K[t] @ (x - result.x[t])
        x = pendulum.step(x, u)
    assert abs(x[0]) < 0.1 and abs(x[1]) < 0.3


def test_cart_pole_moves_half_a_metre_balancing() -> None:
    """Any DiscreteSystem will do (the cart-pole's Jacobians are finite differences). From
    upright the optimum is found in a few iterations; from a leaning start with zero
    controls, the first rollout falls over and iLQR settles in a local minimum that swings
    the pole round — it is a local method, and the first guess matters."""
    cart_pole = CartPole(dt=0.02)
    cost = QuadraticCost.make(Q=0.02 * np.diag([1.0, 1.0, 0.1, 0.1]), R=[[0.002]],
                              Q_final=100 * np.eye(4), goal=[0.5, 0.0, 0.0, 0.0])
    result = solve_ilqr(cart_pole, [0.0, 0.0, 0.0, 0.0], np.zeros((100, 1)), cost)
    assert result.converged, result.reason
    np.testing.assert_allclose(result.x[-1], [0.5, 0.0, 0.0, 0.0], atol=0.02)
    assert np.max(np.abs(result.x[:, 1])) < 0.2  # the pole stays up on the way


def test_stopping_is_reported() -> None:
    result = pendulum_swing_up(max_iterations=2)
    assert not result.converged and result.iterations == 2
    assert result.reason == "max_iterations (2) reached"


def test_bad_arguments_are_named() -> None:
    cost = QuadraticCost.make(np.eye(2), [[1.0]])
    with pytest.raises(ValueError, match=r"x0: expected a vector of shape \(2,\)"):
        solve_ilqr(Pendulum(), [0.0], np.zeros((5, 1)), cost)
    with pytest.raises(ValueError, match=r"u_init: expected a matrix of shape \(n, 1\)"):
        solve_ilqr(Pendulum(), [0.0, 0.0], np.zeros((5, 2)), cost)
    with pytest.raises(ValueError, match=r"cost: Q and R must be \(4, 4\) and \(1, 1\)"):
        solve_ilqr(CartPole(), [0.0] * 4, np.zeros((5, 1)), cost)
    with pytest.raises(ValueError, match="R: must be positive definite"):
        QuadraticCost.make(np.eye(2), [[0.0]])
    with pytest.raises(ValueError, match=r"goal: expected a vector of shape \(2,\)"):
        QuadraticCost.make(np.eye(2), [[1.0]], goal=[0.0])
