"""Notebook 16 · optimal control and learning: one step of the Riccati recursion, the
REINFORCE estimate of the gradient of a linear-Gaussian policy (baseline and discount), and
the discounted cost of an episode (the discount's effect)."""

from __future__ import annotations

import numpy as np

from autograder.checks import Check
from autograder.spec import Case, Function, Misconception

from .spec import Exercise

Arr = np.ndarray


def riccati_step(P_next: np.ndarray, A: np.ndarray, B: np.ndarray, Q: np.ndarray,
                 R: np.ndarray) -> np.ndarray:
    r"""Reference of 16.riccati_step: :math:`P_t` from :math:`P_{t+1}`, the lecture's step
    with no factor ½ and the gain's sign :math:`u = -Kx`:
    :math:`K = (R + B^\top P_{t+1} B)^{-1} B^\top P_{t+1} A` (m x n) and
    :math:`P_t = Q + A^\top P_{t+1} A - A^\top P_{t+1} B K`."""
    P, A, B = (np.asarray(v, dtype=float) for v in (P_next, A, B))
    K = np.linalg.solve(np.asarray(R, dtype=float) + B.T @ P @ B, B.T @ P @ A)
    P_t = np.asarray(Q, dtype=float) + A.T @ P @ A - A.T @ P @ B @ K
    return np.asarray(0.5 * (P_t + P_t.T), dtype=float)


def costs_to_go(cost: np.ndarray, final_cost: np.ndarray, gamma: float) -> np.ndarray:
    """``G_t = Σ_{t≤s<T} γ^{s-t} c_s + γ^{T-t} c_T`` for each episode, ``(N, T)``."""
    c = np.asarray(cost, dtype=float)
    G = np.empty_like(c)
    running = np.asarray(final_cost, dtype=float).copy()
    for t in range(c.shape[1] - 1, -1, -1):
        running = c[:, t] + gamma * running
        G[:, t] = running
    return G


def _score(x: np.ndarray, u: np.ndarray, K: np.ndarray, sigma: float) -> np.ndarray:
    """``∇_K log π(u_t | x_t) = -(u_t + K x_t) x_tᵀ / σ²`` for every episode and step,
    ``(N, T, m, n)``."""
    xs = np.asarray(x, dtype=float)[:, :-1]
    e = np.asarray(u, dtype=float) + xs @ np.asarray(K, dtype=float).T
    return np.asarray(-(e[..., :, None] * xs[..., None, :]) / sigma**2)


def _estimate(score: np.ndarray, G: np.ndarray, gamma: float, *, baseline: bool = True,
              weight_discount: bool = True) -> np.ndarray:
    N, T = G.shape
    if baseline:
        G = G - (G.sum(0, keepdims=True) - G) / (N - 1)
    w = (gamma ** np.arange(T) if weight_discount else np.ones(T)) * G
    return np.asarray((score * w[:, :, None, None]).sum(1).mean(0), dtype=float)


def reinforce_gradient(x: np.ndarray, u: np.ndarray, cost: np.ndarray,
                       final_cost: np.ndarray, K: np.ndarray, sigma: float,
                       gamma: float) -> np.ndarray:
    r"""Reference of 16.reinforce_gradient: the REINFORCE estimate of :math:`\nabla_K J`
    (m x n) from ``N`` episodes of the policy :math:`u \sim \mathcal N(-Kx, \sigma^2 I)`:
    the mean over episodes of
    :math:`\sum_t \gamma^t\, \nabla_K \log\pi(u_t|x_t)\, (G_t - b_t)`, the score
    :math:`-(u_t + Kx_t)x_t^\top/\sigma^2`, :math:`G_t` the cost-to-go discounted *from t*
    and :math:`b_t` the mean :math:`G_t` of the *other* episodes (leave-one-out)."""
    G = costs_to_go(cost, final_cost, gamma)
    return _estimate(_score(x, u, K, sigma), G, gamma)


def discounted_cost(cost: np.ndarray, final_cost: np.ndarray, gamma: float) -> np.ndarray:
    r"""Reference of 16.discounted_cost: each episode's discounted cost
    :math:`J = \sum_{t=0}^{T-1} \gamma^t c_t + \gamma^T c_T`, ``(N,)``, from the running costs
    ``cost (N, T)`` (step ``t`` weighed :math:`\gamma^t`, the first step 1) and the cost of
    the last state ``final_cost (N,)`` (:math:`\gamma^T`, one step after the last control)."""
    return _discounted(cost, final_cost, gamma)


def _discounted(cost: Arr, final_cost: Arr, gamma: float, *, first: int = 0, power: int = 1,
                final_step: int | None = None) -> Arr:
    """``Σ_t γ^(power (t + first)) c_t + γ^(power final_step) c_T`` (``final_step``
    defaults to ``T + first``): the reference and its mistakes."""
    c = np.asarray(cost, dtype=float)
    T = c.shape[1]
    last = T + first if final_step is None else final_step
    weights = float(gamma) ** (power * (np.arange(T) + first))
    final = float(gamma) ** (power * last) * np.asarray(final_cost, dtype=float)
    return np.asarray((c * weights).sum(1) + final, dtype=float)


# -- mistakes ---------------------------------------------------------------------------------


def _parts(P_next: Arr, A: Arr, B: Arr, R: Arr) -> tuple[Arr, Arr, Arr, Arr]:
    P, A, B = (np.asarray(v, dtype=float) for v in (P_next, A, B))
    return P, A, B, np.linalg.solve(np.asarray(R, dtype=float) + B.T @ P @ B, B.T @ P @ A)


def _transposed_gain(P_next: Arr, A: Arr, B: Arr, Q: Arr, R: Arr) -> Arr:
    P, A, B, K = _parts(P_next, A, B, R)
    return np.asarray(np.asarray(Q, dtype=float) + A.T @ P @ A - A.T @ P @ B @ K.T)


def _sign_of_k(P_next: Arr, A: Arr, B: Arr, Q: Arr, R: Arr) -> Arr:
    P, A, B, K = _parts(P_next, A, B, R)
    return np.asarray(np.asarray(Q, dtype=float) + A.T @ P @ A + A.T @ P @ B @ K)


def _not_square(P_next: Arr, A: Arr, B: Arr, Q: Arr, R: Arr) -> bool:
    return bool(np.shape(A)[0] != np.shape(B)[1])


def _discounted_from_zero(x: Arr, u: Arr, cost: Arr, final_cost: Arr, K: Arr, sigma: float,
                          gamma: float) -> Arr:
    T = np.shape(cost)[1]
    G = costs_to_go(cost, final_cost, gamma) * gamma ** np.arange(T)  # γ^s, not γ^{s-t}
    return _estimate(_score(x, u, K, sigma), G, gamma)


def _whole_return(x: Arr, u: Arr, cost: Arr, final_cost: Arr, K: Arr, sigma: float,
                  gamma: float) -> Arr:
    G = costs_to_go(cost, final_cost, gamma)
    G0 = np.broadcast_to(G[:, :1], G.shape).copy()  # every step weighed by the episode's G_0
    return _estimate(_score(x, u, K, sigma), G0, gamma)


# -- cases ------------------------------------------------------------------------------------


def _system(rng: np.random.Generator, n: int, m: int) -> tuple[np.ndarray, ...]:
    A = np.round(np.eye(n) + rng.normal(scale=0.3, size=(n, n)), 2)
    B = np.round(rng.normal(size=(n, m)), 2)
    L = rng.normal(size=(n, n))
    Q = np.round(L @ L.T + 0.1 * np.eye(n), 2)
    M = rng.normal(size=(m, m))
    R = np.round(M @ M.T + 0.5 * np.eye(m), 2)
    S = rng.normal(size=(n, n))
    P = np.round(S @ S.T + np.eye(n), 2)
    return P, A, B, Q, R


def _riccati_cases(rng: np.random.Generator) -> list[Case]:
    h = 0.1
    A = np.array([[1.0, h], [0.0, 1.0]])
    B = np.array([[h * h / 2], [h]])
    cases = [
        Case("double integrator, dt = 0.1 s, from P = Q = I, R = 1",
             (np.eye(2), A, B, np.eye(2), np.array([[1.0]]))),
        Case("a scalar system: x⁺ = 1.2 x + 0.5 u, q = 1, r = 2, P_next = 3",
             (np.array([[3.0]]), np.array([[1.2]]), np.array([[0.5]]), np.array([[1.0]]),
              np.array([[2.0]]))),
    ]
    for n, m in ((2, 2), (3, 3), (3, 1)):
        cases.append(Case(f"a random system, {n} states, {m} control(s)", _system(rng, n, m)))
    return cases


def _rollouts(rng: np.random.Generator, N: int, T: int, gamma: float) -> tuple[object, ...]:
    h = 0.1
    A = np.array([[1.0, h], [0.0, 1.0]])
    B = np.array([[h * h / 2], [h]])
    K = np.round(rng.uniform([0.2, 0.5], [1.5, 2.0]), 2)[None, :]
    sigma = 0.5
    x = np.empty((N, T + 1, 2))
    u = np.empty((N, T, 1))
    x[:, 0] = np.round(rng.normal(size=(N, 2)), 2)
    for t in range(T):
        u[:, t] = np.round(-x[:, t] @ K.T + sigma * rng.normal(size=(N, 1)), 3)
        x[:, t + 1] = x[:, t] @ A.T + u[:, t] @ B.T
    cost = (x[:, :-1] ** 2).sum(-1) + (u**2).sum(-1)
    final = 5.0 * (x[:, -1] ** 2).sum(-1)
    return (x, u, cost, final, K, sigma, gamma)


def _discount_cases(rng: np.random.Generator) -> list[Case]:
    def episodes(N: int, T: int) -> tuple[Arr, Arr]:
        return (np.round(rng.uniform(0.5, 3.0, (N, T)), 2),
                np.round(rng.uniform(1.0, 10.0, N), 2))

    return [Case("one episode of 3 steps, costs 1, 1, 1 and final cost 1, γ = 0.5",
                 (np.ones((1, 3)), np.ones(1), 0.5)),
            Case("4 episodes of 5 steps, γ = 0.9", (*episodes(4, 5), 0.9)),
            Case("3 episodes of 10 steps, γ = 0.7", (*episodes(3, 10), 0.7)),
            Case("2 episodes of 4 steps, no discount (γ = 1)", (*episodes(2, 4), 1.0))]


def _reinforce_cases(rng: np.random.Generator) -> list[Case]:
    return [Case("4 episodes of 3 steps on the double integrator, γ = 0.9",
                 _rollouts(rng, 4, 3, 0.9)),
            Case("6 episodes of 5 steps, γ = 0.8", _rollouts(rng, 6, 5, 0.8)),
            Case("5 episodes of 4 steps, no discount (γ = 1)", _rollouts(rng, 5, 4, 1.0))]


EXERCISES = (
    Exercise(
        "riccati_step",
        Function("riccati_step", ("P_next", "A", "B", "Q", "R"), riccati_step,
                 Check(None, atol=1e-8, rtol=1e-8, noun="value matrix")),
        _riccati_cases,
        hint="Minimise xᵀQx + uᵀRu + (Ax + Bu)ᵀ P_next (Ax + Bu) over u: set the gradient "
             "in u to zero, write the minimiser as u = −K x, and put it back: what is left is "
             "xᵀ P_t x. Use np.linalg.solve rather than an inverse.",
        formula="K = np.linalg.solve(R + B.T @ P_next @ B, B.T @ P_next @ A)  (m × n); "
                "P_t = Q + A.T @ P_next @ A − A.T @ P_next @ B @ K.",
        mistakes=(
            Misconception("transposed_gain", "riccati_step",
                          "the gain transposed (n × m) in P's update",
                          "K = (R + BᵀPB)⁻¹BᵀPA has one row per control and one column per "
                          "state (m × n), and enters as AᵀPB K: (n × m)(m × n).",
                          wrong=_transposed_gain, undefined=_not_square),
            Misconception("sign_of_k", "riccati_step", "the sign of K: + AᵀPBK",
                          "u = −Kx puts a minus in front of the gain: P_t = Q + AᵀPA − AᵀPBK "
                          "(the control lowers the cost-to-go; + would raise it).",
                          wrong=_sign_of_k),
            Misconception("q_r_swapped", "riccati_step", "Q and R swapped",
                          "R weighs the controls, so it sits beside BᵀPB (m × m) inside the "
                          "inverse; Q weighs the states and is added to P (n × n).",
                          wrong=lambda P, A, B, Q, R: riccati_step(P, A, B, R, Q),
                          undefined=_not_square),
            Misconception("no_q", "riccati_step", "the running cost Q left out of P_t",
                          "P_t is the cost of this step plus the cost-to-go from the next: "
                          "Q + AᵀPA − AᵀPBK, not AᵀPA − AᵀPBK.",
                          wrong=lambda P, A, B, Q, R: riccati_step(P, A, B, 0 * Q, R)),
        ),
    ),
    Exercise(
        "reinforce_gradient",
        Function("reinforce_gradient",
                 ("x", "u", "cost", "final_cost", "K", "sigma", "gamma"), reinforce_gradient,
                 Check(None, atol=1e-8, rtol=1e-8, noun="gradient")),
        _reinforce_cases,
        hint="Three pieces: the score of each control, −(u_t + K x_t) x_tᵀ / σ² (m × n); the "
             "cost-to-go G_t from step t on, discounted from t (a loop backwards from the "
             "final cost); and the baseline, the mean G_t of the other episodes. Weigh each "
             "score by γᵗ (G_t − b_t), sum over t, average over episodes.",
        formula="G[:, T−1] = cost[:, T−1] + γ final_cost; G[:, t] = cost[:, t] + γ G[:, t+1]; "
                "b = (G.sum(0) − G)/(N − 1); e = u + x[:, :−1] @ K.T; "
                "score = −e[..., :, None] * x[:, :−1, None, :] / σ²; "
                "grad = (score * (γ**t (G − b))[:, :, None, None]).sum(1).mean(0).",
        mistakes=(
            Misconception("missing_baseline", "reinforce_gradient",
                          "the baseline left out",
                          "Without b_t the estimate is still unbiased but far noisier; "
                          "subtract the mean G_t of the other episodes (leave-one-out, so it "
                          "does not depend on the episode it is subtracted from).",
                          wrong=lambda x, u, c, f, K, s, g: _estimate(
                              _score(x, u, K, s), costs_to_go(c, f, g), g, baseline=False)),
            Misconception("discount_twice", "reinforce_gradient",
                          "the discount applied twice (G_t discounted from 0, then γᵗ again)",
                          "γᵗ in front already brings step t back to time 0; G_t must be "
                          "discounted from t, Σ_s γ^(s−t) c_s, or each term carries γ^(2t).",
                          wrong=_discounted_from_zero),
            Misconception("no_weight_discount", "reinforce_gradient",
                          "γᵗ in front of the score left out",
                          "The objective is Σ_t γᵗ c_t: a control at step t counts γᵗ times, "
                          "so its term is γᵗ ∇log π (G_t − b_t).",
                          wrong=lambda x, u, c, f, K, s, g: _estimate(
                              _score(x, u, K, s), costs_to_go(c, f, g), g,
                              weight_discount=False)),
            Misconception("whole_return", "reinforce_gradient",
                          "the whole return G_0 for every step, not the cost-to-go",
                          "A control at t cannot change the costs before t: only the "
                          "cost-to-go G_t multiplies its score (causality), which also lowers "
                          "the variance.",
                          wrong=_whole_return),
            Misconception("score_sign", "reinforce_gradient",
                          "the score of N(+Kx, σ²): −(u − Kx) xᵀ/σ²",
                          "The mean control is −Kx (u = −Kx, LQR's sign), so the noise is "
                          "u + Kx and ∇_K log π = −(u + Kx) xᵀ / σ².",
                          wrong=lambda x, u, c, f, K, s, g: _estimate(
                              _score(x, u, -np.asarray(K), s), costs_to_go(c, f, g), g)),
        ),
    ),
    Exercise(
        "discounted_cost",
        Function("discounted_cost", ("cost", "final_cost", "gamma"), discounted_cost,
                 Check(None, atol=1e-9, rtol=1e-9, noun="discounted cost")),
        _discount_cases,
        hint="The first step counts fully (γ⁰ = 1), each later step γ times less than the one "
             "before; the final cost belongs to the state after the last control, x_T, one "
             "step after step T − 1. One weight per step, then a sum along each episode.",
        formula="T = cost.shape[1]; J = (cost * gamma ** np.arange(T)).sum(axis=1) "
                "+ gamma ** T * final_cost.",
        mistakes=(
            Misconception("discount_twice", "discounted_cost",
                          "the discount applied twice: γ^(2t)",
                          "Each step is discounted once, by γᵗ; weighing by γᵗ a cost that "
                          "already carries γᵗ (or squaring the weight) discounts it as if "
                          "with γ².",
                          wrong=lambda c, f, g: _discounted(c, f, g, power=2)),
            Misconception("from_one", "discounted_cost",
                          "γᵗ from the wrong start: the first step weighed γ, not 1",
                          "The sum starts at t = 0 with γ⁰ = 1: the first cost is not "
                          "discounted (np.arange(T), not np.arange(1, T + 1)).",
                          wrong=lambda c, f, g: _discounted(c, f, g, first=1)),
            Misconception("from_the_end", "discounted_cost",
                          "γᵗ counted from the end of the episode: γ^(T−t)",
                          "The discount looks ahead from the start: the *first* step counts "
                          "fully and the late ones less (reversing the weights makes the "
                          "controller care most about the end).",
                          wrong=lambda c, f, g: _discounted(np.asarray(c)[:, ::-1], f, g,
                                                            first=1, final_step=0)),
            Misconception("final_undiscounted", "discounted_cost",
                          "the final cost left undiscounted",
                          "c_T is paid at step T, after T steps: it is weighed γ^T like every "
                          "other cost is weighed by its step.",
                          wrong=lambda c, f, g: _discounted(c, f, g, final_step=0)),
            Misconception("final_one_step_short", "discounted_cost",
                          "the final cost weighed γ^(T−1), as the last running cost",
                          "The last control is at step T − 1 and the state it leads to, x_T, "
                          "at step T: its cost carries γ^T.",
                          wrong=lambda c, f, g: _discounted(c, f, g,
                                                            final_step=np.shape(c)[1] - 1)),
            Misconception("no_final_cost", "discounted_cost", "the final cost left out",
                          "The episode's cost includes the cost of the state it ends in, "
                          "γ^T c_T (the LQR's x_Tᵀ Q_f x_T).",
                          wrong=lambda c, f, g: _discounted(c, 0 * np.asarray(f), g)),
            Misconception("no_discount", "discounted_cost", "no discount: a plain sum",
                          "With γ < 1 step t counts γᵗ: the weights fall geometrically, "
                          "and a cost 1/(1 − γ) steps away counts about e⁻¹ ≈ 0.37 of the first.",
                          wrong=lambda c, f, g: _discounted(c, f, 1.0)),
        ),
    ),
)
