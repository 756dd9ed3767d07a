"""The a2 (forward kinematics) autograder: its references against independent ones, its case
generators, and fixture submissions (the reference, each catalogued mistake, partial and
hostile work), each getting the right score and a specific message."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from autograder import Limits, check
from autograder.assignments import load
from autograder.results import Result
from autograder.spec import case_rng

FIXTURES = Path(__file__).parent / "fixtures"
ASSIGNMENTS = Path(__file__).parents[1] / "assignments"
LIMITS = Limits(cpu_seconds=8, memory_mb=600, load_timeout=5.0, case_timeout=1.0)
SEED = "fixture-seed-a2"
A2 = load("a2")


def fixture_submission(key: str, name: str, tmp_path: Path) -> Path:
    """A fixture as a file; ``# extends: reference.py`` fixtures are appended to it."""
    folder = FIXTURES / key
    src = (folder / name).read_text()
    if src.startswith("# extends: reference.py"):
        src = (folder / "reference.py").read_text() + "\n\n" + src
    path = tmp_path / f"{key}_submission.py"
    path.write_text(src)
    return path


def expectation(key: str, name: str) -> tuple[str, str]:
    """``(function, misconception key)`` from a mutant's ``# expect:`` line."""
    found = re.search(r"# expect: (\S+)", (FIXTURES / key / name).read_text())
    assert found, name
    fn, mistake = found.group(1).split(":")
    return fn, mistake


def assert_diagnosed(result: Result, fn: str, key: str) -> None:
    """Every failing test of ``fn`` names the mistake, the report says it, and only ``fn``
    (and functions that call it) lost points."""
    failing = [t for t in result.tests if t.status != "passed"]
    own = [t for t in failing if t.test.function == fn]
    assert own and all(t.misconception and t.misconception.key == key for t in own)
    title = own[0].misconception.title
    assert f"Likely mistake, {title}" in " ".join(str(result).split())
    assert all(t.test.function in (fn, "trace_curve") for t in failing)


def assert_catalogue_matches_fixtures(assignment, key: str) -> None:
    """Every mistake of the assignment's own catalogue has a mutant, every mutant names a
    catalogued mistake, and each shared mistake that can show here has at least one mutant."""
    mutants = sorted(p.name for p in (FIXTURES / key).glob("mutant_*.py"))
    expected = {":".join(expectation(key, m)) for m in mutants}
    own = {f"{m.function}:{m.key}" for m in assignment.misconceptions}
    assert own <= expected <= {f"{m.function}:{m.key}" for m in assignment.catalogue}
    shared = {m.key for m in assignment.shared}
    assert shared <= {e.split(":")[1] for e in expected}


def visible_cases(assignment, fn: str):
    tests = [t for t in assignment.tests if t.function == fn and not t.hidden]
    return [c for t in tests for c in t.cases(case_rng(t, None))]


# --- the references and the cases --------------------------------------------------------------


def test_generated_hierarchies_parse_like_their_own_description():
    from autograder.assignments.a2 import parse_reference, random_hierarchy

    rng = np.random.default_rng(3)
    for n in (1, 2, 9, 25):
        text = random_hierarchy(rng, n)
        names, parents, offsets = parse_reference(text)
        n_end = text.count("End Site")
        assert len(names) == n + n_end == len(parents) == len(offsets)
        assert parents[0] == -1 and all(parents[j] < j for j in range(1, len(parents)))
        assert sum(name.endswith("_end") for name in names) == n_end
        assert text.count("OFFSET") == len(names)


def test_fk_reference_matches_the_recursion_written_out(shared_bvh_dir):
    from course.bvh import load_bvh
    from course.rotations import quat_mul, quat_rotate

    motion = load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")
    fk = A2.function("forward_kinematics")
    sk, f = motion.skeleton, 100
    args = (np.asarray(sk.parents), sk.offsets, motion.local_rotations[f], motion.root_positions[f])
    positions, orientations = fk.reference(*args)
    P, Q = [motion.root_positions[f]], [motion.local_rotations[f, 0]]
    for i in range(1, sk.n_joints):
        p = sk.parents[i]
        Q.append(quat_mul(Q[p], motion.local_rotations[f, i]))
        P.append(P[p] + quat_rotate(Q[p], sk.offsets[i]))
    np.testing.assert_allclose(positions, P, atol=1e-9)
    assert fk.check.compare((positions, orientations), (np.array(P), -np.array(Q))) is None


def test_scored_cases_are_the_same_on_every_machine(monkeypatch):
    """The scored tests use only what the package ships and generates; the real clips a
    machine has add unscored tests and change no scored case."""
    from autograder.assignments import a2

    def scored_cases():
        return {t.name: [c.label for c in t.cases(case_rng(t, "s"))]
                for t in A2.tests if t.points}

    here = scored_cases()
    monkeypatch.setattr(a2, "local_clips", lambda: ())
    a2.clip_motion.cache_clear()
    assert scored_cases() == here
    labels = here["parse_bvh_hierarchy: sample files"]
    assert labels[0] == "the packaged wave clip" and len(labels) == 4
    texts = dict(a2.sample_files())
    assert "\r\n" in texts["sample file: CRLF line endings"]
    assert "End Site" not in texts["sample file: leaves with CHANNELS but no End Site, tabs"]
    rotation_first = texts["sample file: the root's rotation channels before its position, "
                           "mixed orders"]
    assert rotation_first.split("CHANNELS 6 ")[1].startswith(("Xrotation", "Yrotation",
                                                              "Zrotation"))


def test_the_real_clips_here_add_unscored_tests(shared_bvh_dir, tmp_path):
    from autograder.gradescope.feedback import results_json
    from autograder.report import csv_header
    from autograder.runner import prepare

    result = check("a2", FIXTURES / "a2" / "reference.py", limits=LIMITS)
    unscored = [t.test.name for t in result.tests if not t.test.points]
    assert len(unscored) == 2 and "real clips on this machine (unscored) 12/12 cases" in " ".join(
        str(result).split())  # shown to the student ...
    assert not set(unscored) & set(csv_header(result))  # ... not in the class's results
    assert not set(unscored) & {t["name"] for t in results_json(result, "")["tests"]}

    unscored = [p for p in prepare(A2, None) if not p.test.points]
    assert [p.test.function for p in unscored] == ["parse_bvh_hierarchy", "forward_kinematics"]
    labels = [c.label for c in unscored[0].cases]
    assert "the CMU walk (12_01)" in labels
    assert {f"edge case {p.name}" for p in (shared_bvh_dir / "edge_cases").glob("*.bvh")} <= set(
        labels)
    walk = next(c for c in unscored[0].cases if "CMU" in c.label)
    names, parents, _ = A2.function("parse_bvh_hierarchy").reference(*walk.args)
    assert len(names) == 38 and "LeftHand_end" not in names[:1] and names.count("Head_end") == 1


def test_every_catalogued_mistake_differs_from_the_reference():
    for m in A2.misconceptions:
        fn = A2.function(m.function)
        cases = visible_cases(A2, m.function)
        differs = [not fn.check.close(m.wrong(*c.args), fn.reference(*c.args)) for c in cases]
        assert any(differs), m.key


# --- fixture submissions -----------------------------------------------------------------------


def test_reference_gets_full_marks_and_the_bonus():
    result = check("a2", FIXTURES / "a2" / "reference.py", seed=SEED, limits=LIMITS)
    assert result.max_score == 11 and result.score == 13 and result.bonus_score == 2
    assert "Score: 13 / 11 (all tests, including 2 bonus points)" in str(result)


def test_template_is_not_implemented_yet(monkeypatch):
    monkeypatch.delenv("AUTOGRADER_SEED", raising=False)
    result = check("a2", ASSIGNMENTS / "a2_forward_kinematics.py", limits=LIMITS)
    assert result.score == 0 and {t.status for t in result.tests} == {"not_implemented"}


def test_catalogue_covers_every_mutant():
    assert_catalogue_matches_fixtures(A2, "a2")
    assert len(A2.misconceptions) >= 8


@pytest.mark.parametrize("name", sorted(p.name for p in (FIXTURES / "a2").glob("mutant_*.py")))
def test_mutant_is_diagnosed_by_name(name, tmp_path):
    fn, key = expectation("a2", name)
    result = check("a2", fixture_submission("a2", name, tmp_path), seed=SEED, limits=LIMITS)
    assert_diagnosed(result, fn, key)


def test_pose_assuming_positions_first_gets_partial_bonus(tmp_path):
    result = check("a2", fixture_submission("a2", "partial_pose_position_first.py", tmp_path),
                   seed=SEED, limits=LIMITS)
    visible = next(t for t in result.tests if t.test.name.startswith("pose_from_frame (bonus): s"))
    rotation_first = [c for c in visible.cases if "rotation channels before" in c.case.label]
    assert rotation_first and not any(c.passed for c in rotation_first)
    assert 0 < visible.score < 1 and result.score > result.max_score  # the core is all right


def test_reading_the_clips_from_disk_is_refused(tmp_path):
    result = check("a2", fixture_submission("a2", "adv_reads_the_files.py", tmp_path),
                   limits=LIMITS)
    parse = [t for t in result.tests if t.test.function == "parse_bvh_hierarchy"]
    assert all(t.n_passed == 0 for t in parse)
    assert "does not let submissions open '/work/shared/data/bvh/cmu_12_01_walk.bvh'" in " ".join(
        str(result).split())


@pytest.mark.parametrize(("name", "what"), [
    ("mutant_fk_own_orientation.py", "your forward kinematics and the expected pose"),
    ("mutant_parse_end_sites_dropped.py", "the rest pose of your hierarchy"),
    ("mutant_local_reversed_product.py", "the pose your local rotations give"),
    ("mutant_pose_degrees.py", "the pose your frame gives the file&#x27;s skeleton")])
def test_html_report_pictures_the_skeletons(name, what, tmp_path):
    page = check("a2", fixture_submission("a2", name, tmp_path), limits=LIMITS)._repr_html_()
    assert "data:image/png;base64," in page and what in page
