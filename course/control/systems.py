r"""Small systems to control, as discrete-time models ``x_{t+1} = f(x_t, u_t)``.

SI units throughout (m, s, kg, rad, N, N m); in the plane, x to the right and **y up**
(``docs/conventions.md``), angles counter-clockwise unless said otherwise. States list
positions first, then velocities, as MuJoCo orders its ``(qpos, qvel)``.

* :func:`double_integrator` — a mass pushed along a line: ``p̈ = u/m``, discretised exactly
  (zero-order hold). The LQR test problem with a closed form.
* :func:`linear_inverted_pendulum` — lecture 11's linear inverted pendulum (LIPM): the
  centre of mass at constant height ``z_c`` over the centre of pressure ``p``,
  ``c̈ = (g/z_c)(c - p)``, discretised exactly; the control is ``p``.
* :class:`Pendulum` — a point mass on a massless rod about a motor, ``θ`` from upright; the
  swing-up of value iteration and iLQR, and the balance of LQR.
* :class:`CartPole` — a point-mass pole on a cart pushed along x.

The nonlinear ones step by semi-implicit (symplectic) Euler — velocity first, then position
with the new velocity — which is MuJoCo's ``Euler`` integrator too, so an equal MuJoCo model
gives the same Jacobians (``tests/test_control_linearize.py`` checks it).

Every model has ``step(x, u)`` (broadcasting over leading axes: ``x (..., n)``,
``u (..., m)``) and ``jacobians(x, u) -> (A, B)``, ``A = ∂f/∂x (n, n)``, ``B = ∂f/∂u
(n, m)``: what :mod:`course.control.ilqr` needs (:class:`DiscreteSystem`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .._validate import as_array, as_positive, as_time_step
from ._checks import as_vector

GRAVITY = 9.81  # m/s^2, along -y


class DiscreteSystem(Protocol):
    """What a trajectory optimiser needs of a model: its sizes, one step and its Jacobians."""

    @property
    def n_states(self) -> int: ...

    @property
    def n_controls(self) -> int: ...

    def step(self, x: ArrayLike, u: ArrayLike) -> Array: ...

    def jacobians(self, x: ArrayLike, u: ArrayLike) -> tuple[Array, Array]: ...


def _state_and_control(x: ArrayLike, u: ArrayLike, n: int, m: int) -> tuple[Array, Array]:
    xs = as_array(x, "x", (n,))
    us = as_array(u, "u", (m,))
    return xs, us


class LinearSizes:
    """The sizes of a model that holds ``A (n, n)`` and ``B (n, m)``: the one definition of
    ``n_states`` and ``n_controls`` for :class:`LinearSystem` and
    :class:`~course.control.policy_gradient.LQTask`."""

    A: Array
    B: Array

    @property
    def n_states(self) -> int:
        """``n``, the rows of ``A``."""
        return int(self.A.shape[0])

    @property
    def n_controls(self) -> int:
        """``m``, the columns of ``B``."""
        return int(self.B.shape[1])


@dataclass(frozen=True)
class LinearSystem(LinearSizes):
    """``x_{t+1} = A x_t + B u_t``, with names for its state and control entries.

    Attributes
    ----------
    A, B : ndarray, shapes (n, n), (n, m)
    dt : float
        The time step, s.
    state_names, control_names : tuple of str
        What each entry of ``x`` and ``u`` is, with its unit.
    """

    A: Array
    B: Array
    dt: float
    state_names: tuple[str, ...]
    control_names: tuple[str, ...]

    def step(self, x: ArrayLike, u: ArrayLike) -> Array:
        xs, us = _state_and_control(x, u, self.n_states, self.n_controls)
        # Broadcast products summed explicitly (no BLAS): the same bits however many threads.
        return np.asarray((self.A * xs[..., None, :]).sum(-1) + (self.B * us[..., None, :]).sum(-1))

    def jacobians(self, x: ArrayLike, u: ArrayLike) -> tuple[Array, Array]:
        _state_and_control(x, u, self.n_states, self.n_controls)
        return self.A.copy(), self.B.copy()


def double_integrator(dt: float = 0.1, mass: float = 1.0) -> LinearSystem:
    """A mass ``m`` (kg) on a line pushed by a force ``u`` (N): state ``(p, v)`` (m, m/s).

    Exact for a force held over each step (zero-order hold)::

        A = [[1, dt], [0, 1]],   B = [[dt²/(2m)], [dt/m]]
    """
    h = as_time_step(dt)
    m = as_positive(mass, "mass")
    return LinearSystem(A=np.array([[1.0, h], [0.0, 1.0]]),
                        B=np.array([[h * h / (2 * m)], [h / m]]), dt=h,
                        state_names=("position (m)", "velocity (m/s)"),
                        control_names=("force (N)",))


def linear_inverted_pendulum(dt: float = 0.02, com_height: float = 0.9,
                             gravity: float = GRAVITY) -> LinearSystem:
    """Lecture 11's LIPM along one horizontal axis: state ``(c, ċ)``, the centre of mass's
    horizontal position (m) and velocity (m/s); control ``p``, the centre of pressure (ZMP)
    on the ground (m). ``c̈ = ω²(c - p)`` with ``ω = √(g/z_c)``, exact for ``p`` held over
    the step::

        A = [[cosh ωdt, sinh(ωdt)/ω], [ω sinh ωdt, cosh ωdt]],
        B = [[1 - cosh ωdt], [-ω sinh ωdt]]

    (``c = p`` at rest is an equilibrium: ``A (p, 0) + B p = (p, 0)``.) Unstable: one
    eigenvalue ``e^{ωdt} > 1``, which the COP must catch.
    """
    h = as_time_step(dt)
    z = as_positive(com_height, "com_height")
    w = math.sqrt(as_positive(gravity, "gravity") / z)
    ch, sh = math.cosh(w * h), math.sinh(w * h)
    return LinearSystem(A=np.array([[ch, sh / w], [w * sh, ch]]),
                        B=np.array([[1.0 - ch], [-w * sh]]), dt=h,
                        state_names=("COM position (m)", "COM velocity (m/s)"),
                        control_names=("centre of pressure (m)",))


@dataclass(frozen=True)
class Pendulum:
    """A point mass ``m`` at the end of a massless rod of length ``l``, turned by a torque
    ``u`` (N m) at the pivot, with viscous damping ``b`` (N m s/rad).

    State ``(θ, ω)``: ``θ`` (rad) counter-clockwise from **upright**, so the mass is at
    ``(-l sin θ, l cos θ)`` (y up), ``θ = 0`` balanced on top and ``θ = ±π`` hanging down;
    ``ω = θ̇`` (rad/s). Continuous dynamics ``m l² θ̈ = m g l sin θ - b θ̇ + u``; one step by
    semi-implicit Euler: ``ω⁺ = ω + dt θ̈``, ``θ⁺ = θ + dt ω⁺`` (``θ`` is not wrapped).
    """

    mass: float = 1.0
    length: float = 1.0
    gravity: float = GRAVITY
    damping: float = 0.0
    dt: float = 0.02

    def __post_init__(self) -> None:
        as_positive(self.mass, "mass")
        as_positive(self.length, "length")
        as_positive(self.gravity, "gravity", allow_zero=True)
        as_positive(self.damping, "damping", allow_zero=True)
        as_time_step(self.dt)

    n_states = 2
    n_controls = 1

    @property
    def inertia(self) -> float:
        """``m l²``, kg m²."""
        return self.mass * self.length**2

    def acceleration(self, theta: ArrayLike, omega: ArrayLike, torque: ArrayLike) -> Array:
        """``θ̈`` (rad/s²)."""
        return np.asarray((self.gravity / self.length) * np.sin(theta)
                          + (np.asarray(torque) - self.damping * np.asarray(omega))
                          / self.inertia, dtype=np.float64)

    def step(self, x: ArrayLike, u: ArrayLike) -> Array:
        xs, us = _state_and_control(x, u, 2, 1)
        omega = xs[..., 1] + self.dt * self.acceleration(xs[..., 0], xs[..., 1], us[..., 0])
        return np.stack([xs[..., 0] + self.dt * omega, omega], axis=-1)

    def jacobians(self, x: ArrayLike, u: ArrayLike) -> tuple[Array, Array]:
        """The step's exact Jacobians at one ``(x, u)``: ``A (2, 2)``, ``B (2, 1)``."""
        xs = as_vector(x, "x", 2)
        as_vector(u, "u", 1)
        h = self.dt
        dw_dtheta = h * (self.gravity / self.length) * math.cos(xs[0])
        dw_domega = 1.0 - h * self.damping / self.inertia
        dw_du = h / self.inertia
        A = np.array([[1.0 + h * dw_dtheta, h * dw_domega], [dw_dtheta, dw_domega]])
        B = np.array([[h * dw_du], [dw_du]])
        return A, B

    def linearize_upright(self) -> LinearSystem:
        """The step linearised on top, ``x = 0, u = 0``: the LQR balance problem."""
        A, B = self.jacobians(np.zeros(2), np.zeros(1))
        return LinearSystem(A=A, B=B, dt=self.dt, state_names=PENDULUM_STATE,
                            control_names=("torque (N m)",))

    def energy(self, x: ArrayLike) -> Array:
        """Kinetic plus potential energy (J), zero hanging at rest, ``2 m g l`` on top."""
        xs = as_array(x, "x", (2,))
        return np.asarray(0.5 * self.inertia * xs[..., 1] ** 2
                          + self.mass * self.gravity * self.length * (1 + np.cos(xs[..., 0])))


PENDULUM_STATE = ("angle from upright (rad)", "angular velocity (rad/s)")


@dataclass(frozen=True)
class CartPole:
    """A cart of mass ``M`` on the x axis, pushed by a horizontal force ``u`` (N), carrying a
    massless pole of length ``l`` with a point mass ``m`` at its end, on a free hinge.

    State ``(x, θ, ẋ, θ̇)``: cart position (m), pole angle from **upright** (rad, positive
    leaning towards +x: the pole's tip is at ``(x + l sin θ, l cos θ)``, y up), and their
    rates. The equations of motion (Lagrange)::

        (M + m) ẍ + m l (θ̈ cos θ - θ̇² sin θ) = u
        l θ̈ + ẍ cos θ = g sin θ

    solved for ``(ẍ, θ̈)``, stepped by semi-implicit Euler. Jacobians by central finite
    differences of the step.
    """

    cart_mass: float = 1.0
    pole_mass: float = 0.1
    length: float = 0.5
    gravity: float = GRAVITY
    dt: float = 0.02

    def __post_init__(self) -> None:
        as_positive(self.cart_mass, "cart_mass")
        as_positive(self.pole_mass, "pole_mass")
        as_positive(self.length, "length")
        as_positive(self.gravity, "gravity", allow_zero=True)
        as_time_step(self.dt)

    n_states = 4
    n_controls = 1

    def accelerations(self, theta: Array, theta_dot: Array, force: Array) -> tuple[Array, Array]:
        """``(ẍ, θ̈)``."""
        M, m, length, g = self.cart_mass, self.pole_mass, self.length, self.gravity
        s, c = np.sin(theta), np.cos(theta)
        denominator = M + m * s * s
        x_dd = (force + m * s * (length * theta_dot**2 - g * c)) / denominator
        theta_dd = ((M + m) * g * s - c * (force + m * length * theta_dot**2 * s)) / (
            length * denominator)
        return x_dd, theta_dd

    def step(self, x: ArrayLike, u: ArrayLike) -> Array:
        xs, us = _state_and_control(x, u, 4, 1)
        x_dd, theta_dd = self.accelerations(xs[..., 1], xs[..., 3], us[..., 0])
        v = xs[..., 2] + self.dt * x_dd
        w = xs[..., 3] + self.dt * theta_dd
        return np.stack([xs[..., 0] + self.dt * v, xs[..., 1] + self.dt * w, v, w], axis=-1)

    def jacobians(self, x: ArrayLike, u: ArrayLike) -> tuple[Array, Array]:
        return finite_difference_jacobians(self.step, as_vector(x, "x", 4), as_vector(u, "u", 1))

    def linearize_upright(self) -> LinearSystem:
        A, B = self.jacobians(np.zeros(4), np.zeros(1))
        return LinearSystem(A=A, B=B, dt=self.dt,
                            state_names=("cart position (m)", "pole angle from upright (rad)",
                                         "cart velocity (m/s)", "pole rate (rad/s)"),
                            control_names=("force on the cart (N)",))


def finite_difference_jacobians(step: Callable[[Array, Array], Array], x: ArrayLike,
                                u: ArrayLike, eps: float = 1e-6) -> tuple[Array, Array]:
    """``A = ∂f/∂x``, ``B = ∂f/∂u`` of ``f = step`` at ``(x, u)`` by central differences
    (error ``O(eps²)`` in the step's smoothness, plus rounding ``~1e-16/eps``)."""
    xs = as_array(x, "x")
    us = as_array(u, "u")
    if xs.ndim != 1 or us.ndim != 1:
        raise ValueError(f"x, u: expected one state (n,) and one control (m,), got shapes "
                         f"{xs.shape} and {us.shape}")
    h = as_positive(eps, "eps")
    n, m = xs.size, us.size
    A = np.empty((n, n))
    B = np.empty((n, m))
    for j in range(n):
        d = np.zeros(n)
        d[j] = h
        A[:, j] = (step(xs + d, us) - step(xs - d, us)) / (2 * h)
    for j in range(m):
        d = np.zeros(m)
        d[j] = h
        B[:, j] = (step(xs, us + d) - step(xs, us - d)) / (2 * h)
    return A, B
