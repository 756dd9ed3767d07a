"""The a1 autograder on fixture submissions: the reference, every catalogued mistake, partly
right work and hostile code. Each gets the right score and a clear, specific message."""

from __future__ import annotations

import re
import time
from pathlib import Path

import pytest

from autograder import Limits, check
from autograder.assignments import load
from autograder.sandbox import isolation

FIXTURES = Path(__file__).parent / "fixtures" / "a1"
REPO = Path(__file__).resolve().parents[1]
TEMPLATE = REPO / "assignments" / "a1_rotations.py"
LIMITS = Limits(cpu_seconds=5, memory_mb=600, load_timeout=5.0, case_timeout=0.5)
SEED = "fixture-seed-7f3a"
A1 = load("a1")


def submission(name: str, tmp_path: Path) -> Path:
    """A fixture as a file; ``# extends: reference.py`` fixtures are appended to it, and
    ``@REPO@`` stands for this checkout (what a hostile submission would try to read)."""
    src = (FIXTURES / name).read_text().replace("@REPO@", str(REPO))
    if src.startswith("# extends: reference.py"):
        src = (FIXTURES / "reference.py").read_text() + "\n\n" + src
    path = tmp_path / "a1_rotations.py"
    path.write_text(src)
    return path


def by_function(result, fn: str):
    return [t for t in result.tests if t.test.function == fn]


@pytest.mark.parametrize("level", [None, "portable"])
def test_reference_gets_full_marks_including_hidden_tests(level):
    result = check("a1", FIXTURES / "reference.py", seed=SEED, limits=LIMITS, isolation=level)
    assert result.hidden_run and result.score == result.max_score == 24
    assert "Score: 24 / 24 (all tests)" in str(result)


def test_template_runs_visible_tests_only_and_says_not_implemented(monkeypatch):
    monkeypatch.delenv("AUTOGRADER_SEED", raising=False)
    result = check("a1", TEMPLATE, limits=LIMITS)
    assert not result.hidden_run and result.score == 0 and result.max_score == 12
    assert {t.status for t in result.tests} == {"not_implemented"}
    text = str(result)
    assert "Visible tests only" in text and text.count("not implemented yet") == 12


MUTANTS = sorted(p.name for p in FIXTURES.glob("mutant_*.py"))


def test_catalogue_covers_every_mutant_and_is_rich_enough():
    expected = {re.search(r"# expect: (\S+)", (FIXTURES / m).read_text()).group(1)
                for m in MUTANTS}
    own = {f"{m.function}:{m.key}" for m in A1.misconceptions}
    assert own <= expected <= {f"{m.function}:{m.key}" for m in A1.catalogue}
    assert {m.key for m in A1.shared} <= {e.split(":")[1] for e in expected}
    assert len(expected) >= 6


@pytest.mark.parametrize(("name", "level"), [(m, None) for m in MUTANTS]
                         + [(m, "portable") for m in MUTANTS[::6]])
def test_mutant_is_diagnosed_by_name(name, level, tmp_path):
    fn, key = re.search(r"# expect: (\S+)", (FIXTURES / name).read_text()).group(1).split(":")
    result = check("a1", submission(name, tmp_path), seed=SEED, limits=LIMITS, isolation=level)
    failing = [t for t in result.tests if t.status != "passed"]
    assert failing and all(t.test.function == fn for t in failing)
    assert all(t.misconception and t.misconception.key == key for t in failing)
    assert result.score == result.max_score - sum(t.test.points - t.score for t in failing)
    title = failing[0].misconception.title
    assert f"Likely mistake, {title}" in str(result)


def test_partial_work_gets_the_fraction_of_cases_passed(tmp_path):
    result = check("a1", submission("partial_euler_tait_bryan_only.py", tmp_path), seed=SEED,
                   limits=LIMITS)
    random, edges, hidden = by_function(result, "matrix_from_euler")
    assert random.score == 1.0
    assert edges.n_passed == 6 and edges.score == pytest.approx(0.75)  # ZXZ, YXY fail
    proper = sum(len(set(c.case.args[1])) < 3 for c in hidden.cases)
    assert hidden.score == pytest.approx(2.0 * (24 - proper) / 24)
    assert "raised ValueError: order ZXZ not supported" in str(result)


# name -> (visible score, phrases the report must contain)
ADVERSARIAL = {
    "adv_infinite_loop.py": (10, ["quat_mul did not finish within 0.5 s on this case (an "
                                  "endless loop, or too slow?)"]),
    "adv_memory_bomb.py": (10, ["matrix_from_quat raised MemoryError", "limit is 600 MB"]),
    "adv_exits.py": (6, ["quat_from_matrix raised SystemExit", "quat_mul raised Escape",
                         "the interpreter exited (code 0) while slerp ran; does your code call"]),
    "adv_fake_score.py": (0, ["something else wrote to the grader's private result channel",
                              "matrix_from_quat returned None; did you forget a `return`?",
                              "Your code printed (the grader ignores it)"]),
    "adv_always_equal.py": (0, ["returned an object of type Anything, expected a numpy array",
                                "returned a list of 4 items", "off by up to"]),
    "adv_wrong_types.py": (2, ["quat_from_matrix returned shape (3,), expected (4,)",
                               "matrix_from_quat returned shape (9,), expected (3, 3)",
                               "quat_from_axis_angle returned booleans, expected numbers",
                               "matrix_from_euler returned None",
                               "slerp returned NaN or infinity: [nan, nan, nan, nan]"]),
    "adv_monkeypatch.py": (0, ["is not a unit quaternion (|q| = 0)", "off by up to"]),
    "adv_snooping.py": (0, ["seed in env: None", "does not let submissions open",
                            "os.listdir outside their working directory",
                            "importing 'socket' is not allowed"]),
    "adv_fork.py": (10, ["the autograder does not let submissions use os.fork"]),
    "adv_import_course.py": (0, ["Refused: line 3: `from course.rotations import ...` is not "
                                 "allowed: the course library is the reference you are "
                                 "compared with"]),
    "adv_import_course_hidden.py": (0, ["importing 'course.rotations' is not allowed here"]),
    # The sandbox's own defences: none of these reads the reference or memory.
    "adv_patched_builtins.py": (10, [f"quat_mul raised PermissionError: the autograder does not "
                                     f"let submissions open '{REPO}/course/rotations/"
                                     "quaternion.py'"]),
    "adv_patched_os_path.py": (10, [f"quat_mul raised PermissionError: the autograder does not "
                                    f"let submissions open '{REPO}/course/rotations/"
                                    "quaternion.py'"]),
    "adv_ctypes_memory.py": (10, ["quat_mul raised ImportError: importing 'ctypes' is not "
                                  "allowed here"]),
    "adv_reads_reference.py": (0, [f"your file could not be loaded: PermissionError: the "
                                   f"autograder does not let submissions open '{REPO}/course/"
                                   "rotations/_checks.py'"]),
    "adv_hook_tampering.py": (10, ["quat_mul raised RuntimeError: the autograder does not let "
                                   "submissions open", "gc: the autograder does not let "
                                   "submissions use gc.get_objects", "resolve.__code__: the "
                                   "autograder does not let submissions replace code objects"]),
    "adv_forged_recursion.py": (0, ["while your file loaded, something else wrote to the "
                                    "grader's private result channel; nothing can be graded "
                                    "(JSON nested too deeply)"]),
    "adv_garbage_bytes.py": (10, ["while quat_mul ran, something else wrote to the grader's "
                                  "private result channel; this test scores 0 (not JSON"]),
    "adv_tcl_exec.py": (10, ["quat_mul raised RuntimeError: reached ['tkinter: ImportError', "
                             "'_tkinter: ImportError']"]),
    "adv_huge_answer.py": (10, ["far more numbers than the 80 that could make sense here"]),
    # threads up to its own limit: no harm to anyone, full marks for correct answers
    "adv_threads.py": (12, []),
    # bwrap's refusal forged after the child started: the submission's own failure, scored
    "adv_fake_refusal.py": (0, ["Refused: your file could not be loaded: the interpreter "
                                "exited (code 1) while your file ran", "(the last line it "
                                "wrote: bwrap: Creating new namespace failed"]),
}
# The portable level (Windows) has no memory limit: the bomb's 32 GiB would really be filled.
PORTABLE_HOSTILE = sorted(set(ADVERSARIAL) - {"adv_memory_bomb.py"})


@pytest.mark.parametrize(("name", "level"), [(n, None) for n in sorted(ADVERSARIAL)]
                         + [(n, "portable") for n in PORTABLE_HOSTILE])
def test_hostile_submission_earns_nothing_it_did_not_compute(name, level, tmp_path, monkeypatch):
    """At the strongest level here and at the portable one (stdin/stdout pipes, a reader
    thread for the deadlines, no rlimits): the same scores and messages."""
    monkeypatch.setenv("AUTOGRADER_SEED", SEED)  # in the grader's environment, not the child's
    path = submission(name, tmp_path)
    result = check("a1", path, seed="", limits=LIMITS, isolation=level)  # "": the env seed
    assert result.isolation == (level or isolation())
    score, phrases = ADVERSARIAL[name]
    visible = sum(t.score for t in result.tests if not t.test.hidden)
    assert visible == score
    assert not result.not_graded  # a machine fault is no way out of a score
    text = " ".join(str(result).split())  # as one line: the report wraps at 100 columns
    for phrase in phrases:
        assert phrase in text
    assert SEED not in text and SEED not in result.output
    assert not (tmp_path / "results.json").exists()


def test_processes_and_files_outside_the_sandbox_do_not_survive(tmp_path):
    markers = [Path("/tmp/autograder-fork-marker"), Path("/tmp/autograder-escape-marker")]
    for m in markers:
        m.unlink(missing_ok=True)
    check("a1", submission("adv_fork.py", tmp_path), limits=LIMITS)
    check("a1", submission("adv_snooping.py", tmp_path), limits=LIMITS)
    time.sleep(1.8)  # the forked child would have written its marker after 1.5 s
    assert not any(m.exists() for m in markers)


def test_without_namespaces_the_sandbox_still_holds(tmp_path, monkeypatch):
    import autograder.sandbox

    monkeypatch.setattr(autograder.sandbox, "isolation", lambda: "plain")
    assert check("a1", FIXTURES / "reference.py", limits=LIMITS).score == 12
    result = check("a1", submission("adv_fork.py", tmp_path), limits=LIMITS)
    assert result.score == 10 and "use os.fork" in str(result)
