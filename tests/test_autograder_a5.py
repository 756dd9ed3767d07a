"""The a5 (keyframes and implicit Euler) autograder: its references against independent ones,
its judge of the implicit step, and fixture submissions (the reference, each catalogued
mistake, partial and hostile work). The step is judged by its optimality, computed here."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from grading_fixtures import FIXTURES, LIMITS, fixture_submission, one_line, visible_cases

from autograder import check
from autograder.assignments import load
from autograder.assignments.a5 import (
    LINE_SEARCH_CASE,
    catmull_rom_variants,
    dense_newton,
    line_search_iterates,
    newton_iterates,
    spring_hessian,
    squad_formula,
    step_problems,
    step_reference,
    well_posed,
)
from autograder.judging import diagnose
from autograder.results import CaseResult
from course.physics import SpringSystem
from course.physics import step as course_step

REPO = Path(__file__).resolve().parents[1]
A5 = load("a5")


# --- the references and the judge --------------------------------------------------------------


def test_catmull_rom_reproduces_a_quadratic_on_even_keys_and_the_variants_differ():
    times = np.arange(5.0)
    keys = np.stack([times**2, 3 * times], axis=1)  # central differences are exact here
    t = np.linspace(1, 3, 9)  # away from the one-sided end tangents
    cr = A5.function("catmull_rom").reference
    np.testing.assert_allclose(cr(keys, times, t), np.stack([t**2, 3 * t], axis=1), atol=1e-12)
    for c in visible_cases(A5, "catmull_rom"):
        keys, times, at = c.args  # the scalings agree at keys, for h = 1 and for two keys
        if len(times) > 2 and not np.allclose(np.diff(times), 1.0) and not np.all(
                np.isin(at, times)):
            expected = cr(*c.args)
            assert all(not np.allclose(w, expected, atol=1e-6)
                       for w in catmull_rom_variants(*c.args).values()), c.label


def test_squad_written_out_is_the_library_and_without_the_flip_it_is_not():
    squad = A5.function("squad")
    flipped = 0
    for c in visible_cases(A5, "squad"):
        expected = squad.reference(*c.args)
        assert squad.check.close(squad_formula(*c.args), expected), c.label
        q = c.args[0]
        if np.any(np.sum(q[1:] * q[:-1], axis=1) < 0) and len(np.unique(q, axis=0)) > 2:
            assert not squad.check.close(squad_formula(*c.args, shortest=False), expected)
            flipped += 1
    assert flipped >= 6


def test_controls_built_before_the_flip_are_named_whichever_way_the_slerps_go():
    """The controls built from the keys as stored: with the slerps the shortest way (the
    fixture's) or the inner slerp and the blend as they are (the template's), the same
    mistake, told apart from the keys left unflipped."""
    fn = A5.function("squad")
    for as_they_are in (False, True):
        results = []
        for c in visible_cases(A5, "squad"):
            got = squad_formula(*c.args, controls="stored", as_they_are=as_they_are)
            expected = fn.reference(*c.args)
            results.append(CaseResult(c, "pass" if fn.check.close(got, expected) else "wrong",
                                      got=got, expected=expected))
        assert sum(not r.passed for r in results) >= 6
        assert diagnose(A5, fn, results).key == "controls_from_stored_keys"


def test_the_frozen_hessian_with_line_search_is_named_by_its_iterates_not_by_nearness():
    """Its slow iteration passes close to every nearly right answer: an answer a little off
    the minimiser is not named, the iterate where the template's 50 iterations stop is."""
    frozen = next(m for m in A5.misconceptions if m.key == "frozen_hessian_line_search")
    rng = np.random.default_rng(12)
    stopped = near = 0
    for c in visible_cases(A5, "implicit_euler_step"):
        x, h, fixed = c.args[0], c.args[6], c.args[7]
        *_, z = line_search_iterates(c.args, 50, frozen=True)
        if step_problems((z, (z - x) / h), *c.args):
            assert frozen.symptom((z, (z - x) / h), *c.args), c.label
            stopped += 1
        off = step_reference(*c.args)[0] + 1e-5 * rng.normal(size=x.shape)
        off[fixed] = x[fixed]
        if step_problems((off, (off - x) / h), *c.args):
            assert not frozen.symptom((off, (off - x) / h), *c.args), c.label
            near += 1
    assert stopped >= 3 and near >= 10


def test_the_step_reference_is_a_dense_newton_and_the_hessian_its_finite_differences():
    step = A5.function("implicit_euler_step")
    for c in visible_cases(A5, "implicit_euler_step"):
        expected = step.reference(*c.args)
        assert step.check.close(dense_newton(*c.args), expected), c.label
        library = course_step(SpringSystem.create(*c.args[2:6], c.args[7], c.args[8]),
                              c.args[0], c.args[1], c.args[6], tol=1e-11, max_iter=100,
                              solver="direct")
        np.testing.assert_allclose(library.x, expected[0], atol=1e-9, err_msg=c.label)
        assert step_problems(expected, *c.args) == [], c.label
        if c.label != LINE_SEARCH_CASE:  # the edge cases too: the template's Newton is enough
            assert well_posed(c.args), c.label
    x, _, _, springs, rest, k, *_ = visible_cases(A5, "implicit_euler_step")[3].args
    assert np.any(np.linalg.norm(x[springs[:, 0]] - x[springs[:, 1]], axis=1) < rest)
    system = SpringSystem.create(np.ones(len(x)), springs, rest, k)
    eps, H = 1e-6, spring_hessian(x, springs, rest, k)
    for col in (0, 4, 3 * len(x) - 1):
        dx = np.zeros(3 * len(x))
        dx[col] = eps
        fd = (system.spring_gradient(x + dx.reshape(-1, 3))
              - system.spring_gradient(x - dx.reshape(-1, 3))).ravel() / (2 * eps)
        np.testing.assert_allclose(H[:, col], fd, atol=1e-5)


def test_the_step_judge_names_the_broken_condition():
    case = next(c for c in visible_cases(A5, "implicit_euler_step") if "one spring" in c.label)
    x, v, masses, springs, rest, k, h, fixed, gravity = case.args
    right = A5.function("implicit_euler_step").reference(*case.args)
    moved = (right[0] + [0.0, 0.1, 0.0], right[1])
    assert step_problems(moved, *case.args)[0].startswith("fixed particle 0 moved by 0.1")
    short = (x + 0.5 * (right[0] - x), right[1])
    assert "does not minimise E(x)" in step_problems(short, *case.args)[0]
    assert step_problems((right[0], right[1] + 1.0), *case.args) == [
        "v⁺ differs from (x⁺ - x)/h by up to 1; implicit Euler's x⁺ = x + h v⁺ makes "
        "v⁺ = (x⁺ - x)/h"]


# --- fixture submissions -----------------------------------------------------------------------


def test_the_unclipped_segment_index_is_explained_at_the_last_key(tmp_path):
    result = check("a5", fixture_submission("a5", "mutant_catmull_last_key.py", tmp_path),
                   limits=LIMITS)
    edges = next(t for t in result.tests if t.test.name == "catmull_rom: edge cases")
    first = edges.cases[0]
    assert first.kind == "error" and first.reason.startswith("catmull_rom raised IndexError")
    assert first.reason.endswith("t = 2.5 is the last key; np.searchsorted(times, t, "
                                 "side='right') - 1 gives 1, a segment [t_1, t_2] that does not "
                                 "exist: clip i to K - 2 = 0 (the last segment ends at the last "
                                 "key, u = 1)")


def test_the_missing_hessian_term_shows_on_compressed_springs(tmp_path):
    result = check("a5", fixture_submission("a5", "mutant_step_hessian_no_term.py", tmp_path),
                   limits=LIMITS)
    random = next(t for t in result.tests if t.test.name == "implicit_euler_step: random cases")
    failed = [c.case.label for c in random.cases if not c.passed]
    assert failed and all("squeezed" in label for label in failed)
    assert 0 < random.score < random.test.points


def test_controls_for_even_keys_get_partial_credit(tmp_path):
    result = check("a5", fixture_submission("a5", "mutant_squad_even_controls.py", tmp_path),
                   limits=LIMITS)
    random, edges = (t for t in result.tests if t.test.function == "squad")
    assert random.score == 0 and 0 < edges.score < 1
    assert random.misconception.key == edges.misconception.key == "even_controls"
    passed = {c.case.label for c in edges.cases if c.passed}
    assert {"two keys: SQUAD is SLERP", "one key per second"} <= passed
    assert all(t.status == "passed" for t in result.tests if t.test.function != "squad")


def test_running_the_course_library_is_refused(tmp_path):
    src = fixture_submission("a5", "adv_reads_the_library.py", tmp_path)
    src.write_text(src.read_text().replace("@REPO@", str(REPO)))
    result = check("a5", src, limits=LIMITS)
    step = [t for t in result.tests if t.test.function == "implicit_euler_step"]
    assert all(t.n_passed == 0 for t in step)
    assert (f"does not let submissions open '{REPO}/course/physics/mass_spring.py'"
            in " ".join(str(result).split()))


def test_scipy_is_refused_before_anything_runs():
    result = check("a5", FIXTURES / "a5" / "adv_import_scipy.py", limits=LIMITS)
    assert result.score == 0
    assert ("`from scipy.sparse.linalg import ...` is not allowed: the assignment asks you to "
            "implement the math yourself with numpy") in " ".join(str(result).split())


# --- the template's Newton ends, and needs its line search ---------------------------------------


def test_the_line_search_case_needs_the_line_search():
    case = next(c for c in visible_cases(A5, "implicit_euler_step") if c.label == LINE_SEARCH_CASE)
    right = A5.function("implicit_euler_step").reference(*case.args)
    assert step_problems(right, *case.args) == []
    full = newton_iterates(case.args, 50)[-1]  # full Newton steps do not settle
    assert step_problems((full, (full - case.args[0]) / case.args[6]), *case.args)


def test_the_template_written_literally_ends_and_scores_full_marks(tmp_path):
    """Halving α until Armijo holds, with the now-stated slack, α floor, relative threshold
    and 50-iteration cap, ends on every case (hanging cloth #2 once hung) and is right."""
    result = check("a5", fixture_submission("a5", "template_literal.py", tmp_path),
                   seed="fixture-seed-a5", limits=LIMITS)
    assert result.score == result.max_score, one_line(result)


def test_another_minimiser_as_low_is_accepted():
    """The step is judged by ∇E ≈ 0 and E no higher than at the reference, not by equality:
    the same minimiser to 1e-5 (beyond x's 1e-6 comparison) with ∇E small passes."""
    step = A5.function("implicit_euler_step")
    case = next(c for c in visible_cases(A5, "implicit_euler_step") if "6×6" in c.label)
    right = step.reference(*case.args)
    assert step.check.judge(right, right, case.args) is None


def test_a_timeout_of_the_step_names_the_likely_cause():
    from autograder.judging import Outcome, judge

    fn = A5.function("implicit_euler_step")
    case = visible_cases(A5, "implicit_euler_step")[0]
    out = Outcome("timeout", message="implicit_euler_step did not finish within 1 s")
    verdict = judge(fn, case, None, out, None, str, ())
    assert "a Newton loop that never meets its stopping test" in verdict.reason
    assert "cap the iterations at 50" in verdict.reason


def test_spline_rows_are_named_by_their_time_and_shown_to_the_digit_that_differs():
    fn = A5.function("catmull_rom")
    keys, times = np.zeros((3, 3)), np.array([0.0, 2.5, 4.0])
    t = np.array([0.0, 2.5, 3.0])
    expected = np.array([[0.0, 0, 0], [-0.1214, -0.2371, 0.0071], [0, 0, 0]])
    got = expected.copy()
    got[1, 0] += 4e-5
    why = fn.check.judge(got, expected, (keys, times, t))
    assert why.startswith("time index 1 (t = 2.5 s, key 1's time) is at [-0.12136, ")
    assert "expected [-0.1214, " in why
