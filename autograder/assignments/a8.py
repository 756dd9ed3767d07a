r"""Assignment a8, optimal control and learning: the spec ``assignments/a8_optimal_control.py``
is checked by.

* ``riccati_step`` is one backward step of the discrete Riccati recursion, compared with
  :func:`course.control.lqr.riccati_step` (the lecture's convention: no factor ½, ``u = -K x``):
  :math:`K = (R + B^\top P B)^{-1} B^\top P A` and :math:`P_t = Q + A^\top P (A - BK)`,
  returned as ``(P, K)``.
* ``lqr_gain`` is the infinite-horizon gain, the recursion iterated until :math:`P` stops
  changing, compared with :func:`course.control.lqr.lqr_infinite_horizon` (the tests also with
  ``scipy.linalg.solve_discrete_are``), and judged by what it does: it must hold a cart-pole
  (:class:`course.control.systems.CartPole`, the nonlinear one) up after a push.
* ``reinforce_gradient`` is the REINFORCE estimate of :math:`\nabla_K J` for the policy
  :math:`u \sim \mathcal N(-Kx, \sigma^2 I)` with the leave-one-out mean baseline, compared
  with :func:`course.control.policy_gradient.reinforce_gradient` on fixed batches; then called
  on many seeded batches, whose estimates must average to the exact gradient
  (:meth:`~course.control.policy_gradient.LQTask.gradient`) and scatter no more than the
  reference's; then used by the grader's own training loop (Adam, as
  :func:`~course.control.policy_gradient.train_reinforce` has it), whose policy must reach
  within 10 % of LQR's cost.

The mistakes students make each give one definite wrong answer (or, for the sign of the
gain and an iteration stopped early, a definite symptom), so the catalogue writes them as
functions of the arguments.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from course.control.lqr import lqr_infinite_horizon, riccati_step
from course.control.policy_gradient import (
    LinearGaussianPolicy,
    LQTask,
    Rollouts,
    sample_rollouts,
)
from course.control.policy_gradient import reinforce_gradient as library_reinforce
from course.control.systems import CartPole, double_integrator, linear_inverted_pendulum

from ..checks import Check, TupleCheck, show
from ..spec import (
    Assignment,
    Case,
    Function,
    Misconception,
    Rollout,
    Run,
    Test,
    random_edge_hidden,
)

Arr = np.ndarray

# --- the Riccati step --------------------------------------------------------------------------


def riccati_reference(P_next: Arr, A: Arr, B: Arr, Q: Arr, R: Arr) -> tuple[Arr, Arr]:
    """The library's step: ``(P_t, K_t)``."""
    return riccati_step(P_next, A, B, Q, R)


def riccati_formula(P_next: Arr, A: Arr, B: Arr, Q: Arr, R: Arr, *, gain: str = "right",
                    feedback: bool = True, swap: bool = False) -> tuple[Arr, Arr]:
    r"""The step written out, and as students get it wrong: ``gain="transposed"`` takes
    :math:`K^\top = A^\top P B (R + B^\top P B)^{-1}` (n x m) for the gain, in P's update too;
    ``feedback=False`` updates :math:`P_t = Q + A^\top P A` (the :math:`-A^\top P B K` left
    out); ``swap`` puts Q where R goes and R where Q goes."""
    P, A, B, Q, R = (np.asarray(v, dtype=float) for v in (P_next, A, B, Q, R))
    if swap:
        Q, R = R, Q
    K = np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
    if gain == "transposed":
        K = K.T
    P_t = Q + A.T @ P @ A - (A.T @ P @ B @ K if feedback else 0.0)
    return 0.5 * (P_t + P_t.T), K


def _square(P_next: Arr, A: Arr, B: Arr, *_: Any) -> bool:
    """Whether B is square (as many controls as states): only there do Kᵀ and a swapped Q
    and R have the shapes a step needs."""
    return bool(np.shape(A)[0] == np.shape(B)[1])


def _not_square(*args: Any) -> bool:
    return not _square(*args)


def _gain_shape_error(error: dict[str, Any], P_next: Arr, A: Arr, B: Arr, *_: Any) -> str | None:
    """A matmul that fails on a non-square B: what a gain of shape (n, m) does in AᵀPB K."""
    if error.get("type") != "ValueError" or "matmul" not in str(error.get("message", "")):
        return None
    n, m = np.shape(B)
    if n == m:
        return None
    return (f"here B is ({n}, {m}), so K must be ({m}, {n}), one row per control; a gain of "
            f"shape ({n}, {m}) leaves AᵀPB K undefined")


def _cost_shape_error(error: dict[str, Any], P_next: Arr, A: Arr, B: Arr, *_: Any
                      ) -> str | None:
    """Q (n x n) where R (m x m) belongs: a sum or a solve of sizes that do not fit."""
    message = str(error.get("message", ""))
    if error.get("type") != "ValueError" or not ("broadcast" in message or "solve" in message):
        return None
    n, m = np.shape(B)
    if n == m:
        return None
    return (f"R + BᵀPB is ({m}, {m}) here and Q is ({n}, {n}): the matrix beside BᵀPB must be "
            "R, the control's weight")


def _gain_negated(got: Any, *args: Any) -> bool:
    """The gain is the reference's with its sign flipped (whatever P is)."""
    K = riccati_reference(*args)[1]
    return bool(np.abs(K).max() > 1e-9 and np.allclose(got[1], -K, rtol=1e-6, atol=1e-9))


def _system(rng: np.random.Generator, n: int, m: int) -> tuple[Arr, Arr, Arr, Arr, Arr]:
    """``(P_next, A, B, Q, R)``: a random system and costs (Q PSD, R PD, P_next PSD)."""
    A = np.eye(n) + rng.normal(scale=0.3, size=(n, n))
    B = rng.normal(size=(n, m))
    L = rng.normal(size=(n, n))
    M = rng.normal(size=(m, m))
    S = rng.normal(size=(n, n))
    return (S @ S.T + np.eye(n), A, B, L @ L.T + 0.1 * np.eye(n), M @ M.T + 0.5 * np.eye(m))


def _double_integrator(dt: float = 0.1) -> tuple[Arr, Arr]:
    system = double_integrator(dt)
    return system.A, system.B


def riccati_random(rng: np.random.Generator) -> list[Case]:
    return [Case(f"a random system, {n} states, {m} control(s)", _system(rng, n, m))
            for n, m in ((2, 1), (2, 2), (3, 1), (3, 3), (4, 2))]


def riccati_edges(rng: np.random.Generator) -> list[Case]:
    A, B = _double_integrator()
    cart = CartPole().linearize_upright()
    one = (np.array([[3.0]]), np.array([[1.2]]), np.array([[0.5]]), np.array([[1.0]]),
           np.array([[2.0]]))
    P, A2, B2, _, R2 = _system(rng, 2, 2)
    return [
        Case("the double integrator (dt = 0.1 s) from P = Q = I, R = 1",
             (np.eye(2), A, B, np.eye(2), np.array([[1.0]]))),
        Case("a scalar system: x⁺ = 1.2 x + 0.5 u, q = 1, r = 2, P_next = 3", one),
        Case("2 states, 2 controls, Q singular (only the first state weighed)",
             (P, A2, B2, np.diag([1.0, 0.0]), R2)),
        Case("a cart-pole linearised upright, from P_next = 10 I",
             (10 * np.eye(4), cart.A, cart.B, np.diag([1.0, 10.0, 0.1, 0.1]),
              np.array([[0.1]]))),
        Case("controls far dearer than states (R = 100 I, 3 states, 3 controls)",
             (*_system(rng, 3, 3)[:4], 100 * np.eye(3))),
    ]


def riccati_hidden(rng: np.random.Generator) -> list[Case]:
    sizes = [(2, 2), (3, 3)] + [(n, int(rng.integers(1, n + 1)))
                                for n in rng.integers(2, 6, size=6)]
    return [Case(f"hidden system #{i + 1}", _system(rng, n, m))
            for i, (n, m) in enumerate(sizes)]


# --- the infinite-horizon gain -----------------------------------------------------------------


def gain_reference(A: Arr, B: Arr, Q: Arr, R: Arr) -> Arr:
    return lqr_infinite_horizon(A, B, Q, R).K


def _iterates(A: Arr, B: Arr, Q: Arr, R: Arr, most: int = 3000) -> list[Arr]:
    """The gains of the recursion's first ``most`` steps, from P = Q and from P = 0 (as far as
    each changes)."""
    gains = []
    for P in (np.asarray(Q, dtype=float), np.zeros(np.shape(Q))):
        for _ in range(most):
            P_new, K = riccati_formula(P, A, B, Q, R)
            gains.append(K)
            if np.max(np.abs(P_new - P)) <= 1e-13 * max(1.0, float(np.max(np.abs(P_new)))):
                break
            P = P_new
    return gains


def _stopped_early(got: Any, A: Arr, B: Arr, Q: Arr, R: Arr) -> bool:
    """The gain of a fixed number of Riccati steps (from P = Q or P = 0), not the limit's."""
    final = gain_reference(A, B, Q, R)
    if np.allclose(got, final, rtol=1e-6, atol=1e-7):
        return False
    return any(np.allclose(got, K, rtol=1e-8, atol=1e-10) for K in _iterates(A, B, Q, R))


def _stable(rng: np.random.Generator, n: int, m: int) -> tuple[Arr, Arr, Arr, Arr]:
    """A random system that LQR can hold (always controllable here) and its costs."""
    _, A, B, Q, R = _system(rng, n, m)
    return A, B, Q, R


def gain_random(rng: np.random.Generator) -> list[Case]:
    return [Case(f"a random system, {n} states, {m} control(s)", _stable(rng, n, m))
            for n, m in ((2, 1), (2, 2), (3, 1), (3, 2), (4, 2))]


def gain_edges(rng: np.random.Generator) -> list[Case]:
    A, B = _double_integrator()
    lip = _lipm()
    return [
        Case("the double integrator (dt = 0.1 s), Q = I, R = 1",
             (A, B, np.eye(2), np.array([[1.0]]))),
        Case("a scalar unstable system: x⁺ = 1.5 x + u, q = 1, r = 1",
             (np.array([[1.5]]), np.array([[1.0]]), np.array([[1.0]]), np.array([[1.0]]))),
        Case("the linear inverted pendulum (z_c = 0.9 m, dt = 0.02 s): the centre of pressure "
             "catches the centre of mass", lip),
        Case("a system already stable, controls dear (R = 50)",
             (np.array([[0.9, 0.2], [0.0, 0.8]]), np.array([[0.0], [1.0]]), np.eye(2),
              np.array([[50.0]]))),
    ]


def _lipm() -> tuple[Arr, Arr, Arr, Arr]:
    s = linear_inverted_pendulum(dt=0.02, com_height=0.9)
    return s.A, s.B, np.diag([10.0, 1.0]), np.array([[1.0]])


def gain_hidden(rng: np.random.Generator) -> list[Case]:
    sizes = [(int(n), int(rng.integers(1, n + 1))) for n in rng.integers(2, 5, size=6)]
    return [Case(f"hidden system #{i + 1}", _stable(rng, n, m))
            for i, (n, m) in enumerate(sizes)]


# --- the gain holding up a pushed cart-pole ----------------------------------------------------

CART = CartPole()  # 1 kg cart, 0.1 kg on a 0.5 m pole, dt = 0.02 s
BALANCE_STEPS = 400  # 8 s
#: the pushes: at these steps the pole's rate jumps by this much (rad/s), forward then back
PUSHES = {0: 1.5, 100: -2.0}
FALLEN = 0.6  # rad from upright: past it the pole is down


def _balance(K: Any) -> Arr:
    """The nonlinear cart-pole upright at rest, knocked by PUSHES, under u = -K x for 8 s:
    the states (BALANCE_STEPS + 1, 4); a pole that has fallen stays where it fell."""
    x = np.zeros(4)
    gain = np.asarray(K, dtype=float).reshape(1, 4)
    states = [x]
    for k in range(BALANCE_STEPS):
        x = x + np.array([0.0, 0.0, 0.0, PUSHES.get(k, 0.0)])
        if abs(x[1]) > FALLEN or not np.all(np.isfinite(x)):
            states.append(states[-1])
            continue
        with np.errstate(all="ignore"):
            x = CART.step(x, -gain @ x)
        states.append(x)
    return np.array(states)


def _balance_advance(args: tuple[Any, ...], K: Any) -> Any:
    return _balance(K)


def balance_verdict(yours: Run, reference: Run, start: tuple[Any, ...]) -> str | None:
    """Whether the pushed pole falls, and whether the cart comes to rest upright."""
    mine, theirs = yours.states[-1], reference.states[-1]
    t = CART.dt * np.arange(len(mine))
    lean = np.abs(mine[:, 1])
    if lean.max() > FALLEN or not np.all(np.isfinite(mine)):
        k = int(np.argmax((lean > FALLEN) | ~np.isfinite(lean)))
        return (f"the pole falls: by t = {t[k]:.2f} s it leans {np.degrees(lean[k]):.0f}° "
                f"(the reference's gain leans it at most "
                f"{np.degrees(np.abs(theirs[:, 1]).max()):.0f}° and brings the cart to rest)")
    end = np.abs(mine[-1])
    if end[1] > 0.01 or end[2] > 0.05 or end[3] > 0.05:
        return (f"the pole stays up but is not back at rest after {t[-1]:g} s: the state is "
                f"{show(mine[-1])} (cart position, angle, their rates; the reference's is "
                f"{show(theirs[-1])})")
    return None


BALANCE = Rollout(1, _balance_advance, balance_verdict, seconds=10.0)


def balance_runs(rng: np.random.Generator) -> list[Case]:
    lin = CART.linearize_upright()
    R = np.array([[0.1]])
    return [
        Case("a cart-pole knocked forward (θ̇ = 1.5 rad/s), then back at 2 s (-2 rad/s): held "
             "up by u = -K x", (lin.A, lin.B, np.diag([1.0, 10.0, 0.1, 0.1]), R)),
        Case("the same, the cart's position weighed more, the force dearer",
             (lin.A, lin.B, np.diag([10.0, 10.0, 1.0, 0.1]), 10 * R)),
    ]


# --- the REINFORCE estimate --------------------------------------------------------------------


def reinforce_reference(x: Arr, u: Arr, cost: Arr, final_cost: Arr, K: Arr, sigma: float,
                        discount: float) -> Arr:
    """The library's estimator, the leave-one-out mean baseline."""
    batch = Rollouts(x=np.asarray(x, dtype=float), u=np.asarray(u, dtype=float),
                     cost=np.asarray(cost, dtype=float),
                     final_cost=np.asarray(final_cost, dtype=float))
    return library_reinforce(batch, LinearGaussianPolicy(np.asarray(K, dtype=float), sigma),
                             discount=discount, baseline="mean")


def reinforce_formula(x: Arr, u: Arr, cost: Arr, final_cost: Arr, K: Arr, sigma: float,
                      discount: float, *, baseline: bool = True, twice: bool = False,
                      whole: bool = False, sigma_power: int = 2, weigh: bool = True,
                      mean_sign: float = -1.0) -> Arr:
    r"""The estimator written out, and as students get it wrong: no ``baseline``; ``twice``,
    :math:`G_t` discounted from 0 as well as weighed by :math:`\gamma^t`; ``whole``, every
    step's score weighed by the whole return :math:`G_0`; ``sigma_power=1``, the score over
    :math:`\sigma`; ``weigh=False``, no :math:`\gamma^t` in front; ``mean_sign=+1``, the score
    of :math:`\mathcal N(+Kx, \sigma^2)`."""
    xs, us, c = (np.asarray(a, dtype=float) for a in (x, u, cost))
    gamma = float(discount)
    N, T = c.shape
    G = np.empty_like(c)
    running = np.asarray(final_cost, dtype=float).copy()
    for t in range(T - 1, -1, -1):
        running = c[:, t] + gamma * running
        G[:, t] = running
    if twice:
        G = G * gamma ** np.arange(T)
    if whole:
        G = np.repeat(G[:, :1], T, axis=1)
    if baseline:
        G = G - (G.sum(0, keepdims=True) - G) / (N - 1)
    states = xs[:, :-1]
    noise = us - mean_sign * np.einsum("ij,ntj->nti", np.asarray(K, dtype=float), states)
    score = -(noise[..., :, None] * states[..., None, :]) / float(sigma) ** sigma_power
    w = (gamma ** np.arange(T) if weigh else np.ones(T)) * G
    out: Arr = (score * w[:, :, None, None]).sum(1).mean(0)
    return out


def _reinforce_variant(**how: Any) -> Any:
    return lambda *args: reinforce_formula(*args, **how)


#: the double integrator of the training (dt = 0.1 s), its costs and exploration
TRAIN_Q, TRAIN_R, SIGMA = 0.1 * np.eye(2), np.array([[0.1]]), 0.5


def lq_task(horizon: int = 20, discount: float = 1.0, m: int = 1) -> LQTask:
    """The double integrator (one control), or two of them side by side in the plane (two)."""
    A, B = _double_integrator()
    if m == 2:  # a point mass in the plane: (x, y, ẋ, ẏ) ordered as two integrators
        A, B = np.kron(np.eye(2), A), np.kron(np.eye(2), B)
        return LQTask.make(A, B, 0.1 * np.eye(4), 0.1 * np.eye(2), horizon, discount=discount)
    return LQTask.make(A, B, TRAIN_Q, TRAIN_R, horizon, discount=discount)


def batch_args(task: LQTask, K: Arr, sigma: float, episodes: int,
               rng: np.random.Generator) -> tuple[Any, ...]:
    """The call's arguments for a batch of ``episodes`` sampled from ``N(-Kx, σ²I)``."""
    b = sample_rollouts(task, LinearGaussianPolicy(K, sigma), episodes, rng)
    return (b.x, b.u, b.cost, b.final_cost, np.asarray(K, dtype=float), float(sigma),
            float(task.discount))


def reinforce_random(rng: np.random.Generator) -> list[Case]:
    return [
        Case("4 episodes of 3 steps on the double integrator, γ = 0.9",
             batch_args(lq_task(3, 0.9), np.array([[0.8, 1.2]]), SIGMA, 4, rng)),
        Case("6 episodes of 5 steps, γ = 0.8",
             batch_args(lq_task(5, 0.8), np.array([[0.3, 0.7]]), SIGMA, 6, rng)),
        Case("5 episodes of 4 steps, γ = 0.95, σ = 0.3",
             batch_args(lq_task(4, 0.95), np.array([[1.0, 1.5]]), 0.3, 5, rng)),
        Case("8 episodes of 10 steps, γ = 0.99",
             batch_args(lq_task(10, 0.99), np.array([[0.5, 1.0]]), SIGMA, 8, rng)),
        Case("a point mass in the plane (2 controls, 4 states), 5 episodes of 4 steps, γ = 0.9",
             batch_args(lq_task(4, 0.9, m=2), np.array([[0.5, 0, 1.0, 0], [0, 0.4, 0, 0.9]]),
                        SIGMA, 5, rng)),
    ]


def reinforce_edges(rng: np.random.Generator) -> list[Case]:
    return [
        Case("two episodes (the fewest a leave-one-out baseline takes), 4 steps, γ = 0.9",
             batch_args(lq_task(4, 0.9), np.array([[0.6, 1.1]]), SIGMA, 2, rng)),
        Case("one step per episode (T = 1), 5 episodes, γ = 0.9",
             batch_args(lq_task(1, 0.9), np.array([[0.6, 1.1]]), SIGMA, 5, rng)),
        Case("no discount (γ = 1), 5 episodes of 4 steps",
             batch_args(lq_task(4, 1.0), np.array([[0.6, 1.1]]), SIGMA, 5, rng)),
        Case("little exploration (σ = 0.1), 6 episodes of 5 steps, γ = 0.9",
             batch_args(lq_task(5, 0.9), np.array([[0.9, 1.4]]), 0.1, 6, rng)),
        Case("a gain of zero (u is pure noise), 5 episodes of 6 steps, γ = 0.85",
             batch_args(lq_task(6, 0.85), np.zeros((1, 2)), SIGMA, 5, rng)),
    ]


def reinforce_hidden(rng: np.random.Generator) -> list[Case]:
    cases = []
    for i in range(6):
        m = 2 if i == 5 else 1
        T, N = int(rng.integers(2, 8)), int(rng.integers(3, 9))
        gamma = float(rng.choice([0.8, 0.9, 0.95]))
        K = rng.uniform(0.2, 1.5, (m, 2 * m))
        cases.append(Case(f"hidden batch #{i + 1}",
                          batch_args(lq_task(T, gamma, m), K, float(rng.choice([0.3, 0.5, 0.7])),
                                     N, rng)))
    return cases


# --- many batches: unbiased, and no noisier than the reference ---------------------------------

SPREAD_BATCHES, SPREAD_EPISODES, SPREAD_HORIZON = 40, 50, 20
#: how much wider than the reference's the estimates may scatter on the same batches (a
#: right estimator gives the reference's numbers: 1.00; no baseline gives 1.25-1.4 here)
SPREAD_WIDER = 1.2

#: a run's state: the batch's number, the task, the gain, σ and the seed of the batches
SpreadState = tuple[int, LQTask, Arr, float, int]


def _seed_of(args: tuple[Any, ...]) -> int:
    """The seed of a run's batches, from its first call's arguments (whose batch it drew)."""
    x, K, discount = args[0], np.asarray(args[4]), float(args[6])
    return int(round(1e4 * discount + 1e3 * float(np.abs(K).sum()))) + 7 * int(np.shape(x)[1])


def _first_batch(horizon: int, discount: float, K: Arr, episodes: int) -> tuple[Any, ...]:
    """A run's first call: the batch ``_seed_of`` finds the seed of again."""
    x = np.empty((0, horizon + 1))
    seed = _seed_of((x, None, None, None, K, SIGMA, discount))
    return batch_args(lq_task(horizon, discount), K, SIGMA, episodes,
                      np.random.default_rng([seed, 0]))


def _spread_start(args: tuple[Any, ...]) -> SpreadState:
    horizon = np.shape(args[0])[1] - 1
    return 0, lq_task(horizon, float(args[6])), np.asarray(args[4], dtype=float), SIGMA, \
        _seed_of(args)


def _spread_call(state: SpreadState) -> tuple[Any, ...]:
    k, task, K, sigma, seed = state
    return batch_args(task, K, sigma, SPREAD_EPISODES, np.random.default_rng([seed, k]))


def _spread_advance(state: SpreadState, _: Any) -> SpreadState:
    k, task, K, sigma, seed = state
    return k + 1, task, K, sigma, seed


def spread_verdict(yours: Run, reference: Run, start: tuple[Any, ...]) -> str | None:
    """The estimates' mean against the exact gradient (within 5 of their standard errors),
    and their scatter against the reference's on the same batches (at most SPREAD_WIDER
    times as wide: a right estimator gives the reference's numbers, batch by batch)."""
    _, task, K, sigma, _ = yours.states[0]
    exact = task.gradient(K, sigma)
    mine, theirs = (np.array(r.answers, dtype=float) for r in (yours, reference))
    S = len(mine)
    mean, error = mine.mean(0), mine.std(0, ddof=1) / np.sqrt(S)
    off = np.abs(mean - exact) / np.maximum(error, 1e-12)
    if off.max() > 5:
        return (f"your estimates on {S} batches of {SPREAD_EPISODES} episodes average to "
                f"{show(mean.ravel())} (± {show(error.ravel())}), but the exact gradient is "
                f"{show(exact.ravel())}: the estimate is biased, it follows some other "
                "objective than the expected discounted cost")
    wide = float(np.sqrt(mine.var(0).sum() / theirs.var(0).sum()))
    if wide > SPREAD_WIDER:
        return (f"your estimates on {S} batches of {SPREAD_EPISODES} episodes scatter "
                f"{wide:.2f} times as widely as the reference's on the same batches (their "
                f"mean {show(mean.ravel())} ± {show(error.ravel())}, the exact gradient "
                f"{show(exact.ravel())}): an estimator that noisy needs {wide**2:.1f} times "
                "the episodes to be as accurate")
    return None


SPREAD = Rollout(SPREAD_BATCHES, _spread_advance, spread_verdict, _spread_start, _spread_call,
                 seconds=10.0)


def spread_runs(rng: np.random.Generator) -> list[Case]:
    return [
        Case(f"{SPREAD_BATCHES} batches of {SPREAD_EPISODES} episodes of {SPREAD_HORIZON} steps, "
             "γ = 0.9, K = [0.1, 0.3]",
             _first_batch(SPREAD_HORIZON, 0.9, np.array([[0.1, 0.3]]), SPREAD_EPISODES)),
        Case("the same, no discount (γ = 1), K = [2, 3]",
             _first_batch(SPREAD_HORIZON, 1.0, np.array([[2.0, 3.0]]), SPREAD_EPISODES)),
    ]


# --- a policy trained with the estimator -------------------------------------------------------

TRAIN_ITERATIONS, TRAIN_EPISODES, TRAIN_HORIZON = 100, 50, 20
#: Adam's step (train_reinforce's default is 0.1: halved, the reference's gain settles within
#: 1-7 % of LQR's cost in 100 iterations of 50 episodes for every seed tried, where 0.1
#: jitters up to 14 %)
LEARNING_RATE = 0.05
BETA1, BETA2 = 0.9, 0.9  # train_reinforce's Adam (its short second-moment memory)
#: how much dearer than LQR's the trained gain's cost may be
WITHIN = 1.10

#: a run's state: iteration, gain, Adam's two moments, the task and the seed
TrainState = tuple[int, Arr, Arr, Arr, LQTask, int]


def _train_start(args: tuple[Any, ...]) -> TrainState:
    K = np.asarray(args[4], dtype=float)
    task = lq_task(np.shape(args[0])[1] - 1, float(args[6]))
    return 0, K, np.zeros_like(K), np.zeros_like(K), task, _seed_of(args)


def _train_call(state: TrainState) -> tuple[Any, ...]:
    i, K, _, _, task, seed = state
    return batch_args(task, K, SIGMA, TRAIN_EPISODES, np.random.default_rng([seed, i]))


def _train_advance(state: TrainState, g: Any) -> TrainState:
    """One Adam step against the estimate ``g`` (as train_reinforce takes it: each entry moves
    by about the learning rate, however large ``g`` is)."""
    i, K, first, second, task, seed = state
    g = np.asarray(g, dtype=float)
    i += 1
    first = BETA1 * first + (1 - BETA1) * g
    second = BETA2 * second + (1 - BETA2) * g * g
    step = (first / (1 - BETA1**i)) / (np.sqrt(second / (1 - BETA2**i)) + 1e-8)
    return i, K - LEARNING_RATE * step, first, second, task, seed


def train_verdict(yours: Run, reference: Run, start: tuple[Any, ...]) -> str | None:
    """The trained gain's exact cost within 10 % of LQR's."""
    task = yours.states[-1][4]
    K, K_ref = yours.states[-1][1], reference.states[-1][1]
    best = task.lqr_cost()
    ratio, ratio_ref = task.cost(K) / best, task.cost(K_ref) / best
    if ratio <= WITHIN:
        return None
    return (f"after {TRAIN_ITERATIONS} iterations of {TRAIN_EPISODES} episodes trained with "
            f"your estimates, the gain K = {show(K.ravel())} costs {ratio:.2f} times LQR's "
            f"optimum (K_LQR = {show(task.lqr_gain().ravel())}); trained with the reference's "
            f"it costs {ratio_ref:.3f} times (at most {WITHIN:.2f} passes)")


TRAIN = Rollout(TRAIN_ITERATIONS, _train_advance, train_verdict, _train_start, _train_call,
                seconds=10.0)


def train_runs(rng: np.random.Generator) -> list[Case]:
    return [
        Case(f"the double integrator, γ = 0.9: {TRAIN_ITERATIONS} iterations of Adam from "
             "K = 0", _first_batch(TRAIN_HORIZON, 0.9, np.zeros((1, 2)), TRAIN_EPISODES)),
        Case("the same, no discount (γ = 1)",
             _first_batch(TRAIN_HORIZON, 1.0, np.zeros((1, 2)), TRAIN_EPISODES)),
    ]


# --- the catalogue of known mistakes -----------------------------------------------------------

MISCONCEPTIONS = (
    Misconception(
        "transposed_gain", "riccati_step", "the gain transposed (Kᵀ, n × m)",
        "K = (R + BᵀPB)⁻¹ BᵀPA has one row per control and one column per state (m × n), so "
        "that u = −K x is a control. Yours is its transpose, AᵀPB (R + BᵀPB)⁻¹, which only "
        "has the shapes a step needs when B is square: write K = np.linalg.solve(R + B.T @ P "
        "@ B, B.T @ P @ A).",
        wrong=lambda *a: riccati_formula(*a, gain="transposed"), explains=_gain_shape_error,
        undefined=_not_square),
    Misconception(
        "sign_of_k", "riccati_step", "the sign of K (the gain of u = +K x)",
        "The course's gain has the minus outside: u = −K x with K = (R + BᵀPB)⁻¹ BᵀPA. Your "
        "K is its negative, the gain of u = +K x; a controller using it as u = −K x pushes "
        "the state away.",
        symptom=_gain_negated),
    Misconception(
        "q_r_swapped", "riccati_step", "Q and R swapped",
        "R weighs the controls, so it sits beside BᵀPB (m × m) inside the inverse; Q weighs "
        "the states and is added to P (n × n): K = (R + BᵀPB)⁻¹BᵀPA, P = Q + AᵀP(A − BK).",
        wrong=lambda *a: riccati_formula(*a, swap=True), explains=_cost_shape_error,
        undefined=_not_square),
    Misconception(
        "no_feedback_term", "riccati_step", "P updated as Q + AᵀPA (the −AᵀPBK term left out)",
        "P_t is the cost-to-go of the best control, P_t = Q + AᵀP(A − BK) = Q + AᵀPA − "
        "AᵀPBK. Q + AᵀPA is the cost of doing nothing (u = 0): it grows without bound on an "
        "unstable system, the control's −AᵀPBK is what keeps it finite.",
        wrong=lambda *a: riccati_formula(*a, feedback=False)),
    Misconception(
        "gain_sign", "lqr_gain", "the sign of K (the gain of u = +K x)",
        "The course's convention is u = −K x with K = (R + BᵀPB)⁻¹ BᵀPA. Your gain is the "
        "negative of that: applied as u = −K x it pushes the state the wrong way and "
        "destabilises what it should hold.",
        wrong=lambda *a: -gain_reference(*a)),
    Misconception(
        "stopped_early", "lqr_gain", "a fixed number of Riccati steps (not converged)",
        "Your gain is the one the recursion gives after a fixed number of steps. The "
        "infinite-horizon gain is the recursion's limit: iterate P ← Q + AᵀP(A − BK) until P "
        "stops changing (say max |P_new − P| ≤ 1e-10 max(1, max |P|)), however many steps a "
        "slow system takes.",
        symptom=_stopped_early),
    Misconception(
        "missing_baseline", "reinforce_gradient", "the baseline left out",
        "Without b_t the estimate is still unbiased but much noisier: subtract from each "
        "G_t the mean G_t of the OTHER episodes, b = (G.sum(0) − G)/(N − 1) (leave-one-out, "
        "so it does not depend on the episode it is subtracted from).",
        wrong=_reinforce_variant(baseline=False)),
    Misconception(
        "discount_twice", "reinforce_gradient", "the discount applied twice (γ^(2t))",
        "γᵗ in front of the score already brings step t back to time 0, so G_t must be "
        "discounted from t: G_t = Σ_s γ^(s−t) c_s. Yours discounts it from 0 (γ^s), so "
        "step t's term carries γ^(2t).",
        wrong=_reinforce_variant(twice=True)),
    Misconception(
        "whole_return", "reinforce_gradient", "the whole return G_0 for every step",
        "A control at step t cannot change the costs before t: only the cost-to-go G_t from "
        "t on multiplies its score (causality). Weighing every step by the episode's whole "
        "return G_0 stays unbiased but adds the noise of costs the step did not cause.",
        wrong=_reinforce_variant(whole=True)),
    Misconception(
        "sigma_not_squared", "reinforce_gradient", "the score divided by σ, not σ²",
        "log π(u|x) = −|u + Kx|²/(2σ²) + const, so ∇_K log π = −(u + Kx) xᵀ/σ²: σ squared. "
        "Dividing by σ scales the whole gradient by σ.",
        wrong=_reinforce_variant(sigma_power=1)),
    Misconception(
        "no_weight_discount", "reinforce_gradient", "γᵗ in front of the score left out",
        "The objective is Σ_t γᵗ c_t: a control at step t counts γᵗ times, so its term is "
        "γᵗ ∇log π(u_t|x_t) (G_t − b_t).",
        wrong=_reinforce_variant(weigh=False)),
    Misconception(
        "score_sign", "reinforce_gradient", "the score of N(+Kx, σ²): −(u − Kx) xᵀ/σ²",
        "The mean control is −Kx (u = −Kx, LQR's sign), so the exploration noise is u + Kx "
        "and ∇_K log π = −(u + Kx) xᵀ/σ².",
        wrong=_reinforce_variant(mean_sign=1.0)),
)


# --- the assignment ----------------------------------------------------------------------------

_STEP_CHECK = TupleCheck((Check(None, atol=1e-8, rtol=1e-8, noun="value matrix"),
                          Check(None, atol=1e-8, rtol=1e-8, noun="gain")), ("P", "K"))

_FUNCTIONS = (
    Function("riccati_step", ("P_next", "A", "B", "Q", "R"), riccati_reference, _STEP_CHECK),
    Function("lqr_gain", ("A", "B", "Q", "R"), gain_reference,
             Check(None, atol=1e-7, rtol=1e-6, noun="gain"),
             timeout_hint="iterate until P stops changing, but stop: a relative change "
                          "below 1e-10, or a few hundred thousand steps at most"),
    Function("reinforce_gradient", ("x", "u", "cost", "final_cost", "K", "sigma", "discount"),
             reinforce_reference, Check(None, atol=1e-8, rtol=1e-8, noun="gradient")),
)

ASSIGNMENT = Assignment(
    key="a8",
    title="Optimal control and learning",
    template="a8_optimal_control.py",
    functions=_FUNCTIONS,
    tests=(
        *random_edge_hidden("riccati_step", riccati_random, riccati_edges, riccati_hidden),
        *random_edge_hidden("lqr_gain", gain_random, gain_edges, gain_hidden),
        Test("lqr_gain: a pushed cart-pole held up for 8 s", "lqr_gain", 1.0, balance_runs,
             rollout=BALANCE),
        *random_edge_hidden("reinforce_gradient", reinforce_random, reinforce_edges,
                            reinforce_hidden),
        Test("reinforce_gradient: 40 batches, unbiased and no noisier than the reference",
             "reinforce_gradient", 1.0, spread_runs, rollout=SPREAD),
        Test("reinforce_gradient: a policy trained with it reaches LQR's cost",
             "reinforce_gradient", 1.0, train_runs, rollout=TRAIN),
    ),
    misconceptions=MISCONCEPTIONS,
)
