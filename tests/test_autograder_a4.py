"""The a4 (IK on a character, rest poses) autograder: its judges, its references against
independent ones, and fixture submissions (the reference, each catalogued mistake, partial and
hostile work). IK answers are judged by forward kinematics and constraints, never by angles."""

from __future__ import annotations

import numpy as np
from grading_fixtures import ASSIGNMENTS, LIMITS, fixture_submission, one_line, seed, visible_cases

from autograder import check
from autograder.assignments import load
from autograder.assignments.a4 import (
    bone_directions,
    character,
    ik_problems,
    path_length,
    random_quats,
    retarget_problems,
)
from course import rotations as rot
from course.fk import forward_kinematics

TEMPLATE = ASSIGNMENTS / "a4_character.py"
SEED = seed("a4")
A4 = load("a4")


# --- the judges --------------------------------------------------------------------------------


def _foot_to_hand():
    names, parents, offsets = character()
    case = next(c for c in visible_cases(A4, "ik_local") if c.label.startswith(
        "the left foot planted, the left hand"))
    return names, case.args


def test_path_reference_goes_up_then_down_through_the_common_ancestor():
    names, parents, _ = character()
    fn = A4.function("path_to")
    got = [names[j] for j in fn.reference(parents, names.index("LeftFoot"),
                                          names.index("RightHand"))]
    assert got == ["LeftFoot", "LeftLeg", "LeftUpLeg", "Hips", "Spine", "Chest", "RightArm",
                   "RightForeArm", "RightHand"]


def test_any_answer_that_reaches_with_the_foot_planted_is_right_not_just_the_reference():
    from course.ik import solve
    from course.skeleton import Skeleton

    names, args = _foot_to_hand()
    parents, offsets, quats, root, fixed, effector, target, iterations = args
    sk = Skeleton(names, parents, offsets)
    answers = [np.array(solve(sk, quats, root, {effector: target}, method=m, root=fixed,
                              tol=1e-6, max_iter=500).local_rotations) for m in ("dls", "ccd")]
    assert np.max(rot.quat_angle(answers[0], answers[1])) > 1e-2  # different rotations ...
    assert ik_problems(answers[0], args) == ik_problems(answers[1], args) == []  # both right


def test_ik_judge_names_the_broken_constraint():
    names, args = _foot_to_hand()
    parents, offsets, quats, root, fixed, effector, target, iterations = args
    right = A4.function("ik_local").reference(*args)
    assert ik_problems(right, args) == []
    assert ik_problems(2 * right, args)[0].startswith("joint 0 is not a unit quaternion")
    head = names.index("Head")
    off_path = right.copy()
    off_path[head] = rot.quat_mul(off_path[head], rot.quat_from_axis_angle([1.0, 0, 0], 0.3))
    assert ik_problems(off_path, args)[0].startswith(f"joint {head} is off the path")
    turned = right.copy()
    turned[0] = rot.quat_mul(rot.quat_from_axis_angle([0.0, 1, 0], 0.2), turned[0])
    problems = ik_problems(turned, args)
    assert problems[0].startswith(f"the fixed joint {fixed} turned by 0.2 rad")
    assert "stopped" in problems[1]  # the whole body swung about the foot, the hand with it
    assert "stopped" in ik_problems(quats, args)[0]  # not solved at all


def test_ik_answers_are_placed_by_the_fixed_joint_not_by_joint_0():
    """The answer holds no root position: the reference's root moved around the planted foot,
    and the foot is where it was, in position and orientation."""
    from course.ik import solve
    from course.skeleton import Skeleton

    names, args = _foot_to_hand()
    parents, offsets, quats, root, fixed, effector, target, _ = args
    result = solve(Skeleton(names, parents, offsets), quats, root, {effector: target},
                   root=fixed, tol=1e-8, max_iter=400)
    P0, Q0 = forward_kinematics(parents, offsets, quats, root)
    P, Q = forward_kinematics(parents, offsets, result.local_rotations, result.root_position)
    assert np.linalg.norm(result.root_position - root) > 1e-2 * path_length(
        parents, offsets, fixed, effector)
    np.testing.assert_allclose(P[fixed], P0[fixed], atol=1e-9)
    assert rot.quat_angle(Q[fixed], Q0[fixed]) < 1e-9
    assert ik_problems(result.local_rotations, args) == []


def test_retarget_judge_is_global_bone_directions_with_the_twist_free():
    case = visible_cases(A4, "retarget_rest")[0]  # the character, A pose to T pose
    parents, offsets_from, offsets_to, quats = case.args
    right = A4.function("retarget_rest").reference(*case.args)
    assert retarget_problems(right, *case.args) == []
    leaf = int(np.flatnonzero(np.bincount(parents[1:], minlength=len(parents)) == 0)[0])
    twisted = right.copy()  # a leaf has no bone below it: its rotation is free
    twisted[leaf] = rot.quat_mul(twisted[leaf], random_quats(np.random.default_rng(0), 1, 2)[0])
    assert retarget_problems(twisted, *case.args) == []
    copied = retarget_problems(quats, *case.args)  # the naive copy: the arms point wrongly
    assert copied and "bones in all" in copied[0]
    want = bone_directions(parents, offsets_from, quats)
    np.testing.assert_allclose(bone_directions(parents, offsets_to, right), want, atol=1e-9)


def test_ik_cases_are_solved_by_the_reference_in_a_quarter_of_the_iterations():
    fn = A4.function("ik_local")
    for c in visible_cases(A4, "ik_local"):
        quick = c.args._replace(iterations=c.args.iterations // 4)
        assert ik_problems(fn.reference(*quick), c.args) == [], c.label


def test_symptoms_never_fire_on_right_answers_and_wrong_answers_differ():
    for m in A4.misconceptions:
        fn = A4.function(m.function)
        cases = visible_cases(A4, m.function)
        if m.caused_by is not None:  # found by calling the callee: see the path mutants
            assert any(u.name == m.caused_by for u in fn.uses), m.key
        elif m.symptom is not None:
            assert not any(m.symptom(fn.reference(*c.args), *c.args) for c in cases), m.key
        else:
            assert any(not fn.check.close(m.wrong(*c.args), fn.reference(*c.args))
                       for c in cases), m.key


# --- fixture submissions -----------------------------------------------------------------------


def test_rotations_left_as_they_were_earn_nothing_for_ik(tmp_path):
    result = check("a4", fixture_submission("a4", "adv_ik_returns_input.py", tmp_path),
                   seed=SEED, limits=LIMITS)
    ik = [t for t in result.tests if t.test.function == "ik_local"]
    assert all(t.score == 0 for t in ik)
    assert "stopped" in one_line(result) and "from the target" in one_line(result)


def test_an_ik_that_moves_joints_off_the_path_is_told_which(tmp_path):
    result = check("a4", fixture_submission("a4", "partial_ik_whole_body.py", tmp_path),
                   seed=SEED, limits=LIMITS)
    ik = [t for t in result.tests if t.test.function == "ik_local"]
    assert all(t.score < t.test.points for t in ik)
    assert "is off the path" in one_line(result)
    assert all(t.status == "passed" for t in result.tests if t.test.function != "ik_local")


def test_html_report_pictures_the_pose_and_the_target(tmp_path):
    page = check("a4", fixture_submission("a4", "mutant_ik_root_moved.py", tmp_path),
                 limits=LIMITS)._repr_html_()
    assert "data:image/png;base64," in page
    assert "the fixed joint kept in place" in page


def test_the_notebook_loads_with_its_template(tmp_path):
    """What the grader keeps of the notebook's display cells loads: the template's stubs are
    all it sees of the functions."""
    import shutil

    for suffix in (".ipynb", ".py"):
        shutil.copy(TEMPLATE.with_suffix(suffix), tmp_path)
    result = check("a4", tmp_path / "a4_character.ipynb", limits=LIMITS)
    assert not result.problems, result.problems
    assert {t.status for t in result.tests} == {"not_implemented"}


def test_the_templates_method_solves_every_visible_case():
    """The wrong-joint symptom is the template's CCD with one rule changed: the course's CCD,
    run from the given pose and stopped as the template says, solves every case."""
    from course.ik import solve
    from course.skeleton import Skeleton

    for c in visible_cases(A4, "ik_local"):
        case = c.args
        names = [f"joint{j}" for j in range(len(case.parents))]
        result = solve(Skeleton(names, case.parents, case.offsets), case.local_quats,
                       case.root_position, {case.effector: case.target}, method="ccd",
                       root=case.fixed, tol=1e-5 * case.scale, max_iter=case.iterations,
                       reach_start=False)
        assert ik_problems(result.local_rotations, case) == [], c.label
