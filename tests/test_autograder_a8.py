"""The a8 (Riccati step, LQR gain, REINFORCE) autograder: its references against independent
ones (the formulas written out, scipy's DARE, the exact gradient of the expected cost), the
symptoms and runs that separate the mistakes, and hostile submissions."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
from grading_fixtures import FIXTURES, LIMITS, one_line, seed, visible_cases

from autograder import check
from autograder.assignments import load
from autograder.assignments.a8 import (
    SPREAD_WIDER,
    WITHIN,
    _first_batch,
    _seed_of,
    _stopped_early,
    batch_args,
    lq_task,
    reinforce_formula,
    riccati_formula,
)
from autograder.spec import case_rng

REPO = Path(__file__).resolve().parents[1]
A8 = load("a8")


def test_the_riccati_reference_is_the_step_written_out_and_fixes_the_dare():
    """The library's step is the lecture's formula, and scipy's DARE solution is its fixed
    point (one step from it gives it back)."""
    fn = A8.function("riccati_step")
    for c in visible_cases(A8, "riccati_step"):
        expected = fn.reference(*c.args)
        assert fn.check.close(riccati_formula(*c.args), expected), c.label
        _, A, B, Q, R = c.args
        P = scipy.linalg.solve_discrete_are(A, B, Q, R)
        P_again, K = fn.reference(P, A, B, Q, R)
        np.testing.assert_allclose(P_again, P, rtol=1e-8, atol=1e-8 * np.abs(P).max())
        np.testing.assert_allclose(K, np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A), atol=1e-12)


def test_the_gain_reference_is_scipys_dare_gain():
    fn = A8.function("lqr_gain")
    for c in visible_cases(A8, "lqr_gain"):
        A, B, Q, R = c.args
        P = scipy.linalg.solve_discrete_are(A, B, Q, R)
        K = np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
        np.testing.assert_allclose(fn.reference(*c.args), K, rtol=1e-7,
                                   atol=1e-8 * np.abs(K).max(), err_msg=c.label)
        closed = A - B @ K
        assert np.max(np.abs(np.linalg.eigvals(closed))) < 1, c.label


def test_a_gain_stopped_early_is_recognised_and_the_converged_one_is_not():
    for c in visible_cases(A8, "lqr_gain"):
        A, B, Q, R = c.args
        P = Q.copy()
        for _ in range(20):
            P, K = riccati_formula(P, A, B, Q, R)
        converged = A8.function("lqr_gain").reference(*c.args)
        assert not _stopped_early(converged, *c.args), c.label
        if not np.allclose(K, converged, rtol=1e-6, atol=1e-7):
            assert _stopped_early(K, *c.args), c.label
        assert not _stopped_early(-converged, *c.args), c.label


def test_the_reinforce_reference_is_the_estimator_written_out():
    fn = A8.function("reinforce_gradient")
    cases = visible_cases(A8, "reinforce_gradient")
    assert len(cases) == 5 + 5 + 2 + 2  # random, edges, the batches' runs and the trainings
    for c in cases:
        np.testing.assert_allclose(reinforce_formula(*c.args), fn.reference(*c.args),
                                   rtol=1e-10, atol=1e-12, err_msg=c.label)


@pytest.mark.parametrize("discount", [0.9, 1.0])
def test_the_estimator_averages_to_the_exact_gradient(discount):
    """Seeded, 400,000 episodes of 5 steps in 100 batches (1 s): the reference's mean is
    within 4 standard errors of LQTask.gradient, the exact ∂J/∂K of the expected discounted
    cost; with σ where σ² belongs it is not (it is σ times the gradient)."""
    task = lq_task(5, discount)
    K, sigma = np.array([[0.3, 0.6]]), 0.5
    fn = A8.function("reinforce_gradient").reference
    rng = np.random.default_rng(5)
    right, scaled = [], []
    for _ in range(100):
        args = batch_args(task, K, sigma, 4000, rng)
        right.append(fn(*args))
        scaled.append(reinforce_formula(*args, sigma_power=1))
    exact = task.gradient(K, sigma)
    for estimates, ok in ((right, True), (scaled, False)):
        e = np.array(estimates)
        z = np.abs(e.mean(0) - exact) / (e.std(0, ddof=1) / np.sqrt(len(e)))
        assert (z.max() < 4) == ok, (z, exact, e.mean(0))


def test_each_run_starts_from_its_cases_own_batch():
    """A run's first call is its case's arguments: the seed of its batches is found again
    from them."""
    for name in ("reinforce_gradient: 40 batches", "reinforce_gradient: a policy"):
        test = next(t for t in A8.tests if t.name.startswith(name))
        assert test.rollout is not None
        for c in test.cases(case_rng(test, None)):
            first = test.rollout.call(test.rollout.start(c.args))
            for a, b in zip(first, c.args, strict=True):
                np.testing.assert_array_equal(a, b)
    again = _first_batch(20, 0.9, np.array([[0.1, 0.3]]), 50)
    assert _seed_of(again) == _seed_of(_first_batch(20, 0.9, np.array([[0.1, 0.3]]), 7))


def rollout_test(name: str):
    test = next(t for t in A8.tests if t.name.startswith(name))
    assert test.rollout is not None
    return test, test.cases(case_rng(test, None))


def test_the_reference_runs_pass_their_verdicts():
    """The reference's cart-pole stays within 15° of upright through both pushes and is at
    rest at the end; its estimates average to the exact gradient; its trained gain costs
    within 5 % of LQR's."""
    for name in ("lqr_gain: a pushed", "reinforce_gradient: 40 batches",
                 "reinforce_gradient: a policy"):
        test, cases = rollout_test(name)
        fn = A8.function(test.function)
        for c in cases:
            run = test.rollout.run(fn.reference, c.args)
            assert test.rollout.verdict(run, run, c.args) is None, (name, c.label)
            if name.startswith("lqr_gain"):
                states = run.states[-1]
                assert np.abs(states[:, 1]).max() < np.radians(15)
            if name.startswith("reinforce_gradient: a policy"):
                task, K = run.states[-1][4], run.states[-1][1]
                assert task.cost(K) / task.lqr_cost() < 1.05 < WITHIN


@pytest.mark.parametrize(("key", "name", "says"), [
    ("gain_sign", "lqr_gain: a pushed", "the pole falls"),
    ("missing_baseline", "reinforce_gradient: 40 batches", "times as widely as the reference"),
    ("whole_return", "reinforce_gradient: 40 batches", "times as widely as the reference"),
    ("score_sign", "reinforce_gradient: 40 batches", "the estimate is biased"),
    ("score_sign", "reinforce_gradient: a policy", "times LQR's optimum"),
])
def test_a_mistake_run_is_told_what_it_did(key, name, says):
    """The runs a mistake fails say what the estimates or the gain did, in words."""
    mistake = next(m for m in A8.misconceptions if m.key == key)
    test, cases = rollout_test(name)
    fn = A8.function(test.function)
    verdicts = []
    for c in cases:
        with np.errstate(all="ignore"):
            run = test.rollout.run(mistake.wrong, c.args)
        verdicts.append(test.rollout.verdict(run, test.rollout.run(fn.reference, c.args),
                                             c.args))
    assert any(v is not None and says in v for v in verdicts), verdicts


def test_no_baseline_scatters_wider_than_the_limit_on_every_run():
    """The variance check: on both runs' batches no baseline scatters more than SPREAD_WIDER
    times the reference's (a right estimator: exactly 1)."""
    test, cases = rollout_test("reinforce_gradient: 40 batches")
    fn = A8.function(test.function)
    wrong = next(m for m in A8.misconceptions if m.key == "missing_baseline").wrong
    for c in cases:
        mine = np.array(test.rollout.run(wrong, c.args).answers)
        theirs = np.array(test.rollout.run(fn.reference, c.args).answers)
        assert np.sqrt(mine.var(0).sum() / theirs.var(0).sum()) > SPREAD_WIDER + 0.03


def test_the_reference_scores_full_marks_in_bounded_time():
    """Every rollout test of the reference runs well within its own seconds (measured: 1.5 s
    for the batches and 3 s for the training on a loaded 2-core machine)."""
    result = check("a8", FIXTURES / "a8" / "reference.py", seed=seed("a8"), limits=LIMITS)
    assert result.score == result.max_score == 15, one_line(result)
    for t in result.tests:
        if t.test.rollout is not None:
            assert t.elapsed < t.test.rollout.seconds, (t.test.name, t.elapsed)


def test_scipy_is_refused_before_anything_runs():
    result = check("a8", FIXTURES / "a8" / "adv_import_scipy.py", limits=LIMITS)
    assert result.score == 0
    assert ("`from scipy.linalg import ...` is not allowed: the assignment asks you to "
            "implement the math yourself with numpy") in one_line(result)


def test_the_notebook_beside_a_right_solution_scores_full_marks(tmp_path):
    """The notebook's display code names nothing a solution's helpers are likely called:
    graded with it, the solution keeps every visible point."""
    shutil.copy(REPO / "assignments" / "a8_optimal_control.ipynb", tmp_path)
    shutil.copy(FIXTURES / "a8" / "reference.py", tmp_path / "a8_optimal_control.py")
    result = check("a8", tmp_path / "a8_optimal_control.ipynb", limits=LIMITS)
    assert not result.problems and result.score == result.max_score == 9, one_line(result)
