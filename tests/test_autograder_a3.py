"""The a3 (inverse kinematics) autograder: its judges of IK answers, its references against
independent ones, and fixture submissions (the reference, each catalogued mistake, partial and
hostile work). IK answers are judged by what they achieve, never by one reference pose."""

from __future__ import annotations

import numpy as np
import pytest
from grading_fixtures import LIMITS, fixture_submission, seed, visible_cases

from autograder import check
from autograder.assignments import load
from autograder.assignments.a3 import bones, chain_problems, random_chain, two_link_problems

SEED = seed("a3")
A3 = load("a3")


# --- the judges --------------------------------------------------------------------------------


def test_any_pose_that_reaches_is_right_not_just_the_reference():
    rng = np.random.default_rng(1)
    P = random_chain(rng, 5)
    t = P[0] + 0.5 * bones(P).sum() * np.array([0.0, 1.0, 0.0])
    from course.ik import ccd_positions, fabrik_positions

    a, b = ccd_positions(P, t, 1e-8, 500)[0], fabrik_positions(P, t, 1e-8, 500)[0]
    assert np.max(np.abs(a - b)) > 1e-2  # two different answers ...
    assert chain_problems(a, P, t, 1e-6) == chain_problems(b, P, t, 1e-6) == []  # both right


def test_chain_judge_names_the_broken_invariant():
    P = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]])
    t = np.array([1.0, 1.0, 0.0])
    moved = P + [0.5, 0, 0]
    assert chain_problems(moved, P, t, 1e-4)[0].startswith("the root moved from [0, 0, 0]")
    pulled = P.copy()
    pulled[2] = [1.5, 0.5, 0.0]  # the effector put on a target, the bone left behind
    assert chain_problems(pulled, P, pulled[2], 1e-4) == [
        "bone 1 (joint 1 to 2) has length 0.7071, was 1; joints turn, bones keep their lengths"]
    far = np.array([5.0, 0.0, 0.0])
    assert chain_problems(P, P, far, 1e-4) == []  # already stretched at it
    bent = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0]])
    assert "out of reach" in chain_problems(bent, bent, far, 1e-4)[0]


def test_two_link_judge_is_the_law_of_cosines_and_the_pole_plane():
    from course.ik import two_link

    rng = np.random.default_rng(2)
    for _ in range(20):
        a, b, c = random_chain(rng, 3, bend=1.5)
        t = a + rng.uniform(0.1, 1.4) * (bones(np.array([a, b, c])).sum()) * np.array([0, 0, 1.0])
        pole = a + rng.normal(size=3)
        mid, end, _ = two_link(a, b, c, t, pole)
        assert two_link_problems((mid, end), a, b, c, t, pole) == []
        mirror, _, _ = two_link(a, b, c, t, pole, flip=True)
        if np.linalg.norm(mirror - mid) > 1e-3:
            assert two_link_problems((mirror, end), a, b, c, t, pole) == [
                "the middle joint bends away from the pole"]


def test_jacobian_reference_is_the_closed_form_and_dls_the_normal_equations():
    from course.ik import chain_jacobian
    from course.ik import dls_step as course_dls

    jac, dls = A3.function("jacobian"), A3.function("dls_step")
    for c in visible_cases(A3, "jacobian"):
        P, axes = c.args
        closed = chain_jacobian(P[:-1], axes, P[-1])
        assert jac.check.compare(jac.reference(*c.args), closed) is None, c.label
    for c in visible_cases(A3, "dls_step"):
        J, e, lam = c.args
        step = dls.reference(*c.args)
        np.testing.assert_allclose(step, course_dls(J, e, lam), atol=1e-8)
        if lam > 0:  # bounded at singular poses: |dθ| <= |e| / 2λ
            assert np.linalg.norm(step) <= np.linalg.norm(e) / (2 * lam) + 1e-12


def test_solver_cases_are_solvable_by_the_reference_within_a_quarter_of_max_iter():
    for fn in ("ccd", "fabrik"):
        f = A3.function(fn)
        for c in visible_cases(A3, fn):
            P, t, tol, max_iter = c.args
            assert chain_problems(f.reference(*c.args), P, t, tol) == [], (fn, c.label)


def test_symptoms_never_fire_on_right_answers_and_wrong_answers_differ():
    for m in A3.misconceptions:
        fn = A3.function(m.function)
        cases = visible_cases(A3, m.function)
        if m.symptom is not None:
            assert not any(m.symptom(fn.reference(*c.args), *c.args) for c in cases), m.key
        else:
            assert any(not fn.check.close(m.wrong(*c.args), fn.reference(*c.args))
                       for c in cases), m.key


# --- fixture submissions -----------------------------------------------------------------------


def test_a_solver_ignoring_max_iter_loses_the_cases_it_cannot_finish(tmp_path):
    result = check("a3", fixture_submission("a3", "partial_ccd_no_max_iter.py", tmp_path),
                   seed=SEED, limits=LIMITS)
    random, edges, hidden = (t for t in result.tests if t.test.function == "ccd")
    assert random.status == "passed" and 0 < hidden.score < 2
    # Limits are per case: the unreachable targets time out, the case after them still
    # passes in a fresh interpreter, and after two timeouts the rest of the test is skipped.
    kinds = [c.kind for c in edges.cases]
    assert kinds[:3] == ["timeout", "pass", "timeout"] and set(kinds[3:]) == {"skipped"}
    assert edges.score == pytest.approx(1 / len(kinds))
    assert edges.cases[-1].reason == "not run: 2 cases of this test stopped the interpreter"
    text = " ".join(str(result).split())
    assert "ccd did not finish within 1 s on this case" in text
    assert "Also stopped the interpreter (the same): one bone, the target out of reach" in text


@pytest.mark.parametrize("name", ["adv_ik_returns_input.py", "adv_ik_effector_only.py"])
def test_ik_without_moving_the_bones_earns_nothing(name, tmp_path):
    result = check("a3", fixture_submission("a3", name, tmp_path), seed=SEED, limits=LIMITS)
    for t in result.tests:
        if t.test.function in ("ccd", "fabrik", "two_link_ik", "trace_curve") and (
                t.test.function != "two_link_ik" or "effector" in name):
            assert t.score == 0, t.test.name
    text = " ".join(str(result).split())
    if "returns_input" in name:
        assert "Likely mistake, the chain never moved" in text
    else:
        assert "has length" in text and "joints turn, bones keep their lengths" in text


def test_the_undamped_step_at_a_singular_pose_says_what_happened(tmp_path):
    result = check("a3", fixture_submission("a3", "mutant_dls_inverse_no_damping.py", tmp_path),
                   limits=LIMITS)
    edges = next(t for t in result.tests if t.test.name == "dls_step: edge cases")
    stretched = edges.cases[0]
    assert stretched.kind == "error" and edges.misconception.key == "no_damping"
    assert stretched.reason.startswith("dls_step raised LinAlgError: Singular matrix (line ")
    assert stretched.reason.endswith(
        "here J Jᵀ (3×3) has rank 1: a singular pose (the chain stretched), so (J Jᵀ)⁻¹ does not "
        "exist; J Jᵀ + λ²I (λ = 0.1) is invertible for any λ > 0")


def test_a_ccd_skipping_opposite_vectors_fails_only_the_target_behind(tmp_path):
    result = check("a3", fixture_submission("a3", "mutant_ccd_antiparallel_skipped.py", tmp_path),
                   limits=LIMITS)
    edges = next(t for t in result.tests if t.test.name == "ccd: edge cases")
    assert [c.case.label[:46] for c in edges.cases if not c.passed] == [
        "a straight chain, the target straight behind i"]
    behind = next(c for c in visible_cases(A3, "fabrik") if "straight behind" in c.label)
    P, t, tol, _ = behind.args
    assert np.allclose(P[:, :2], 0) and np.allclose(t, [0, 0, -2])  # P = 0..4 along z


def test_html_report_pictures_the_chain_and_the_target(tmp_path):
    page = check("a3", fixture_submission("a3", "mutant_fabrik_no_reanchor.py", tmp_path),
                 limits=LIMITS)._repr_html_()
    assert "data:image/png;base64," in page
    assert "fabrik: random cases, random chain #1" in page
    assert "your chain and the reference solver&#x27;s (one right answer of many)" in page
