r"""The linear–quadratic regulator 线性二次调节器 (LQR), by the Riccati recursion of GAMES105
lecture 12.

The problem, in the lecture's notation (no factor ½ anywhere)::

    x_{t+1} = A x_t + B u_t                          x: (n,) state, u: (m,) control
    J = Σ_{t=0}^{T-1} (x_tᵀ Q x_t + u_tᵀ R u_t) + x_Tᵀ Q_f x_T

Dynamic programming backwards from ``V_T(x) = xᵀ Q_f x``: if ``V_{t+1}(x) = xᵀ P_{t+1} x``,
then ``V_t(x) = min_u [xᵀQx + uᵀRu + (Ax + Bu)ᵀ P_{t+1} (Ax + Bu)]``, a quadratic in ``u``
whose minimiser is linear in ``x``::

    K_t = (R + Bᵀ P_{t+1} B)⁻¹ Bᵀ P_{t+1} A            (m, n)
    u_t = -K_t x_t                                     the sign: u = -K x, always
    P_t = Q + Aᵀ P_{t+1} A - Aᵀ P_{t+1} B (R + Bᵀ P_{t+1} B)⁻¹ Bᵀ P_{t+1} A

and ``V_t(x) = xᵀ P_t x`` again, so the recursion closes. The optimal cost from ``x_0`` is
``x_0ᵀ P_0 x_0``. Run long enough backwards, ``P_t`` stops changing: its fixed point solves
the discrete algebraic Riccati equation (DARE), ``P = Q + AᵀPA - AᵀPB (R + BᵀPB)⁻¹ BᵀPA``,
whose gain is the infinite-horizon LQR (:func:`lqr_infinite_horizon`, here by iterating the
recursion to convergence, step by step or doubling the steps each time for a fine time step;
``scipy.linalg.solve_discrete_are`` solves the same equation directly, and the tests check
they agree).

Shapes: ``A (n, n)``, ``B (n, m)``, ``Q (n, n)`` symmetric positive semi-definite, ``R (m, m)``
symmetric positive definite, ``K (m, n)``. A time-varying gain sequence is ``(T, m, n)``,
``K[t]`` applied at step ``t``; value matrices ``(T + 1, n, n)``, ``P[T] = Q_f``.
numpy only.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from ._checks import (
    as_cost_matrix,
    as_count,
    as_fraction,
    as_gain,
    as_matrix,
    as_square,
    as_vector,
    system_shapes,
)

#: A value matrix larger than this is taken as diverging (an unstabilisable system).
DIVERGED = 1e100

#: How :func:`lqr_infinite_horizon` runs the recursion: step by step, or doubling.
Method = Literal["iteration", "doubling"]
METHODS = ("iteration", "doubling")


def riccati_step(P_next: ArrayLike, A: ArrayLike, B: ArrayLike, Q: ArrayLike,
                 R: ArrayLike) -> tuple[Array, Array]:
    """One step of the Riccati recursion backwards in time: ``(P_t, K_t)`` from ``P_{t+1}``.

    ``K_t = (R + Bᵀ P_{t+1} B)⁻¹ Bᵀ P_{t+1} A`` and
    ``P_t = Q + Aᵀ P_{t+1} A - Aᵀ P_{t+1} B K_t`` (the lecture's formula, with the inverse
    applied as a linear solve), symmetrised against rounding.

    Parameters
    ----------
    P_next : array_like, shape (n, n)
        ``P_{t+1}``, the value matrix one step later (``Q_f`` at the horizon).
    A, B : array_like, shapes (n, n), (n, m)
    Q, R : array_like, shapes (n, n), (m, m)

    Returns
    -------
    P : ndarray, shape (n, n)
    K : ndarray, shape (m, n)
        The optimal control at step ``t`` is ``u_t = -K x_t``.
    """
    a, b = system_shapes(A, B)
    n, m = b.shape
    q = as_cost_matrix(Q, "Q", n, definite=False)
    r = as_cost_matrix(R, "R", m, definite=True)
    p = as_cost_matrix(P_next, "P_next", n, definite=False)
    return _riccati_step(p, a, b, q, r)


def _riccati_step(P: Array, A: Array, B: Array, Q: Array, R: Array) -> tuple[Array, Array]:
    PA = P @ A
    K = np.linalg.solve(R + B.T @ P @ B, B.T @ PA)
    P_new = Q + A.T @ PA - (B.T @ PA).T @ K  # A^T P B K = (B^T P A)^T K, P symmetric
    return 0.5 * (P_new + P_new.T), K


@dataclass(frozen=True)
class FiniteHorizonLQR:
    """The gains and value matrices of a finite-horizon LQR (:func:`lqr_finite_horizon`).

    Attributes
    ----------
    K : ndarray, shape (T, m, n)
        ``u_t = -K[t] x_t``.
    P : ndarray, shape (T + 1, n, n)
        ``V_t(x) = xᵀ P[t] x``, the optimal cost-to-go from step ``t``; ``P[T] = Q_f``.
    """

    K: Array
    P: Array

    @property
    def horizon(self) -> int:
        return int(self.K.shape[0])

    def cost(self, x0: ArrayLike) -> float:
        """The optimal cost ``x_0ᵀ P_0 x_0`` from the initial state ``x0`` (n,)."""
        x = as_vector(x0, "x0", self.P.shape[1])
        return float(x @ self.P[0] @ x)


def lqr_finite_horizon(A: ArrayLike, B: ArrayLike, Q: ArrayLike, R: ArrayLike, horizon: int,
                       Q_final: ArrayLike | None = None) -> FiniteHorizonLQR:
    """The optimal time-varying gains of the finite-horizon LQR, by the Riccati recursion
    from ``P_T = Q_final`` backwards.

    Parameters
    ----------
    A, B : array_like, shapes (n, n) and (n, m), or (T, n, n) and (T, n, m)
        The dynamics ``x_{t+1} = A x_t + B u_t``; a leading axis of length ``horizon`` makes
        them time-varying (``A[t]``, ``B[t]`` at step ``t``, as along a trajectory in iLQR).
    Q, R : array_like, shapes (n, n), (m, m)
        The running cost ``xᵀQx + uᵀRu``.
    horizon : int
        ``T``, the number of controls.
    Q_final : array_like, shape (n, n), optional
        The final cost ``x_Tᵀ Q_f x_T``; ``Q`` when omitted.
    """
    T = as_count(horizon, "horizon")
    As, Bs = _time_varying(A, B, T)
    n, m = Bs.shape[1:]
    q = as_cost_matrix(Q, "Q", n, definite=False)
    r = as_cost_matrix(R, "R", m, definite=True)
    qf = q if Q_final is None else as_cost_matrix(Q_final, "Q_final", n, definite=False)
    K = np.empty((T, m, n))
    P = np.empty((T + 1, n, n))
    P[T] = qf
    for t in range(T - 1, -1, -1):
        P[t], K[t] = _riccati_step(P[t + 1], As[t], Bs[t], q, r)
    return FiniteHorizonLQR(K=K, P=P)


def _time_varying(A: ArrayLike, B: ArrayLike, T: int) -> tuple[Array, Array]:
    """``A``, ``B`` as ``(T, n, n)``, ``(T, n, m)``: a constant pair repeated, or checked."""
    a, b = np.asarray(A), np.asarray(B)
    if a.ndim == 2 and b.ndim == 2:
        a2, b2 = system_shapes(a, b)
        return np.broadcast_to(a2, (T, *a2.shape)), np.broadcast_to(b2, (T, *b2.shape))
    if a.ndim != 3 or b.ndim != 3 or a.shape[0] != T or b.shape[0] != T:
        raise ValueError(f"A, B: expected (n, n) and (n, m), or ({T}, n, n) and ({T}, n, m) "
                         f"for a time-varying system of horizon {T}; got shapes {a.shape} "
                         f"and {b.shape}")
    for t in range(T):
        system_shapes(a[t], b[t])
    return a.astype(np.float64), b.astype(np.float64)


@dataclass(frozen=True)
class LQRResult:
    """The infinite-horizon LQR (:func:`lqr_infinite_horizon`) and how the iteration ended.

    Attributes
    ----------
    K : ndarray, shape (m, n)
        The stationary gain, ``u = -K x``.
    P : ndarray, shape (n, n)
        The fixed point of the Riccati recursion: the cost from ``x`` is ``xᵀ P x``.
    converged : bool
        Whether ``P`` stopped changing (relative change at most ``tol``).
    iterations : int
        Riccati steps taken.
    change : float
        The last step's largest change of ``P`` relative to ``max(1, max |P|)``.
    spectral_radius : float
        Of the closed loop ``A - B K`` (with the discount folded in, ``√γ (A - B K)``);
        below 1 when the gain stabilises the system.
    reason : str
        Why the iteration stopped, in words.
    """

    K: Array
    P: Array
    converged: bool
    iterations: int
    change: float
    spectral_radius: float
    reason: str


def lqr_infinite_horizon(A: ArrayLike, B: ArrayLike, Q: ArrayLike, R: ArrayLike, *,
                         discount: float = 1.0, tol: float = 1e-12,
                         max_iterations: int = 100_000,
                         P0: ArrayLike | None = None,
                         method: Method = "iteration") -> LQRResult:
    """The infinite-horizon LQR: the Riccati recursion iterated from ``P0`` (``Q`` when
    omitted) until ``P`` stops changing, the DARE's solution by fixed-point iteration.

    ``method="doubling"`` runs the same recursion from ``Q`` but doubles the number of steps
    each time (:func:`_doubling`): after ``k`` doubling steps ``P`` is the recursion's after
    ``2^k - 1`` steps, so a slow closed loop — a step of 1/600 s on a character, where the
    plain iteration needs ~10^4 steps — converges in a few dozen (``iterations`` then
    counts doubling steps; ``P0`` is not accepted).

    With a discount ``γ`` the cost is ``Σ γᵗ (xᵀQx + uᵀRu)``; since
    ``γᵗ xᵀQx = (γ^{t/2} x)ᵀ Q (γ^{t/2} x)``, that is the undiscounted problem of the system
    ``(√γ A, √γ B)``, which is what is solved (the gain is then
    ``(R/γ + BᵀPB)⁻¹ BᵀPA``).

    The iteration converges when ``(A, B)`` is stabilisable and ``Q`` sees every unstable
    mode, at the rate of the closed loop's spectral radius squared; it otherwise stops and
    says why in ``reason`` (``converged`` False) instead of raising: a value matrix that grows
    past 1e100 (no control keeps the cost finite), or ``max_iterations`` used up.

    Returns
    -------
    LQRResult
    """
    a, b = system_shapes(A, B)
    n, m = b.shape
    q = as_cost_matrix(Q, "Q", n, definite=False)
    r = as_cost_matrix(R, "R", m, definite=True)
    gamma = as_fraction(discount, "discount")
    limit = as_count(max_iterations, "max_iterations")
    if not (isinstance(tol, (int, float)) and tol > 0):
        raise ValueError(f"tol: expected a positive number, got {tol!r}")
    a, b = np.sqrt(gamma) * a, np.sqrt(gamma) * b
    if method == "doubling":
        if P0 is not None:
            raise ValueError("P0: the doubling method starts from Q (its steps are the "
                             "recursion's from P = Q); pass method='iteration' to give P0")
        return _doubling(a, b, q, r, tol, limit)
    if method != "iteration":
        raise ValueError(f"method: expected one of {METHODS}, got {method!r}")
    P = q.copy() if P0 is None else as_cost_matrix(P0, "P0", n, definite=False)
    K = np.zeros((m, n))
    change, reason, converged = float("inf"), "", False
    iteration = 0
    for iteration in range(1, limit + 1):
        P_new, K = _riccati_step(P, a, b, q, r)
        step_change, P = _relative_change(P_new, P), P_new
        if step_change is None:
            reason = (f"diverged: max |P| passed {DIVERGED:.0e} after {iteration} steps; no "
                      "gain keeps the cost finite ((A, B) not stabilisable on a mode Q "
                      "penalises, or the discount too close to 1 for it)")
            break
        change = step_change
        if change <= tol:
            converged = True
            reason = f"converged: relative change of P {change:.1e} <= tol {tol:.0e}"
            break
    else:
        reason = (f"not converged: {limit} steps used, relative change of P still {change:.1e}"
                  f" > tol {tol:.0e} (a slow closed loop converges slowly: raise "
                  "max_iterations)")
    return LQRResult(K=K, P=P, converged=converged, iterations=iteration, change=change,
                     spectral_radius=_radius(a, b, K), reason=reason)


def _relative_change(new: Array, old: Array) -> float | None:
    """``max |new - old| / max(1, max |new|)``, the stopping test of both infinite-horizon
    iterations; None once ``new`` is not finite or passed :data:`DIVERGED`."""
    size = float(np.max(np.abs(new)))
    if not np.isfinite(size) or size > DIVERGED:
        return None
    return float(np.max(np.abs(new - old))) / max(1.0, size)


def _radius(A: Array, B: Array, K: Array) -> float:
    """The closed loop's spectral radius, ``max |eig(A - B K)|`` (inf for a non-finite K)."""
    if not np.all(np.isfinite(K)):
        return float("inf")
    return float(np.max(np.abs(np.linalg.eigvals(A - B @ K))))


def _doubling(A: Array, B: Array, Q: Array, R: Array, tol: float,
              limit: int) -> LQRResult:
    """The doubling algorithm for the DARE, in its structure-preserving form (SDA).

    With ``A_0 = A``, ``G_0 = B R⁻¹ Bᵀ``, ``H_0 = Q`` and ``W_k = I + G_k H_k``::

        A_{k+1} = A_k W_k⁻¹ A_k
        G_{k+1} = G_k + A_k W_k⁻¹ G_k A_kᵀ
        H_{k+1} = H_k + A_kᵀ H_k W_k⁻¹ A_k

    ``H_k`` is the Riccati recursion's ``P`` after ``2^k - 1`` steps from ``P = Q`` (the
    tests check it against :func:`riccati_step`), so it converges to the same fixed point,
    quadratically. The gain is one last :func:`riccati_step` from it.
    """
    n = A.shape[0]
    eye = np.eye(n)
    Ak, G, H = A.copy(), B @ np.linalg.solve(R, B.T), Q.copy()
    change, reason, converged, k = float("inf"), "", False, 0
    for k in range(1, limit + 1):
        W = eye + G @ H
        WA = np.linalg.solve(W, Ak)
        H_new = H + Ak.T @ H @ WA
        G = G + Ak @ np.linalg.solve(W, G) @ Ak.T
        Ak = Ak @ WA
        H_new = 0.5 * (H_new + H_new.T)
        step_change, H = _relative_change(H_new, H), H_new
        if step_change is None:
            reason = (f"diverged: max |P| passed {DIVERGED:.0e} after {k} doubling steps "
                      "(2^k - 1 Riccati steps); no gain keeps the cost finite ((A, B) not "
                      "stabilisable on a mode Q penalises)")
            break
        change = step_change
        if change <= tol:
            converged = True
            reason = (f"converged: relative change of P {change:.1e} <= tol {tol:.0e} after "
                      f"{k} doubling steps ({2**k - 1} Riccati steps)")
            break
    else:
        reason = (f"not converged: {limit} doubling steps used, relative change of P still "
                  f"{change:.1e} > tol {tol:.0e}")
    if not np.all(np.isfinite(H)):
        K = np.full((B.shape[1], n), np.nan)
        return LQRResult(K=K, P=H, converged=False, iterations=k, change=change,
                         spectral_radius=float("inf"), reason=reason)
    _, K = _riccati_step(H, A, B, Q, R)
    return LQRResult(K=K, P=H, converged=converged, iterations=k, change=change,
                     spectral_radius=_radius(A, B, K), reason=reason)


def gain_value_matrices(A: ArrayLike, B: ArrayLike, Q: ArrayLike, R: ArrayLike,
                        K: ArrayLike, horizon: int, Q_final: ArrayLike | None = None, *,
                        discount: float = 1.0) -> Array:
    """The cost-to-go matrices of *a given* linear policy ``u = -K x`` (policy evaluation,
    no minimisation): ``P_T = Q_f`` and, backwards,
    ``P_t = Q + KᵀRK + γ (A - BK)ᵀ P_{t+1} (A - BK)``, so the cost of the policy from ``x``
    at step ``t`` is ``xᵀ P_t x`` (the discount ``γ`` counted from step ``t``). For the
    optimal gains these are the Riccati recursion's ``P``.

    Parameters
    ----------
    K : array_like, shape (m, n) or (T, m, n)
        One gain for every step, or one per step.

    Returns
    -------
    ndarray, shape (T + 1, n, n)
    """
    a, b = system_shapes(A, B)
    n, m = b.shape
    T = as_count(horizon, "horizon")
    q = as_cost_matrix(Q, "Q", n, definite=False)
    r = as_cost_matrix(R, "R", m, definite=False)
    qf = q if Q_final is None else as_cost_matrix(Q_final, "Q_final", n, definite=False)
    gamma = as_fraction(discount, "discount")
    Ks = _gains(K, m, n, T)
    P = np.empty((T + 1, n, n))
    P[T] = qf
    for t in range(T - 1, -1, -1):
        closed = a - b @ Ks[t]
        P_t = q + Ks[t].T @ r @ Ks[t] + gamma * closed.T @ P[t + 1] @ closed
        P[t] = 0.5 * (P_t + P_t.T)
    return P


def _gains(K: ArrayLike, m: int, n: int, T: int) -> Array:
    k = np.asarray(K)
    if k.ndim == 2:
        return np.broadcast_to(as_gain(k, "K", m, n), (T, m, n))
    if k.shape != (T, m, n):
        raise ValueError(f"K: expected a gain of shape ({m}, {n}) (u = -K x, {m} control(s) "
                         f"by {n} states) or one per step ({T}, {m}, {n}); got shape {k.shape}")
    return as_matrix(k.reshape(T * m, n), "K", T * m, n).reshape(T, m, n)


def rollout_linear(A: ArrayLike, B: ArrayLike, K: ArrayLike, x0: ArrayLike,
                   horizon: int) -> tuple[Array, Array]:
    """The closed loop ``x_{t+1} = A x_t + B u_t`` with ``u_t = -K_t x_t`` from ``x0``.

    Returns
    -------
    x : ndarray, shape (T + 1, n)
    u : ndarray, shape (T, m)
    """
    a, b = system_shapes(A, B)
    n, m = b.shape
    T = as_count(horizon, "horizon")
    Ks = _gains(K, m, n, T)
    x = np.empty((T + 1, n))
    u = np.empty((T, m))
    x[0] = as_vector(x0, "x0", n)
    for t in range(T):
        u[t] = -Ks[t] @ x[t]
        x[t + 1] = a @ x[t] + b @ u[t]
    return x, u


def quadratic_cost(x: ArrayLike, u: ArrayLike, Q: ArrayLike, R: ArrayLike,
                   Q_final: ArrayLike | None = None) -> float:
    """``Σ_{t<T} (x_tᵀQx_t + u_tᵀRu_t) + x_Tᵀ Q_f x_T`` of a trajectory ``x (T + 1, n)``,
    ``u (T, m)`` (``Q_f = Q`` when omitted)."""
    xs = as_matrix(x, "x")
    n = xs.shape[1]
    us = as_matrix(u, "u", xs.shape[0] - 1)
    m = us.shape[1]
    q = as_square(Q, "Q", n)
    r = as_square(R, "R", m)
    qf = q if Q_final is None else as_square(Q_final, "Q_final", n)
    running = np.einsum("ti,ij,tj->", xs[:-1], q, xs[:-1]) + np.einsum("ti,ij,tj->", us, r, us)
    return float(running + xs[-1] @ qf @ xs[-1])
