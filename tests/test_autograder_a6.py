"""The a6 (rigid body, PD torque, balance torque) autograder: its references against
independent ones (the step written out, the rotation vector, finite differences of the
centre of mass), the cases that separate the mistakes, and hostile submissions."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest
from grading_fixtures import (
    FIXTURES,
    LIMITS,
    fixture_submission,
    one_line,
    seed,
    visible_cases,
)
from hypothesis import given, settings
from hypothesis import strategies as st

from autograder import check
from autograder.assignments import load
from autograder.assignments.a6 import (
    DRIVE_H,
    _flips,
    balance_formula,
    chain_points,
    com_jacobian,
    drive_rates,
    drive_verdict,
    is_drive_case,
    pd_formula,
    step_formula,
)
from autograder.spec import case_rng
from course import rotations as rot
from course.physics.rigid_body import RigidState, simulate_rigid, t_handle

REPO = Path(__file__).resolve().parents[1]
A6 = load("a6")


def test_the_step_reference_is_the_step_written_out():
    fn = A6.function("rigid_body_step")
    for c in visible_cases(A6, "rigid_body_step"):
        expected = fn.reference(*c.args)
        assert fn.check.close(step_formula(*c.args), expected), c.label
        assert abs(np.linalg.norm(expected[2]) - 1) < 1e-12
    no_torque = next(c for c in visible_cases(A6, "rigid_body_step") if "no torque" in c.label)
    np.testing.assert_array_equal(fn.reference(*no_torque.args)[3], no_torque.args[3])


def test_the_step_keeps_l_and_unit_q_and_energy_drifts_at_first_order():
    """Many steps of the reference with no torque: L exactly conserved, |q| = 1, and the
    kinetic energy's drift halves (about) when h halves."""
    body = t_handle()
    q = np.array([1.0, 0.0, 0.0, 0.0])
    L = body.inertia @ np.array([0.3, 2.0, 0.1])
    drift = []
    for h in (2e-3, 1e-3):
        state = RigidState.create(x=np.zeros(3), v=np.zeros(3), q=q, L=L)
        traj = simulate_rigid(body, state, h, int(round(0.5 / h)), method="symplectic",
                              rotation="quaternion", gravity=np.zeros(3))
        np.testing.assert_allclose(traj.L, np.broadcast_to(L, traj.L.shape), atol=1e-12)
        np.testing.assert_allclose(np.linalg.norm(traj.q, axis=-1), 1.0, atol=1e-12)
        e = traj.energy.total
        drift.append(float(np.max(np.abs(e - e[0]))))
        fn = A6.function("rigid_body_step").reference
        one = fn(np.zeros(3), np.zeros(3), q, L, body.mass, body.inertia, np.zeros(3),
                 np.zeros(3), h)
        np.testing.assert_allclose(one[2], traj.q[1], atol=1e-14)
    assert 1.5 < drift[0] / drift[1] < 2.5, drift


def test_the_pd_reference_is_the_rotation_vector_taken_the_short_way():
    fn = A6.function("pd_torque")
    flips = 0
    for c in visible_cases(A6, "pd_torque"):
        expected = fn.reference(*c.args)
        np.testing.assert_allclose(pd_formula(*c.args), expected, atol=1e-10)
        q, q_bar, *rest = c.args
        np.testing.assert_allclose(fn.reference(q, -q_bar, *rest), expected, atol=1e-10)
        flips += int(not np.allclose(pd_formula(*c.args, shortest=False), expected))
    assert flips >= 6
    q = np.array([[1.0, 0, 0, 0]])
    turn = np.array([[np.cos(0.4), 0, 0, np.sin(0.4)]])  # 0.8 rad about z
    np.testing.assert_allclose(fn.reference(q, turn, np.zeros((1, 3)), 10.0, 1.0, 100.0),
                               [[0.0, 0.0, 8.0]], atol=1e-12)


def test_the_com_jacobian_is_its_finite_differences_and_the_torque_its_transpose():
    for c in visible_cases(A6, "balance_torque"):
        angles, lengths, masses, ratios = c.args[:4]
        _, J = com_jacobian(angles, lengths, masses, ratios)
        eps = 1e-6
        for j in range(len(angles)):
            d = np.zeros(len(angles))
            d[j] = eps
            fd = (com_jacobian(angles + d, lengths, masses, ratios)[0]
                  - com_jacobian(angles - d, lengths, masses, ratios)[0]) / (2 * eps)
            np.testing.assert_allclose(J[:, j], fd, atol=1e-8)
        joints, _ = chain_points(angles, lengths, ratios)
        np.testing.assert_allclose(np.linalg.norm(np.diff(joints, axis=0), axis=1), lengths)
        f = c.args[6] * (c.args[4] - com_jacobian(*c.args[:4])[0]) - c.args[7] * c.args[5]
        np.testing.assert_allclose(balance_formula(*c.args), J.T @ f, atol=1e-12)


def test_balance_torques_bring_a_pushed_chain_back():
    """What the torque achieves: on a 3-link chain with unit joint inertias (a crude but
    independent plant), the COM error after 2 s of J_cᵀ f feedback from a push is smaller
    than at the start."""
    args = next(c for c in visible_cases(A6, "balance_torque") if "3 links" in c.label).args
    _, lengths, masses, ratios, _, _, kp, kd = args
    target = com_jacobian(np.zeros(3), lengths, masses, ratios)[0]
    theta, dtheta, h = np.array([0.1, -0.05, 0.08]), np.zeros(3), 1e-3
    start = np.linalg.norm(com_jacobian(theta, lengths, masses, ratios)[0] - target)
    for _ in range(2000):
        c, J = com_jacobian(theta, lengths, masses, ratios)
        tau = balance_formula(theta, lengths, masses, ratios, target, J @ dtheta, kp / 10,
                              kd / 10)
        dtheta += h * (tau - 2.0 * dtheta)
        theta += h * dtheta
    end = np.linalg.norm(com_jacobian(theta, lengths, masses, ratios)[0] - target)
    assert end < 0.2 * start, (start, end)


def test_the_reference_scores_full_marks_hidden_tests_included(tmp_path):
    """(How long a6 takes to grade: benchmarks/grading.py --assignment a6.)"""
    result = check("a6", FIXTURES / "a6" / "reference.py", seed=seed("a6"), limits=LIMITS)
    assert result.score == result.max_score


def test_running_the_course_library_is_refused(tmp_path):
    src = fixture_submission("a6", "adv_reads_the_library.py", tmp_path)
    src.write_text(src.read_text().replace("@REPO@", str(REPO)))
    result = check("a6", src, limits=LIMITS)
    step = [t for t in result.tests if t.test.function == "rigid_body_step"]
    assert all(t.n_passed == 0 for t in step)
    assert (f"does not let submissions open '{REPO}/course/physics/rigid_body.py'"
            in " ".join(str(result).split()))


def test_scipy_is_refused_before_anything_runs():
    result = check("a6", FIXTURES / "a6" / "adv_import_scipy.py", limits=LIMITS)
    assert result.score == 0
    assert ("`from scipy.spatial.transform import ...` is not allowed: the assignment asks you "
            "to implement the math yourself with numpy") in " ".join(str(result).split())


def test_the_drive_cases_measure_the_torque_law_and_judge_the_closed_loop():
    """On the drive cases the reference's central differences are k_p I and k_d I (a stable
    loop); +k_d ω makes the same joint diverge, and the judge says so."""
    fn = A6.function("pd_torque")
    cases = [c for c in visible_cases(A6, "pd_torque") if is_drive_case(c.args)]
    assert len(cases) == 4
    # 10 per-call cases, and the 2 runs from far
    assert len([c for c in visible_cases(A6, "pd_torque") if not is_drive_case(c.args)]) == 12
    for c in cases:
        got = fn.reference(*c.args)
        tau0, Kp, Kd, lam = drive_rates(got)
        kp, kd = c.args[3], c.args[4]
        np.testing.assert_allclose(tau0, 0.0, atol=1e-9)
        np.testing.assert_allclose(Kp, kp * np.eye(3), atol=1e-5 * kp)
        np.testing.assert_allclose(Kd, kd * np.eye(3), atol=1e-6 * kd)
        assert np.max(lam.real) < 0 and drive_verdict(got) is None
        wrong = pd_formula(*c.args, kd_sign=1.0)
        assert "it diverges" in fn.check.judge(wrong, got, c.args)


def test_minus_q_is_the_same_step_and_a_wrong_inertia_is_not():
    fn = A6.function("rigid_body_step")
    for c in visible_cases(A6, "rigid_body_step"):
        x, v, q, L = fn.reference(*c.args)
        assert fn.check.judge((x, v, -q, L), (x, v, q, L), c.args) is None, c.label
        if c.args[2][0] != 1.0:  # away from the identity the body-frame ω shows
            body = step_formula(*c.args, omega="body")
            assert "q is a different rotation" in fn.check.judge(body, (x, v, q, L), c.args)


def test_the_notebook_beside_a_right_solution_scores_full_marks(tmp_path):
    """The notebook's display code names nothing a solution's helpers are likely called
    (its demo chain is ``pose_of``, not ``chain``): graded with it, the solution keeps 10/10."""
    import shutil

    shutil.copy(REPO / "assignments" / "a6_physics.ipynb", tmp_path)
    shutil.copy(FIXTURES / "a6" / "reference.py", tmp_path / "a6_physics.py")
    result = check("a6", tmp_path / "a6_physics.ipynb", limits=LIMITS)
    assert not result.problems and result.score == result.max_score == 10


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(1.0, 300.0), st.floats(0.1, 30.0),
       st.floats(0.5, 500.0))
def test_pd_reference_against_scipys_rotation_vector(seed_, kp, kd, limit):
    """τ = clip(k_p r - k_d ω) with r scipy's rotation vector of q⁻¹ q̄ (scalar last there),
    the same for q̄ and -q̄, and never beyond the limit."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed_)
    q, q_bar = (v / np.linalg.norm(v, axis=1, keepdims=True) for v in rng.normal(size=(2, 5, 4)))
    omega = rng.normal(0, 2, (5, 3))
    r = (Rotation.from_quat(np.roll(q, -1, axis=1)).inv()
         * Rotation.from_quat(np.roll(q_bar, -1, axis=1))).as_rotvec()
    tau = A6.function("pd_torque").reference(q, q_bar, omega, kp, kd, limit)
    np.testing.assert_allclose(tau, np.clip(kp * r - kd * omega, -limit, limit), atol=1e-9)
    np.testing.assert_allclose(pd_formula(q, -q_bar, omega, kp, kd, limit), tau, atol=1e-9)
    assert np.all(np.abs(tau) <= limit)


# --- the rollouts: judged by what a run achieves -------------------------------------------------


def rollout_test(name: str):
    test = next(t for t in A6.tests if t.name.startswith(name))
    assert test.rollout is not None
    return test, test.cases(case_rng(test, None))


def test_the_reference_runs_do_what_the_verdicts_ask():
    """The reference T-handle turns over (the Dzhanibekov flip, first at 0.58 s here, then
    again and again), and every joint driven from 2-2.8 rad away is on its target and still
    within 1° of it by 0.7 s; the pushed body's centre of mass strays less than 10 cm and
    is back within 2 cm for the last 0.25 s, where the grader's posture PD alone lets it
    fall; each run passes its own verdict."""
    test, cases = rollout_test("rigid_body_step: bodies simulated")
    fn = A6.function("rigid_body_step")
    for c in cases:
        run = test.rollout.run(fn.reference, c.args)
        assert test.rollout.verdict(run, run, c.args) is None
        q, L = (np.array([a[i] for a in run.answers]) for i in (2, 3))
        flips = _flips(q, L, c.args[5], c.args[8])
        assert (flips is not None) == ("T-handle" in c.label), c.label
        if flips is not None:
            # the times assignments/a6_physics.ipynb quotes (to a step either way)
            np.testing.assert_allclose(flips[:3], [0.58, 0.91, 1.18], atol=0.011)
    test, cases = rollout_test("pd_torque: joints driven from far")
    fn = A6.function("pd_torque")
    for c in cases:
        states = test.rollout.run(fn.reference, c.args).states
        error = np.array([np.degrees(rot.quat_angle(s[0], s[1])) for s in states])
        assert np.all(error[0] > 110) and np.all(error[int(0.7 / DRIVE_H):] < 1.0)
    test, cases = rollout_test("balance_torque: a pushed body")
    fn = A6.function("balance_torque")
    for c in cases:
        run = test.rollout.run(fn.reference, c.args)
        com = np.array([com_jacobian(s[0], *c.args[1:4])[0] - c.args[4] for s in run.states])
        assert np.abs(com[:, 0]).max() < 0.1 and np.all(np.linalg.norm(com[-50:], axis=1) < 0.02)
        limp = test.rollout.run(lambda *a: np.zeros(3), c.args)  # the posture PD alone
        assert "the chain falls" in test.rollout.verdict(limp, run, c.args)


@pytest.mark.parametrize(("key", "says"), [
    ("not_renormalised", "the orientation is no longer a rotation"),
    ("omega_body_inertia", "it never turns over"),
    ("inertia_rotated_wrong_way", "its orientation leaves the reference's"),
    ("explicit", "its centre of mass is"),
    ("kd_sign", "rad from its target, turning at"),
    ("limit_ignored", "past the limit"),
    ("error_world_frame", "rad from its target"),
    ("pseudo_inverse", "the chain falls"),
])
def test_each_mistake_run_for_seconds_is_told_what_it_did(key, says):
    """Every listed mistake that shows in a run fails it (all its cases but maybe one), and
    the verdict says what the body or joint did, not which number differed."""
    mistake = next(m for m in A6.misconceptions if m.key == key)
    name = {"rigid_body_step": "rigid_body_step: bodies simulated",
            "pd_torque": "pd_torque: joints driven from far",
            "balance_torque": "balance_torque: a pushed body"}[mistake.function]
    test, cases = rollout_test(name)
    fn = A6.function(mistake.function)

    def wrong(*args):
        if mistake.wrong is not None:
            return mistake.wrong(*args)
        return step_formula(*args, explicit=True)  # the symptom's mistake, written out

    verdicts = []
    for c in cases:
        with np.errstate(all="ignore"):
            run = test.rollout.run(wrong, c.args)
        verdicts.append(test.rollout.verdict(run, test.rollout.run(fn.reference, c.args),
                                             c.args))
    failed = [v for v in verdicts if v is not None]
    assert len(failed) >= len(cases) - 1 and any(says in v for v in failed), verdicts


def test_a_run_that_raises_part_way_says_at_which_step(tmp_path):
    """The state is the grader's: a function that raises at its 60th call ends the first
    run at step 50 (the 10 visible one-step cases come first), says so, and the other runs
    still go."""
    src = tmp_path / "a6_physics.py"
    src.write_text((FIXTURES / "a6" / "reference.py").read_text() + '''

_calls = [0]
_right = rigid_body_step


def rigid_body_step(*args):
    _calls[0] += 1
    if _calls[0] == 60:
        raise RuntimeError("tired")
    return _right(*args)
''')
    result = check("a6", src, limits=LIMITS)
    run = next(t for t in result.tests if t.test.name.startswith("rigid_body_step: bodies"))
    assert [c.kind for c in run.cases] == ["error", "pass", "pass"]
    assert run.cases[0].reason.startswith("step 50 of 300: rigid_body_step raised "
                                          "RuntimeError: tired"), run.cases[0].reason
    assert result.score == result.max_score - run.test.points / 3


def _runs_test(result, name="rigid_body_step: bodies"):
    return next(t for t in result.tests if t.test.name.startswith(name))


def test_a_forged_frame_in_one_run_voids_the_whole_test(tmp_path):
    """As in a test of single calls: bytes written to the result channel in the middle of a
    run leave nothing of that test to trust, so every run of it scores 0, and the tests
    after it still run."""
    src = tmp_path / "a6_physics.py"
    src.write_text((FIXTURES / "a6" / "reference.py").read_text() + '''
import os as _os

_calls = [0]
_right = rigid_body_step


def rigid_body_step(*args):
    _calls[0] += 1
    if _calls[0] == 400:  # in the second run
        for fd in range(3, 1024):
            try:
                _os.write(fd, b"\\x00\\x00\\x00\\x05hello")
            except OSError:
                pass
    return _right(*args)
''')
    result = check("a6", src, limits=LIMITS)
    run = _runs_test(result)
    assert [c.kind for c in run.cases] == ["garbage"] * 3 and run.score == 0
    assert all("result channel" in c.reason for c in run.cases), run.cases[0].reason
    assert result.score == result.max_score - run.test.points


def _rollout_seconds(monkeypatch, seconds: dict[str, float], default: float | None = None):
    """a6 loaded with the rollout tests of each function of ``seconds`` given that many
    seconds (the others ``default``, or their own): small budgets, fast tests."""
    import autograder.assignments

    real_load = autograder.assignments.load

    def load(key):
        assignment = real_load(key)
        tests = tuple(
            dataclasses.replace(t, rollout=dataclasses.replace(
                t.rollout, seconds=seconds.get(t.function, default or t.rollout.seconds)))
            if t.rollout else t for t in assignment.tests)
        return dataclasses.replace(assignment, tests=tests)

    monkeypatch.setattr(autograder.assignments, "load", load)


RAN_OUT = re.compile(r'not run: the test "rigid_body_step: bodies simulated for 1\.5 s" ran out '
                     r"of its own 4 s after (\d+) of its 900 calls: a step took ([\d.]+) ms "
                     r"here \(.*\), and 4\.4 ms would run them all; a correct step takes ")


def test_a_slow_rollout_test_spends_only_its_own_time(tmp_path, monkeypatch):
    """Thousands of calls: a correct step at 20 ms a call (``slow_step.py``) in the first
    rollout test spends that test's own seconds (here 4 s, where its 900 calls need 18 s)
    and nothing of the others'. Its runs end there, and its report names it and says why
    (the calls made, the time a step took and the time that would do); the submission's
    budget (4 s too) has not run out for the tests after it (the other rollout tests have 60
    s of their own here), so every one of them runs and passes."""
    _rollout_seconds(monkeypatch, {"rigid_body_step": 4.0}, default=60.0)
    limits = dataclasses.replace(LIMITS, budget=4.0)
    result = check("a6", fixture_submission("a6", "slow_step.py", tmp_path), limits=limits)
    run = _runs_test(result)
    assert [c.kind for c in run.cases] == ["skipped"] * 3, [c.reason for c in run.cases]
    first, *later = [c.reason for c in run.cases]
    found = RAN_OUT.search(first)
    assert found and first.startswith("step ") and not first.startswith("step 1 "), first
    assert float(found[2]) >= 20 and 0 < int(found[1]) < 300, first  # in the first run
    assert all(r.startswith("step 1 of 300: ") and RAN_OUT.search(r) for r in later), later
    assert RAN_OUT.search(one_line(result)), one_line(result)  # the report says it
    assert run.elapsed < 4 + 3  # its own 4 s, not 900 steps x 20 ms
    others = [t for t in result.tests if t is not run]
    assert all(t.status == "passed" for t in others), [
        (t.test.name, t.first_failure and t.first_failure.reason) for t in others
        if t.status != "passed"]
    assert "whole time budget" not in one_line(result)
    assert result.score == result.max_score - run.test.points


def test_the_tests_before_a_rollout_test_cannot_spend_its_time(tmp_path):
    """Single calls that use up the whole budget (here 1.5 s, at 0.3 s a call) leave each
    rollout test its own seconds: they run and pass, while the single-call tests after the
    budget ran out score 0 and say so."""
    src = tmp_path / "a6_physics.py"
    src.write_text((FIXTURES / "a6" / "reference.py").read_text() + '''
import time as _time

_right = rigid_body_step


def rigid_body_step(*args):
    if args[-1] != 0.005:  # most of the single calls; no step of a run (h = 0.005 there)
        _time.sleep(0.3)
    return _right(*args)
''')
    result = check("a6", src, limits=dataclasses.replace(LIMITS, budget=1.5))
    rollouts = [t for t in result.tests if t.test.rollout is not None]
    assert len(rollouts) == 3 and all(t.status == "passed" for t in rollouts), [
        (t.test.name, t.first_failure and t.first_failure.reason) for t in rollouts]
    single = [t for t in result.tests if t.test.rollout is None]
    assert all(c.kind == "skipped" and "whole time budget" in c.reason
               for t in single[2:] for c in t.cases), [(t.test.name, t.cases[0].reason)
                                                       for t in single[2:]]
    assert result.score == sum(t.test.points for t in rollouts) + sum(
        t.score for t in single[:2])
