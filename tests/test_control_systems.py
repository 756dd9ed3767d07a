"""The small systems of course.control.systems: exact discretisations against the
continuous dynamics (matrix exponential), the pendulum's and cart-pole's conventions (y up,
θ from upright, equilibria, the sign of gravity's pull), their Jacobians against central
differences, broadcasting and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
from hypothesis import given, settings
from hypothesis import strategies as st

from course.control import (
    CartPole,
    Pendulum,
    double_integrator,
    finite_difference_jacobians,
    linear_inverted_pendulum,
)

PROPERTY = settings(max_examples=30, derandomize=True, deadline=None, database=None)


def zero_order_hold(Ac: np.ndarray, Bc: np.ndarray, dt: float) -> tuple[np.ndarray, ...]:
    n, m = Bc.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = Ac, Bc
    E = scipy.linalg.expm(M * dt)
    return E[:n, :n], E[:n, n:]


def test_double_integrator_is_exact() -> None:
    system = double_integrator(dt=0.1, mass=2.0)
    A, B = zero_order_hold(np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [0.5]]), 0.1)
    np.testing.assert_allclose(system.A, A, atol=1e-14)
    np.testing.assert_allclose(system.B, B, atol=1e-14)
    assert system.state_names == ("position (m)", "velocity (m/s)")


def test_linear_inverted_pendulum_is_exact_and_unstable() -> None:
    system = linear_inverted_pendulum(dt=0.02, com_height=0.8)
    w2 = 9.81 / 0.8
    A, B = zero_order_hold(np.array([[0.0, 1.0], [w2, 0.0]]), np.array([[0.0], [-w2]]), 0.02)
    np.testing.assert_allclose(system.A, A, atol=1e-13)
    np.testing.assert_allclose(system.B, B, atol=1e-13)
    # At rest above the centre of pressure it stays; the unstable eigenvalue is e^{ω dt}.
    np.testing.assert_allclose(system.step([0.3, 0.0], [0.3]), [0.3, 0.0], atol=1e-15)
    assert max(abs(np.linalg.eigvals(system.A))) == pytest.approx(math.exp(math.sqrt(w2) * 0.02))


def test_pendulum_conventions() -> None:
    p = Pendulum(dt=0.01)
    # Upright and hanging are equilibria; leaning counter-clockwise it falls further that way.
    np.testing.assert_allclose(p.step([0.0, 0.0], [0.0]), [0.0, 0.0])
    np.testing.assert_allclose(p.step([np.pi, 0.0], [0.0]), [np.pi, 0.0], atol=1e-15)
    assert p.step([0.1, 0.0], [0.0])[1] > 0
    # A torque of m g l sin θ holds it.
    np.testing.assert_allclose(p.step([0.5, 0.0], [-9.81 * math.sin(0.5)]), [0.5, 0.0],
                               atol=1e-15)
    # Symplectic Euler keeps the energy of a swing bounded: it oscillates by O(dt) within a
    # swing, with no drift from the first 5 s to the last of 20 s.
    x = np.array([2.0, 0.0])
    energies = []
    for _ in range(2000):
        x = p.step(x, [0.0])
        energies.append(float(p.energy(x)))
    assert np.ptp(energies) < 0.05 * energies[0]
    assert abs(np.mean(energies[:500]) - np.mean(energies[-500:])) < 1e-3 * energies[0]
    assert p.energy([0.0, 0.0]) == pytest.approx(2 * 9.81)


def test_cart_pole_conventions() -> None:
    c = CartPole()
    np.testing.assert_allclose(c.step([0.5, 0.0, 0.0, 0.0], [0.0]), [0.5, 0.0, 0.0, 0.0])
    # Leaning towards +x it falls towards +x and the cart moves back; pushing +x moves +x.
    nxt = c.step([0.0, 0.1, 0.0, 0.0], [0.0])
    assert nxt[3] > 0 and nxt[2] < 0
    assert c.step([0.0, 0.0, 0.0, 0.0], [1.0])[2] > 0
    lin = c.linearize_upright()
    assert max(abs(np.linalg.eigvals(lin.A))) > 1  # unstable on top


@PROPERTY
@given(st.floats(-4, 4), st.floats(-5, 5), st.floats(-3, 3))
def test_pendulum_jacobians_are_the_steps(theta: float, omega: float, torque: float) -> None:
    p = Pendulum(damping=0.3, dt=0.02)
    A, B = p.jacobians([theta, omega], [torque])
    A_fd, B_fd = finite_difference_jacobians(p.step, [theta, omega], [torque])
    np.testing.assert_allclose(A, A_fd, atol=1e-8)
    np.testing.assert_allclose(B, B_fd, atol=1e-8)


def test_steps_broadcast() -> None:
    p = Pendulum()
    x = np.random.default_rng(0).standard_normal((3, 5, 2))
    u = np.ones((3, 5, 1))
    batch = p.step(x, u)
    assert batch.shape == (3, 5, 2)
    np.testing.assert_array_equal(batch[1, 2], p.step(x[1, 2], u[1, 2]))
    c = CartPole()
    assert c.step(np.zeros((4, 4)), np.zeros((4, 1))).shape == (4, 4)
    assert double_integrator().step(np.zeros((6, 2)), np.ones((6, 1))).shape == (6, 2)


def test_bad_arguments_are_named() -> None:
    with pytest.raises(ValueError, match="length: must be a positive number"):
        Pendulum(length=0.0)
    with pytest.raises(ValueError, match="h: the time step"):
        CartPole(dt=-0.1)
    with pytest.raises(ValueError, match=r"x: expected shape \(\.\.\., 2\)"):
        Pendulum().step([0.0, 0.0, 0.0], [0.0])
    with pytest.raises(ValueError, match=r"u: expected shape \(\.\.\., 1\)"):
        CartPole().step([0.0] * 4, [0.0, 1.0])
    with pytest.raises(ValueError, match=r"x: expected a vector of shape \(2,\)"):
        Pendulum().jacobians(np.zeros((3, 2)), [0.0])
