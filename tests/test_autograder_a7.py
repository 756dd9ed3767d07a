"""The a7 (capture point, SIMBICON's feedback, ZMP) autograder: its references against
independent ones (notebook 15's exercises, the pendulum run to rest, the forces' moment), the
hooks that plug a student's function into the library's controllers, and the runs on the
simulated CMU character that judge what the functions achieve."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from grading_fixtures import FIXTURES, LIMITS, visible_cases

from autograder import check
from autograder.assignments import load
from autograder.assignments.a7 import (
    STEP_LATE,
    capture_formula,
    cmu_character,
    hip_formula,
    zmp_formula,
)
from autograder.spec import case_rng
from course.exercises import nb15
from course.physics import lip

REPO = Path(__file__).resolve().parents[1]
A7 = load("a7")


def test_the_capture_point_is_where_the_pendulum_comes_to_rest():
    """The reference is the formula written out, notebook 15's exercise on single states,
    and a foot put there stops the library's pendulum: c → ξ, ċ → 0."""
    fn = A7.function("capture_point")
    for c in visible_cases(A7, "capture_point"):
        expected = fn.reference(*c.args)
        np.testing.assert_allclose(capture_formula(*c.args), expected, atol=1e-12)
        com, vel, ground, g = c.args
        if np.ndim(com) == 1 and g == lip.G:
            np.testing.assert_allclose(nb15.capture_point(com, vel, ground), expected,
                                       atol=1e-12)
        h = np.asarray(com)[..., 1] - np.asarray(ground)
        w = np.sqrt(g / h)[..., None]
        end, speed = lip.lip_state(15.0 / w, com[..., [0, 2]], vel[..., [0, 2]], expected, w)
        np.testing.assert_allclose(end, expected, atol=1e-6)
        np.testing.assert_allclose(speed, 0.0, atol=1e-6)


def test_the_feedback_is_notebook_15s_law_along_the_heading():
    fn = A7.function("swing_hip_target")
    for c in visible_cases(A7, "swing_hip_target"):
        expected = fn.reference(*c.args)
        if np.ndim(c.args[3]) == 1:
            assert abs(nb15.swing_hip_target(*c.args) - expected) < 1e-12, c.label
        else:
            for k in range(len(c.args[3])):
                one = (*c.args[:3], c.args[3][k], c.args[4][k], c.args[5][k], c.args[6])
                assert abs(nb15.swing_hip_target(*one) - expected[k]) < 1e-12


def test_the_zmp_has_no_horizontal_moment_and_is_notebook_15s():
    """About the reference's ZMP the forces' moment Σ (r - p) × f is vertical."""
    fn = A7.function("zmp_from_forces")
    for c in visible_cases(A7, "zmp_from_forces"):
        p = fn.reference(*c.args)
        r, f = np.asarray(c.args[0]), np.asarray(c.args[1])
        moment = np.cross(r - p[..., None, :], f).sum(axis=-2)
        np.testing.assert_allclose(moment[..., [0, 2]], 0.0, atol=1e-9)
        np.testing.assert_allclose(p[..., 1], c.args[2], atol=1e-15)
        np.testing.assert_allclose(zmp_formula(*c.args), p, atol=1e-12)
        if r.ndim == 2:
            np.testing.assert_allclose(nb15.zmp_from_forces(*c.args), p, atol=1e-12)


def test_every_mistake_is_wrong_somewhere_visible_and_tells_itself_apart():
    """Each named mistake differs from the reference on a visible case, and no two of one
    function give the same answers on every visible case (so each is diagnosed by name)."""
    for name in ("capture_point", "swing_hip_target", "zmp_from_forces"):
        fn, cases = A7.function(name), visible_cases(A7, name)
        answers = {}
        for m in A7.misconceptions_of(name):
            got = [np.asarray(m.wrong(*c.args)) for c in cases]
            assert any(not np.allclose(g, fn.reference(*c.args), atol=1e-6)
                       for g, c in zip(got, cases, strict=True)), m.key
            answers[m.key] = got
        keys = list(answers)
        for i, a in enumerate(keys):
            for b in keys[i + 1:]:
                assert any(not np.allclose(x, y, atol=1e-6) for x, y in
                           zip(answers[a], answers[b], strict=True)), (a, b)


def test_the_notebook_beside_a_right_solution_scores_full_marks(tmp_path):
    shutil.copy(REPO / "assignments" / "a7_walking.ipynb", tmp_path)
    shutil.copy(FIXTURES / "a7" / "reference.py", tmp_path / "a7_walking.py")
    result = check("a7", tmp_path / "a7_walking.ipynb", limits=LIMITS)
    assert not result.problems and result.score == result.max_score == 8


# --- the simulated character -----------------------------------------------------------------

needs_character = pytest.mark.skipif(cmu_character() is None,
                                     reason="MuJoCo or the CMU clip is missing here")


def rollout_test(function: str):
    test = next(t for t in A7.tests if t.rollout is not None and t.function == function)
    return test, test.cases(case_rng(test, None))


@needs_character
def test_the_hooks_give_the_librarys_answers():
    """SIMBICON's ``feedback`` hook with the a7 reference places the swing thigh as the
    built-in law does, and CaptureStep's ``capture_point`` hook finds the library's capture
    point and landing target, on a state of a run (the hooks' default None is the library's
    own code, unchanged: tests/test_physics_walking.py)."""
    import mujoco

    from autograder.assignments.a7 import capture_reference, character_simulation, hip_reference
    from course.physics.stepping import CaptureStep
    from course.physics.walking import SIMBICON

    walker = SIMBICON(cmu_character())
    sim = character_simulation(walker, np.array([0.0, 0.0, 0.3]))
    for _ in range(40):
        sim.step(walker)
    stance, swing = walker.legs()
    mujoco.mj_subtreeVel(sim.model, sim.data)
    built_in = walker.placement(sim, stance, swing)
    walker.feedback = hip_reference
    np.testing.assert_allclose(walker.placement(sim, stance, swing), built_in, atol=1e-12)

    stepper = CaptureStep(cmu_character())
    sim = character_simulation(stepper, np.array([0.0, 0.0, -0.27]))
    for _ in range(20):
        sim.step(stepper)
    legs = stepper.parts.left, stepper.parts.right
    own = stepper.capture(sim), stepper.landing(sim, *legs)
    stepper.capture_hook = capture_reference
    np.testing.assert_allclose(stepper.capture(sim), own[0], atol=1e-12)
    np.testing.assert_allclose(stepper.landing(sim, *legs), own[1], atol=1e-12)


@needs_character
def test_the_reference_runs_pass_and_a_correct_function_written_otherwise_too():
    """The reference's runs pass their own verdicts: the shoved character steps (first at
    1.43 s and 0.80 s) and stays up for 2.2 s, the walker walks 6 strides in 4 s through the
    push; a correct answer off by a relative 1e-12 (another order of operations) runs the
    same."""
    for name in ("capture_point", "swing_hip_target"):
        test, cases = rollout_test(name)
        fn = A7.function(name)
        assert len(cases) == 2
        for c in cases:
            ref = test.rollout.run(fn.reference, c.args)
            assert test.rollout.verdict(ref, ref, c.args) is None, c.label
            last = ref.states[-1]
            assert last.sim.fall_time is None
            if name == "capture_point":
                assert last.controller.capture_points
            else:
                assert len(last.controller.footsteps) // 2 >= 5
            nudged = test.rollout.run(lambda *a, f=fn: f.reference(*a) * (1 + 1e-12), c.args)
            assert test.rollout.verdict(nudged, ref, c.args) is None, c.label


@needs_character
@pytest.mark.parametrize(("key", "says"), [
    ("times_omega", "too early"),
    ("omega_not_rooted", "too late"),
    ("no_velocity", "too late"),
    ("c_d_sign", "the walker falls"),
    ("c_v_sign", "the walker falls"),
    ("d_from_origin", "the walker falls"),
])
def test_each_mistake_run_on_the_character_is_told_what_it_did(key, says):
    """A mistake that shows on the character fails its run (at least one case) and the
    verdict says what the character did; the COM's y for its height (the floor is 4 cm
    below y = 0 here) and the heading ignored (the walk is along +z) pass their runs and are
    caught by the single calls."""
    mistake = next(m for m in A7.misconceptions if m.key == key)
    test, cases = rollout_test(mistake.function)
    fn = A7.function(mistake.function)
    verdicts = []
    for c in cases:
        ref = test.rollout.run(fn.reference, c.args)
        verdicts.append(test.rollout.verdict(test.rollout.run(mistake.wrong, c.args), ref,
                                             c.args))
    failed = [v for v in verdicts if v is not None]
    assert failed and any(says in v for v in failed), verdicts
    assert STEP_LATE == 0.1


def test_hip_and_capture_mistakes_are_the_formulas_named():
    """Spot values: at heading 0 with the COM 10 cm ahead and 0.5 m/s forward, θ_d = 0.3 +
    0.8·0.1 + 0.3·0.5 = 0.53; flipped c_d 0.37; a COM 0.981 m up at 1 m/s has ξ 0.316 m ahead,
    ċ·ω₀ 3.16 m."""
    args = (0.3, 0.8, 0.3, np.array([0.1, 0.7, 2.1]), np.array([0.0, 0.0, 0.5]),
            np.array([0.1, 0.0, 2.0]), 0.0)
    assert abs(hip_formula(*args) - 0.53) < 1e-12
    assert abs(hip_formula(*args, sign_d=-1.0) - 0.37) < 1e-12
    state = (np.array([0.0, 0.981, 0.0]), np.array([0.0, 0.0, 1.0]), 0.0, 9.81)
    np.testing.assert_allclose(capture_formula(*state), [0.0, np.sqrt(0.981 / 9.81)])
    np.testing.assert_allclose(capture_formula(*state, velocity="times"),
                               [0.0, np.sqrt(9.81 / 0.981)])
