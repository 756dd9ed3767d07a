"""REINFORCE on a linear-Gaussian policy (course.control.policy_gradient): the exact cost
and gradient against finite differences and sampling; the estimator unbiased (its mean
within a few standard errors of the exact gradient, seeded, 100 000 episodes) with and
without baselines, and the variance each baseline saves; a discount applied twice caught;
training reaching LQR's cost; bit-for-bit reproducibility, also across BLAS thread counts.
The full-length training and its timing are benchmarks/control.py."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from course.control import (
    LinearGaussianPolicy,
    LQTask,
    Rollouts,
    ValueBaseline,
    double_integrator,
    reinforce_gradient,
    reinforce_terms,
    sample_rollouts,
    train_reinforce,
)

REPO = Path(__file__).resolve().parents[1]
SYSTEM = double_integrator(dt=0.1)
SIGMA = 0.5


def task(horizon: int = 20, discount: float = 1.0) -> LQTask:
    return LQTask.make(SYSTEM.A, SYSTEM.B, 0.1 * np.eye(2), [[0.1]], horizon,
                       discount=discount)


@pytest.mark.parametrize("discount", [1.0, 0.9])
def test_the_exact_gradient_is_the_costs_derivative(discount: float) -> None:
    t = task(discount=discount)
    K = np.array([[0.3, 0.4]])
    exact = t.gradient(K, SIGMA)
    h = 1e-6
    for j in range(2):
        d = np.zeros((1, 2))
        d[0, j] = h
        fd = (t.cost(K + d, SIGMA) - t.cost(K - d, SIGMA)) / (2 * h)
        assert exact[0, j] == pytest.approx(fd, rel=1e-6)
    # At the LQR gain the deterministic cost is stationary and minimal.
    K_lqr = t.lqr_gain()
    assert np.max(np.abs(t.gradient(K_lqr))) < 1e-9
    assert t.cost(K_lqr) == pytest.approx(t.lqr_cost(), rel=1e-12)


def test_the_exact_cost_is_the_sampled_mean() -> None:
    t = task()
    policy = LinearGaussianPolicy(np.array([[0.3, 0.4]]), SIGMA)
    returns = sample_rollouts(t, policy, 100_000, np.random.default_rng(10)).returns()
    se = returns.std() / np.sqrt(returns.size)
    assert abs(returns.mean() - t.cost(policy.K, SIGMA)) < 4 * se


def test_the_score_is_the_log_probabilitys_gradient() -> None:
    policy = LinearGaussianPolicy(np.array([[0.3, -0.7], [1.1, 0.2]]), 0.4)
    x, u = np.array([0.5, -1.2]), np.array([0.1, 0.3])
    score = policy.score(x, u)
    h = 1e-6
    for i in range(2):
        for j in range(2):
            d = np.zeros((2, 2))
            d[i, j] = h
            up = LinearGaussianPolicy(policy.K + d, 0.4).log_prob(x, u)
            down = LinearGaussianPolicy(policy.K - d, 0.4).log_prob(x, u)
            assert score[i, j] == pytest.approx((up - down) / (2 * h), rel=1e-6)


def discounted_twice(rollouts: Rollouts, policy: LinearGaussianPolicy, discount: float,
                     baseline: ValueBaseline) -> np.ndarray:
    """A mutant: G_t - b_t discounted from time 0 (γˢ, not γ^{s-t}), then by γᵗ again."""
    T = rollouts.cost.shape[1]
    G = (rollouts.costs_to_go(discount) - baseline(rollouts.x[:, :-1])) * discount ** np.arange(T)
    score = policy.score(rollouts.x[:, :-1], rollouts.u)
    return np.asarray((score * (discount ** np.arange(T) * G)[:, :, None, None]).sum(1).mean(0))


@pytest.fixture(scope="module")
def estimates() -> dict[str, object]:
    """200 independent batches of 500 episodes (100 000 in all) of one policy on the
    discounted task; each batch's estimate with every baseline, from the same episodes."""
    t = task(discount=0.9)
    policy = LinearGaussianPolicy(0.5 * t.lqr_gain(), SIGMA)
    rng = np.random.default_rng(20)
    value = ValueBaseline.fit(sample_rollouts(t, policy, 2000, rng), t.discount)
    found: dict[str, list[np.ndarray]] = {"none": [], "mean": [], "value": [], "twice": []}
    for _ in range(200):
        batch = sample_rollouts(t, policy, 500, rng)
        for name in ("none", "mean"):
            found[name].append(reinforce_gradient(batch, policy, discount=t.discount,
                                                  baseline=name))  # type: ignore[arg-type]
        found["value"].append(reinforce_gradient(batch, policy, discount=t.discount,
                                                 baseline=value))
        found["twice"].append(discounted_twice(batch, policy, t.discount, value))
    return {"exact": t.gradient(policy.K, SIGMA),
            **{k: np.array(v)[:, 0] for k, v in found.items()}}


def z_scores(samples: np.ndarray, exact: np.ndarray) -> np.ndarray:
    se = samples.std(0, ddof=1) / np.sqrt(samples.shape[0])
    return np.asarray((samples.mean(0) - exact) / se)


@pytest.mark.parametrize("baseline", ["none", "mean", "value"])
def test_the_estimator_is_unbiased(estimates: dict[str, np.ndarray], baseline: str) -> None:
    z = z_scores(estimates[baseline], estimates["exact"][0])
    assert np.all(np.abs(z) < 4), z


def test_a_discount_applied_twice_is_caught(estimates: dict[str, np.ndarray]) -> None:
    """The check the correct estimators pass rejects the mutant by a wide margin."""
    z = z_scores(estimates["twice"], estimates["exact"][0])
    assert np.max(np.abs(z)) > 20, z


def test_baselines_reduce_the_variance(estimates: dict[str, np.ndarray]) -> None:
    """Measured on the same episodes: the batch-mean baseline removes each step's mean
    cost (variance about 1.7x lower); the quadratic value baseline removes what the state
    explains too (about 100x lower)."""
    none = estimates["none"].var(0)
    assert np.all(none / estimates["mean"].var(0) > 1.3)
    assert np.all(none / estimates["value"].var(0) > 30)


def test_training_reaches_lqrs_cost() -> None:
    """A short run (60 iterations of 100 episodes, about 0.5 s): within 10% of the optimal
    cost, from K = 0 at 30x it."""
    t = task(horizon=50)
    result = train_reinforce(t, iterations=60, batch_size=100, seed=0)
    assert result.cost_history[0] > 20 * result.lqr_cost
    assert result.cost_ratio < 1.1, result.cost_ratio
    assert result.reason == "ran all 60 iterations"
    assert result.K_history.shape == (61, 1, 2) and result.sampled_cost.shape == (60,)
    np.testing.assert_allclose(result.K, t.lqr_gain(), rtol=0.3)


def test_training_is_reproducible_bit_for_bit() -> None:
    t = task()
    a = train_reinforce(t, iterations=15, batch_size=50, seed=7)
    b = train_reinforce(t, iterations=15, batch_size=50, seed=7)
    c = train_reinforce(t, iterations=15, batch_size=50, seed=8)
    np.testing.assert_array_equal(a.K_history, b.K_history)
    np.testing.assert_array_equal(a.sampled_cost, b.sampled_cost)
    assert not np.array_equal(a.K_history, c.K_history)


CHILD = """
import numpy as np
from course.control import LQTask, double_integrator, train_reinforce
s = double_integrator(dt=0.1)
t = LQTask.make(s.A, s.B, 0.1 * np.eye(2), [[0.1]], 20)
r = train_reinforce(t, iterations=15, batch_size=50, seed=7)
print(r.K_history.tobytes().hex(), r.sampled_cost.tobytes().hex())
"""


def test_the_same_bits_on_one_or_two_blas_threads() -> None:
    here = train_reinforce(task(), iterations=15, batch_size=50, seed=7)
    expected = f"{here.K_history.tobytes().hex()} {here.sampled_cost.tobytes().hex()}"
    for threads in ("1", "2"):
        env = {**os.environ, "OPENBLAS_NUM_THREADS": threads, "OMP_NUM_THREADS": threads,
               "MKL_NUM_THREADS": threads}
        out = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True,
                             cwd=REPO, env=env, check=True)
        assert out.stdout.strip() == expected, f"{threads} thread(s)"


def test_a_diverging_run_stops_and_says_why() -> None:
    result = train_reinforce(task(), K0=[[-1e8, -1e8]], iterations=5, batch_size=20)
    assert result.reason.startswith("stopped at iteration ")
    assert "not finite" in result.reason and "lower learning_rate" in result.reason
    stopped = int(result.reason.split()[3].rstrip(":"))
    assert result.K_history.shape == (stopped, 1, 2)


def test_bad_arguments_are_named() -> None:
    t = task()
    with pytest.raises(ValueError, match="sigma: must be a positive number"):
        LinearGaussianPolicy(np.zeros((1, 2)), 0.0)
    with pytest.raises(ValueError, match=r"policy: its K has shape \(2, 1\); this task needs"):
        sample_rollouts(t, LinearGaussianPolicy(np.zeros((2, 1)), 1.0), 10,
                        np.random.default_rng(0))
    batch = sample_rollouts(t, LinearGaussianPolicy(np.zeros((1, 2)), 1.0), 1,
                            np.random.default_rng(0))
    with pytest.raises(ValueError, match="baseline='mean' needs at least 2 episodes"):
        reinforce_terms(batch, LinearGaussianPolicy(np.zeros((1, 2)), 1.0))
    with pytest.raises(ValueError, match="baseline: expected one of"):
        reinforce_gradient(batch, LinearGaussianPolicy(np.zeros((1, 2)), 1.0),
                           baseline="median")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"K0: expected a gain of shape \(1, 2\) \(u = -K x"):
        train_reinforce(t, K0=np.zeros(2))
    with pytest.raises(ValueError, match="baseline: expected one of"):
        train_reinforce(t, baseline="learned")
