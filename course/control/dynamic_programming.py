r"""Value iteration 值迭代 on a discretised pendulum: dynamic programming (DP) without
linearisation, so it finds the swing-up as well as the balance on top.

The Bellman equation of a discounted cost ``Σ γᵗ c(x_t, u_t)``,
``c(x, u) = xᵀQx + uᵀRu`` (``θ`` wrapped to ``(-π, π]``, so both ways to the top count)::

    V(x) = min_u [ c(x, u) + γ V(f(x, u)) ]

is solved on a grid of states ``(θ_i, ω_j)`` and a finite set of torques ``u_a``. The next
state ``f(x_ij, u_a)`` falls between grid points; ``V`` there is read by bilinear
interpolation of its four neighbours (periodic in ``θ``, clamped in ``ω``). Those four
indices and weights do not change from one sweep to the next, so they are computed once
(:class:`Transitions`), and each sweep is a gather, a weighted sum and a minimum::

    V_{k+1}[s] = min_a ( c[s, a] + γ Σ_{i<4} w[s, a, i] V_k[idx[s, a, i]] )

**Why it works.** The Bellman operator is a contraction by ``γ`` in the largest-error norm:
two value functions that differ by at most ``ε`` anywhere give successors that differ by at
most ``γ ε``. Interpolation weights are non-negative and sum to one, so reading ``V``
between grid points is an average that cannot enlarge a difference: the discretised
operator is still a ``γ``-contraction (Gordon 1995, *Stable function approximation in
dynamic programming*). So the sweeps converge from any start to one fixed point, and once a
sweep changes ``V`` by at most ``δ``, ``V`` is within ``γ δ / (1 - γ)`` of that fixed point
(the bound :class:`ValueIterationResult` reports). What the grid cannot give is the exact
``V`` of the continuous problem: near the top, where ``V ≈ xᵀPx``, its policy approaches
LQR's ``u = -Kx`` of the discounted linearisation as the grid is refined
(``tests/test_control_dynamic_programming.py`` measures how close).

numpy only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._typing import Array
from .._validate import as_array, as_positive
from ._checks import as_cost_matrix, as_count, as_fraction
from .systems import Pendulum


def wrap_angle(theta: ArrayLike) -> Array:
    """``θ`` wrapped to ``[-π, π)``."""
    return np.asarray(np.mod(np.asarray(theta, dtype=np.float64) + np.pi, 2 * np.pi) - np.pi,
                      dtype=np.float64)


@dataclass(frozen=True)
class PendulumGrid:
    """The discretisation: ``n_theta`` angles over ``[-π, π)`` (periodic, spacing
    ``2π / n_theta``), ``n_omega`` velocities over ``[-omega_max, omega_max]`` and the
    torques tried, ``n_torques`` over ``[-torque_max, torque_max]`` (odd counts put 0 on
    the grid)."""

    n_theta: int = 101
    n_omega: int = 101
    omega_max: float = 8.0
    n_torques: int = 21
    torque_max: float = 5.0

    def __post_init__(self) -> None:
        as_count(self.n_theta, "n_theta", minimum=3)
        as_count(self.n_omega, "n_omega", minimum=2)
        as_count(self.n_torques, "n_torques", minimum=2)
        as_positive(self.omega_max, "omega_max")
        as_positive(self.torque_max, "torque_max")

    @property
    def theta(self) -> Array:
        return -np.pi + (2 * np.pi / self.n_theta) * np.arange(self.n_theta, dtype=np.float64)

    @property
    def omega(self) -> Array:
        return np.linspace(-self.omega_max, self.omega_max, self.n_omega)

    @property
    def torques(self) -> Array:
        return np.linspace(-self.torque_max, self.torque_max, self.n_torques)

    def states(self) -> Array:
        """Every grid state, ``(n_theta * n_omega, 2)``, ``θ`` major (``s = i n_omega + j``)."""
        th, om = np.meshgrid(self.theta, self.omega, indexing="ij")
        return np.stack([th.ravel(), om.ravel()], axis=-1)

    def neighbours(self, x: ArrayLike) -> tuple[NDArray[np.intp], Array]:
        """The four grid states around each state ``x (..., 2)`` and their bilinear weights:
        ``(..., 4)`` flat indices and ``(..., 4)`` weights (non-negative, summing to 1).
        ``θ`` wraps around; ``ω`` beyond ``±omega_max`` is read at the edge."""
        xs = as_array(x, "x", (2,))
        d_theta = 2 * np.pi / self.n_theta
        d_omega = 2 * self.omega_max / (self.n_omega - 1)
        a = (wrap_angle(xs[..., 0]) + np.pi) / d_theta
        i0 = np.floor(a).astype(np.intp)
        fa = a - i0
        i0 %= self.n_theta
        i1 = (i0 + 1) % self.n_theta
        b = (np.clip(xs[..., 1], -self.omega_max, self.omega_max) + self.omega_max) / d_omega
        j0 = np.minimum(np.floor(b).astype(np.intp), self.n_omega - 2)
        fb = b - j0
        n = self.n_omega
        index = np.stack([i0 * n + j0, i0 * n + j0 + 1, i1 * n + j0, i1 * n + j0 + 1], axis=-1)
        weight = np.stack([(1 - fa) * (1 - fb), (1 - fa) * fb, fa * (1 - fb), fa * fb], axis=-1)
        return index, weight

    def interpolate(self, V: Array, x: ArrayLike) -> Array:
        """``V`` (``(n_theta, n_omega)`` on the grid) at states ``x (..., 2)``."""
        index, weight = self.neighbours(x)
        return np.asarray((V.ravel()[index] * weight).sum(-1))


@dataclass(frozen=True)
class Transitions:
    """Where each (grid state, torque) leads, as interpolation neighbours, and its cost.

    Attributes
    ----------
    index, weight : ndarray, shapes (S, U, 4)
        The next state's four grid neighbours and weights (``S`` states, ``U`` torques).
    cost : ndarray, shape (S, U)
        ``c(x_s, u_a) = x_sᵀ Q x_s + u_aᵀ R u_a``.
    """

    index: NDArray[np.intp]
    weight: Array
    cost: Array


def transitions(pendulum: Pendulum, grid: PendulumGrid, Q: Array, R: Array) -> Transitions:
    """The :class:`Transitions` of ``pendulum`` on ``grid`` for the cost ``Q``, ``R``."""
    x = grid.states()
    u = grid.torques
    S, U = x.shape[0], u.size
    x_next = pendulum.step(np.repeat(x[:, None, :], U, axis=1),
                           np.broadcast_to(u[None, :, None], (S, U, 1)))
    index, weight = grid.neighbours(x_next)
    state_cost = Q[0, 0] * x[:, 0] ** 2 + 2 * Q[0, 1] * x[:, 0] * x[:, 1] + Q[1, 1] * x[:, 1] ** 2
    cost = state_cost[:, None] + R[0, 0] * u[None, :] ** 2
    return Transitions(index=index, weight=weight, cost=cost)


def bellman_backup(table: Transitions, V: Array,
                   discount: float) -> tuple[Array, NDArray[np.intp]]:
    """One sweep: ``min_a (c[s, a] + γ Σ_i w[s, a, i] V[idx[s, a, i]])`` for every grid
    state ``s``, and the minimising torque's index. ``V`` is flat, ``(S,)``."""
    backup = table.cost + discount * (V[table.index] * table.weight).sum(-1)
    best = np.argmin(backup, axis=1)
    return np.take_along_axis(backup, best[:, None], axis=1)[:, 0], best


@dataclass(frozen=True)
class ValueIterationResult:
    """The value function and policy found by :func:`value_iteration`.

    Attributes
    ----------
    V : ndarray, shape (n_theta, n_omega)
        The discounted cost-to-go at each grid state.
    policy : ndarray, shape (n_theta, n_omega)
        The greedy torque (N m) at each grid state, from ``grid.torques``.
    iterations : int
        Sweeps run.
    change : float
        ``max |V_{k+1} - V_k|`` of the last sweep.
    error_bound : float
        ``γ change / (1 - γ)``: how far ``V`` can be from the discretised problem's fixed
        point.
    converged : bool
    reason : str
    pendulum, grid, Q, R, discount
        The problem solved.
    """

    V: Array
    policy: Array
    iterations: int
    change: float
    error_bound: float
    converged: bool
    reason: str
    pendulum: Pendulum
    grid: PendulumGrid
    Q: Array
    R: Array
    discount: float

    def value(self, x: ArrayLike) -> Array:
        """``V`` interpolated at states ``x (..., 2)``."""
        return self.grid.interpolate(self.V, x)

    def greedy_torque(self, x: ArrayLike, torques: ArrayLike | None = None) -> Array:
        """The torque minimising ``c(x, u) + γ V(f(x, u))`` at states ``x (..., 2)``, over
        ``torques`` (the grid's when omitted; a finer set reads the policy between the
        grid's torques)."""
        xs = as_array(x, "x", (2,))
        u = self.grid.torques if torques is None else as_array(torques, "torques")
        if u.ndim != 1:
            raise ValueError(f"torques: expected a 1-D array of candidates, got {u.shape}")
        xb = np.broadcast_to(xs[..., None, :], (*xs.shape[:-1], u.size, 2))
        x_next = self.pendulum.step(xb, np.broadcast_to(u[:, None], (*xb.shape[:-1], 1)))
        q = self.Q
        th = wrap_angle(xs[..., 0])
        state_cost = q[0, 0] * th**2 + 2 * q[0, 1] * th * xs[..., 1] + q[1, 1] * xs[..., 1] ** 2
        total = (state_cost[..., None] + self.R[0, 0] * u**2
                 + self.discount * self.value(x_next))
        return np.asarray(u[np.argmin(total, axis=-1)])


def value_iteration(pendulum: Pendulum | None = None, grid: PendulumGrid | None = None, *,
                    Q: ArrayLike | None = None, R: ArrayLike | None = None,
                    discount: float = 0.98, tol: float = 1e-6,
                    max_iterations: int = 20_000) -> ValueIterationResult:
    """Solve the discounted pendulum problem on ``grid`` by value iteration from ``V = 0``.

    Parameters
    ----------
    pendulum : Pendulum
        ``Pendulum(dt=0.05)`` when omitted (1 kg, 1 m, no damping). The step should move the
        state by about a grid cell or more: with much smaller steps the next state lands in
        the same cell, and interpolation smears ``V`` (numerical diffusion).
    grid : PendulumGrid
    Q, R : array_like, shapes (2, 2), (1, 1)
        The per-step cost; ``Q = dt diag(1, 0.1)``, ``R = dt [[0.01]]`` when omitted.
    discount : float
        ``γ`` in ``(0, 1)``: below 1 so the cost of hanging forever stays finite.
    tol : float
        Stop once ``V`` is provably within ``tol`` of the fixed point, ``γ δ/(1 - γ) ≤ tol``.
    max_iterations : int
    """
    p = Pendulum(dt=0.05) if pendulum is None else pendulum
    g = PendulumGrid() if grid is None else grid
    q = as_cost_matrix(p.dt * np.diag([1.0, 0.1]) if Q is None else Q, "Q", 2, definite=False)
    r = as_cost_matrix(p.dt * np.array([[0.01]]) if R is None else R, "R", 1, definite=False)
    gamma = as_fraction(discount, "discount", allow_one=False)
    tolerance = as_positive(tol, "tol")
    limit = as_count(max_iterations, "max_iterations")
    table = transitions(p, g, q, r)
    V = np.zeros(g.n_theta * g.n_omega)
    change = math.inf
    reason, converged, sweep = f"max_iterations ({limit}) reached", False, 0
    best = np.zeros(V.size, dtype=np.intp)
    for sweep in range(1, limit + 1):  # noqa: B007 (the count is reported)
        V_new, best = bellman_backup(table, V, gamma)
        change = float(np.max(np.abs(V_new - V)))
        V = V_new
        if gamma * change / (1 - gamma) <= tolerance:
            converged = True
            reason = (f"converged: the last sweep changed V by {change:.1e}, so V is within "
                      f"{gamma * change / (1 - gamma):.1e} of the fixed point")
            break
    shape = (g.n_theta, g.n_omega)
    return ValueIterationResult(
        V=V.reshape(shape), policy=g.torques[best].reshape(shape), iterations=sweep,
        change=change, error_bound=gamma * change / (1 - gamma), converged=converged,
        reason=reason, pendulum=p, grid=g, Q=q, R=r, discount=gamma)
