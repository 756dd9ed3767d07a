"""Notebook 16's exercises against course.control: the reference of 16.riccati_step is the
package's Riccati step (and iterated reaches the DARE's fixed point), and 16.reinforce_gradient
is the package's leave-one-out REINFORCE estimate on the same episodes, and
16.discounted_cost is the discounted objective LQTask computes exactly. (Solved by the
reference and every named mistake caught: tests/test_exercises.py, which runs every
notebook's; 16.discounted_cost's mistakes each named alone, here.)"""

from __future__ import annotations

import numpy as np

from course.exercises import reference


def test_riccati_step_is_course_controls() -> None:
    """16.riccati_step's P_t is course.control.riccati_step's, and iterated it reaches the
    DARE's fixed point (the infinite-horizon LQR)."""
    from course.control import double_integrator, lqr_infinite_horizon
    from course.control import riccati_step as library_step

    rng = np.random.default_rng(16)
    ref = reference("16.riccati_step")
    for n, m in ((2, 1), (3, 2), (4, 4)):
        A, B = np.eye(n) + 0.3 * rng.normal(size=(n, n)), rng.normal(size=(n, m))
        L, M = rng.normal(size=(n, n)), rng.normal(size=(m, m))
        Q, R = L @ L.T, M @ M.T + np.eye(m)
        assert np.allclose(ref(Q, A, B, Q, R), library_step(Q, A, B, Q, R)[0], rtol=1e-10)
    s = double_integrator(dt=0.1)
    P = np.eye(2)
    for _ in range(400):
        P = ref(P, s.A, s.B, np.eye(2), np.array([[1.0]]))
    assert np.allclose(P, lqr_infinite_horizon(s.A, s.B, np.eye(2), [[1.0]]).P, rtol=1e-9)


def test_reinforce_gradient_is_course_controls_with_the_mean_baseline() -> None:
    """16.reinforce_gradient on a batch equals course.control's leave-one-out estimate."""
    from course.control import LinearGaussianPolicy, LQTask, double_integrator, sample_rollouts
    from course.control import reinforce_gradient as library_gradient

    s = double_integrator(dt=0.1)
    for gamma in (1.0, 0.9):
        task = LQTask.make(s.A, s.B, np.eye(2), [[1.0]], horizon=20, discount=gamma)
        policy = LinearGaussianPolicy(np.array([[0.5, 1.0]]), 0.5)
        batch = sample_rollouts(task, policy, 50, np.random.default_rng(3))
        ours = reference("16.reinforce_gradient")(batch.x, batch.u, batch.cost,
                                                  batch.final_cost, policy.K, 0.5, gamma)
        theirs = library_gradient(batch, policy, discount=gamma, baseline="mean")
        assert np.allclose(ours, theirs, rtol=1e-10, atol=1e-12)


def test_discounted_cost_is_the_tasks_objective() -> None:
    """16.discounted_cost averaged over sampled episodes is LQTask's exact discounted J(K)
    (within 4 standard errors), and with γ = 1 the plain sum of the episode's costs."""
    from course.control import LinearGaussianPolicy, LQTask, double_integrator, sample_rollouts

    s = double_integrator(dt=0.1)
    ref = reference("16.discounted_cost")
    policy = LinearGaussianPolicy(np.array([[0.5, 1.0]]), 0.5)
    for gamma in (1.0, 0.9, 0.5):
        task = LQTask.make(s.A, s.B, np.eye(2), [[1.0]], horizon=30, discount=gamma)
        batch = sample_rollouts(task, policy, 20_000, np.random.default_rng(16))
        J = ref(batch.cost, batch.final_cost, gamma)
        sem = J.std(ddof=1) / np.sqrt(len(J))
        assert abs(J.mean() - task.cost(policy.K, policy.sigma)) < 4 * sem
    plain = ref(batch.cost[:5], batch.final_cost[:5], 1.0)
    assert np.allclose(plain, batch.cost[:5].sum(1) + batch.final_cost[:5], rtol=1e-12)


def test_discounted_cost_passes_and_names_each_mistake() -> None:
    """The reference passes 16.discounted_cost's check; each listed mistake fails it and is
    the one named (no other mistake's title in its feedback)."""
    from course.exercises import check, exercise

    key = "16.discounted_cost"
    assert check(key, reference(key)).passed
    mistakes = exercise(key).mistakes
    assert {m.key for m in mistakes} >= {"discount_twice", "from_one", "from_the_end",
                                        "final_undiscounted", "no_discount"}
    for m in mistakes:
        feedback = check(key, lambda *args, wrong=m.wrong: wrong(*args))
        assert feedback.status == "fail", m.key
        named = [other.key for other in mistakes if other.title in feedback.text]
        assert named == [m.key], (m.key, named)
