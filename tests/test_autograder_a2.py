"""The a2 (forward kinematics) autograder: its references against independent ones, its case
generators, and fixture submissions (the reference, each catalogued mistake, partial and
hostile work), each getting the right score and a specific message."""

from __future__ import annotations

import numpy as np
import pytest
from grading_fixtures import FIXTURES, LIMITS, fixture_submission, seed, visible_cases

from autograder import check
from autograder.assignments import load
from autograder.spec import case_rng

SEED = seed("a2")
A2 = load("a2")


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
    from autograder.findings import Findings
    from autograder.gradescope_json import results_json
    from autograder.judging import prepare
    from autograder.report import csv_header

    result = check("a2", FIXTURES / "a2" / "reference.py", limits=LIMITS)
    unscored = [t.test.name for t in result.tests if not t.test.points]
    assert len(unscored) == 2 and "real clips on this machine (unscored) 12/12 cases" in " ".join(
        str(result).split())  # shown to the student ...
    found = Findings.of(result)
    assert not set(unscored) & set(csv_header(found))  # ... not in the class's results
    assert not set(unscored) & {t["name"] for t in results_json(found, "")["tests"]}

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
