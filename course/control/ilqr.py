r"""The iterative LQR (iLQR): LQR applied again and again along a trajectory of a nonlinear
system, as in Tassa, Erez and Todorov (2012), *Synthesis and stabilization of complex
behaviors through online trajectory optimization* (IROS), Sec. II.

Given controls ``û_0 … û_{T-1}`` and the states ``x̂`` they reach, each iteration

1. **linearises** the dynamics along ``(x̂, û)``: ``δx_{t+1} ≈ A_t δx_t + B_t δu_t``
   (``A_t = ∂f/∂x``, ``B_t = ∂f/∂u``);
2. runs the **backward pass**, a Riccati recursion with linear terms: with
   ``V_x, V_xx`` the gradient and Hessian of the cost-to-go at ``t + 1``::

       Q_x  = l_x  + A_tᵀ V_x          Q_u  = l_u  + B_tᵀ V_x
       Q_xx = l_xx + A_tᵀ V_xx A_t     Q_uu = l_uu + B_tᵀ (V_xx + μI) B_t
                                       Q_ux = l_ux + B_tᵀ (V_xx + μI) A_t
       k_t = Q_uu⁻¹ Q_u,   K_t = Q_uu⁻¹ Q_ux,   δu_t = -k_t - K_t δx_t

   the same sign as LQR's ``u = -K x``: on a linear system with a quadratic cost the
   ``K_t`` here are :func:`~course.control.lqr.lqr_finite_horizon`'s. ``μ ≥ 0``
   regularises (Tassa et al. put it on ``V_xx``, which keeps the step's effect on the
   *state* small, rather than on ``Q_uu``); a ``Q_uu`` that is not positive definite makes
   ``μ`` grow and the pass start again;
3. runs the **forward pass** with a line search over ``α = 1, ½, ¼, …``: from the same
   ``x_0``, ``u_t = û_t - α k_t - K_t (x_t - x̂_t)`` stepped through the *nonlinear*
   dynamics, accepted when the cost falls by at least a fraction ``c`` of the decrease the
   quadratic model predicts, ``ΔJ(α) = α Σ k_tᵀ Q_u - ½ α² Σ k_tᵀ Q_uu k_t``.

Accepted steps lower ``μ``, rejected ones raise it (the schedule of their Sec. II-F), so
the cost falls monotonically. The iteration ends with a ``reason``: the relative decrease
below ``tol`` (converged), the predicted decrease below ``tol`` (at a stationary point), the
regularisation past ``mu_max`` (no descent found), or ``max_iterations``.

Costs are the lecture's quadratics about a goal state (``l = (x - x*)ᵀQ(x - x*) + uᵀRu``,
no ½): :class:`QuadraticCost`. Control limits are not handled (that is box-DDP, Tassa,
Mansard and Todorov 2014); ``R`` keeps the torques moderate instead. numpy only.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .._validate import as_positive
from ._checks import as_cost_matrix, as_count, as_matrix, as_square, as_vector
from .systems import DiscreteSystem, Pendulum

#: The line search's step sizes, tried in this order.
LINE_SEARCH = tuple(0.5**i for i in range(11))


@dataclass(frozen=True)
class QuadraticCost:
    """``Σ_{t<T} [(x_t - x*)ᵀ Q (x_t - x*) + u_tᵀ R u_t] + (x_T - x*)ᵀ Q_f (x_T - x*)``.

    Attributes
    ----------
    Q, R, Q_final : ndarray, shapes (n, n), (m, m), (n, n)
    goal : ndarray, shape (n,)
        ``x*``.
    """

    Q: Array
    R: Array
    Q_final: Array
    goal: Array

    @classmethod
    def make(cls, Q: ArrayLike, R: ArrayLike, Q_final: ArrayLike | None = None,
             goal: ArrayLike | None = None) -> QuadraticCost:
        """Checked: ``Q``, ``Q_final`` positive semi-definite, ``R`` positive definite;
        ``Q_final = Q`` and ``goal = 0`` when omitted."""
        n = as_square(Q, "Q").shape[0]
        q = as_cost_matrix(Q, "Q", n, definite=False)
        r = as_cost_matrix(R, "R", as_square(R, "R").shape[0], definite=True)
        qf = q if Q_final is None else as_cost_matrix(Q_final, "Q_final", n, definite=False)
        g = np.zeros(n) if goal is None else as_vector(goal, "goal", n)
        return cls(Q=q, R=r, Q_final=qf, goal=g)

    def total(self, x: Array, u: Array) -> float:
        """The cost of states ``x (T + 1, n)`` and controls ``u (T, m)``."""
        e = x - self.goal
        running = np.einsum("ti,ij,tj->", e[:-1], self.Q, e[:-1])
        effort = np.einsum("ti,ij,tj->", u, self.R, u)
        return float(running + effort + e[-1] @ self.Q_final @ e[-1])


@dataclass(frozen=True)
class ILQRResult:
    """What :func:`solve_ilqr` found and why it stopped.

    Attributes
    ----------
    x : ndarray, shape (T + 1, n)
        The states of the final controls, from ``x0``.
    u : ndarray, shape (T, m)
    k : ndarray, shape (T, m)
        The last backward pass's feed-forward terms.
    K : ndarray, shape (T, m, n)
        Its feedback gains: about the returned trajectory, ``u_t = u[t] - K[t] (x_t - x[t])``
        is the time-varying LQR that holds it (from the last accepted iteration's pass).
    cost : float
    cost_history : tuple of float
        The cost before the first iteration and after each accepted one: never increasing.
    iterations : int
        Backward passes run (accepted or not).
    converged : bool
        Whether it stopped at a (local) optimum rather than on a limit.
    reason : str
    mu : float
        The regularisation at the end.
    """

    x: Array
    u: Array
    k: Array
    K: Array
    cost: float
    cost_history: tuple[float, ...]
    iterations: int
    converged: bool
    reason: str
    mu: float


def rollout_open_loop(system: DiscreteSystem, x0: Array, u: Array) -> Array:
    """The states ``(T + 1, n)`` that controls ``u (T, m)`` reach from ``x0`` (open loop)."""
    x = np.empty((u.shape[0] + 1, x0.shape[0]))
    x[0] = x0
    for t in range(u.shape[0]):
        x[t + 1] = system.step(x[t], u[t])
    return x


@dataclass
class _Regularization:
    """Tassa et al.'s schedule for ``μ``: multiplied by a factor that itself grows while
    steps keep failing and shrinks while they keep succeeding."""

    mu: float
    mu_min: float = 1e-6
    mu_max: float = 1e10
    factor0: float = 2.0
    factor: float = field(default=1.0)

    def increase(self) -> None:
        self.factor = max(self.factor0, self.factor * self.factor0)
        self.mu = max(self.mu_min, self.mu * self.factor)

    def decrease(self) -> None:
        self.factor = min(1 / self.factor0, self.factor / self.factor0)
        self.mu = self.mu * self.factor if self.mu * self.factor > self.mu_min else 0.0


def backward_pass(A: Array, B: Array, x: Array, u: Array, cost: QuadraticCost,
                  mu: float) -> tuple[Array, Array, float, float] | None:
    """The feed-forward ``k (T, m)``, gains ``K (T, m, n)`` and the two terms of the
    predicted decrease, ``(Σ kᵀQ_u, Σ kᵀQ_uu k)``; ``None`` when some ``Q_uu`` is not
    positive definite (raise ``μ``).

    ``A (T, n, n)``, ``B (T, n, m)`` are the Jacobians along ``x (T + 1, n)``,
    ``u (T, m)``.
    """
    T, n, m = B.shape
    Q2, R2 = 2 * cost.Q, 2 * cost.R  # l_xx, l_uu of the lecture's cost (no ½)
    V_x = 2 * cost.Q_final @ (x[T] - cost.goal)
    V_xx = 2 * cost.Q_final
    k = np.empty((T, m))
    K = np.empty((T, m, n))
    linear = quadratic = 0.0
    eye = np.eye(n)
    for t in range(T - 1, -1, -1):
        a, b = A[t], B[t]
        Q_x = Q2 @ (x[t] - cost.goal) + a.T @ V_x
        Q_u = R2 @ u[t] + b.T @ V_x
        Q_xx = Q2 + a.T @ V_xx @ a
        Q_uu = R2 + b.T @ V_xx @ b
        Q_ux = b.T @ V_xx @ a
        V_reg = V_xx + mu * eye
        Q_uu_reg = R2 + b.T @ V_reg @ b
        Q_ux_reg = b.T @ V_reg @ a
        try:
            np.linalg.cholesky(Q_uu_reg)  # the test of positive definiteness
        except np.linalg.LinAlgError:
            return None
        both = np.linalg.solve(Q_uu_reg, np.concatenate([Q_u[:, None], Q_ux_reg], axis=1))
        k[t], K[t] = both[:, 0], both[:, 1:]
        # Tassa et al.'s eq. (11), with their k, K as our -k, -K.
        V_x = Q_x + K[t].T @ Q_uu @ k[t] - K[t].T @ Q_u - Q_ux.T @ k[t]
        V_xx = Q_xx + K[t].T @ Q_uu @ K[t] - K[t].T @ Q_ux - Q_ux.T @ K[t]
        V_xx = 0.5 * (V_xx + V_xx.T)
        linear += float(k[t] @ Q_u)
        quadratic += float(k[t] @ Q_uu @ k[t])
    return k, K, linear, quadratic


def _forward(system: DiscreteSystem, x: Array, u: Array, k: Array, K: Array,
             alpha: float) -> tuple[Array, Array] | None:
    """The new trajectory from ``x[0]``; ``None`` if it diverges (a state not finite)."""
    x_new = np.empty_like(x)
    u_new = np.empty_like(u)
    x_new[0] = x[0]
    with np.errstate(over="ignore", invalid="ignore"):
        for t in range(u.shape[0]):
            u_new[t] = u[t] - alpha * k[t] - K[t] @ (x_new[t] - x[t])
            if not np.all(np.isfinite(u_new[t])):
                return None
            x_new[t + 1] = system.step(x_new[t], u_new[t])
            if not np.all(np.isfinite(x_new[t + 1])):
                return None
    return x_new, u_new


def solve_ilqr(system: DiscreteSystem, x0: ArrayLike, u_init: ArrayLike, cost: QuadraticCost, *,
         max_iterations: int = 200, tol: float = 1e-7, mu0: float = 1.0,
         accept: float = 1e-4) -> ILQRResult:
    """Optimise the controls ``u (T, m)`` of ``system`` from ``x0`` for ``cost`` by iLQR.

    Parameters
    ----------
    system : DiscreteSystem
        Anything with ``step(x, u)`` and ``jacobians(x, u)`` (:mod:`course.control.systems`).
    x0 : array_like, shape (n,)
    u_init : array_like, shape (T, m)
        The first guess (zeros are fine for the pendulum).
    cost : QuadraticCost
    max_iterations : int
        Backward passes at most.
    tol : float
        Stop when an accepted step lowers the cost by less than ``tol`` times the cost, or
        the model predicts less than that.
    mu0 : float
        The initial regularisation ``μ``.
    accept : float
        The line search's ``c``: a step is taken when the actual decrease is at least ``c``
        times the predicted one.
    """
    n, m = system.n_states, system.n_controls
    x_start = as_vector(x0, "x0", n)
    u = as_matrix(u_init, "u_init", None, m).copy()
    if cost.Q.shape != (n, n) or cost.R.shape != (m, m):
        raise ValueError(f"cost: Q and R must be ({n}, {n}) and ({m}, {m}) for this system, "
                         f"got {cost.Q.shape} and {cost.R.shape}")
    limit = as_count(max_iterations, "max_iterations")
    tolerance = as_positive(tol, "tol")
    reg = _Regularization(mu=as_positive(mu0, "mu0", allow_zero=True))
    T = u.shape[0]
    x = rollout_open_loop(system, x_start, u)
    J = cost.total(x, u)
    history = [J]
    k = np.zeros((T, m))
    K = np.zeros((T, m, n))
    reason, converged, iteration = f"max_iterations ({limit}) reached", False, 0
    jacobians_stale = True
    A = np.empty((T, n, n))
    B = np.empty((T, n, m))
    for iteration in range(1, limit + 1):  # noqa: B007 (the count is reported)
        if jacobians_stale:
            for t in range(T):
                A[t], B[t] = system.jacobians(x[t], u[t])
            jacobians_stale = False
        passed = backward_pass(A, B, x, u, cost, reg.mu)
        if passed is None:
            reg.increase()
            if reg.mu > reg.mu_max:
                reason = f"mu passed mu_max ({reg.mu_max:.0e}): Q_uu stays indefinite"
                break
            continue
        k_new, K_new, linear, quadratic = passed
        if linear < tolerance * max(J, 1e-12) and reg.mu <= reg.mu_min:
            k, K = k_new, K_new
            reason = f"converged: predicted decrease {linear:.2e} below tol x cost"
            converged = True
            break
        for alpha in LINE_SEARCH:
            tried = _forward(system, x, u, k_new, K_new, alpha)
            if tried is None:
                continue
            x_try, u_try = tried
            with np.errstate(over="ignore", invalid="ignore"):
                J_try = cost.total(x_try, u_try)
            predicted = alpha * linear - 0.5 * alpha**2 * quadratic
            if np.isfinite(J_try) and J_try < J and (J - J_try) >= accept * predicted:
                break
        else:
            reg.increase()
            if reg.mu > reg.mu_max:
                reason = (f"mu passed mu_max ({reg.mu_max:.0e}): no step size lowered the "
                          "cost")
                break
            continue
        decrease = J - J_try
        x, u, J, k, K = x_try, u_try, J_try, k_new, K_new
        history.append(J)
        jacobians_stale = True
        reg.decrease()
        if decrease < tolerance * J:
            reason = f"converged: relative decrease {decrease / max(J, 1e-300):.2e} < tol"
            converged = True
            break
    return ILQRResult(x=x, u=u, k=k, K=K, cost=J, cost_history=tuple(history),
                      iterations=iteration, converged=converged, reason=reason, mu=reg.mu)


def pendulum_swing_up(pendulum: Pendulum | None = None, *, duration: float = 4.0,
                      effort: float = 1.0, final_weight: float = 100.0,
                      max_iterations: int = 200) -> ILQRResult:
    """The pendulum from hanging at rest (``θ = π``) to balanced on top (``θ = 0``) by iLQR,
    from zero torques.

    With the defaults (1 kg, 1 m, dt = 0.02 s, 4 s) it converges in about 60 iterations
    (about 2 s) to within 0.03 rad of the top, and the torque stays below 5 N m, half of
    the ``m g l`` that would lift the pendulum straight up: it pumps. A cheaper ``effort``
    (0.01) lifts it in one go with 30 N m.

    Cost: ``Σ dt (θ² + 0.1 ω²) + effort · dt · u²`` running, ``final_weight (θ² + ω²)`` at the
    end (the running weights scaled by ``dt`` so the cost does not depend on the step).
    """
    p = Pendulum() if pendulum is None else pendulum
    T = max(1, round(as_positive(duration, "duration") / p.dt))
    cost = QuadraticCost.make(Q=p.dt * np.diag([1.0, 0.1]),
                              R=[[as_positive(effort, "effort") * p.dt]],
                              Q_final=as_positive(final_weight, "final_weight") * np.eye(2))
    return solve_ilqr(p, [np.pi, 0.0], np.zeros((T, 1)), cost, max_iterations=max_iterations)
