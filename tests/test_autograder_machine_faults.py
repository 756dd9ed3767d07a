"""No classmate, host daemon or machine fault costs a submission a point.

At the kernel levels each submission's sandbox runs as a user id leased for it alone, so the
threads another submission (or a daemon running as ``nobody``) holds count against no one
else's limit; a sandbox the machine cannot start is retried, and then the submission is *not
graded* (no score, its own status, ``grade`` exits non-zero) and ``--resume`` grades exactly
those again; and a submission cannot pass its own failure off as the machine's.
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
import threading
from pathlib import Path

import pytest

import autograder.runner
import autograder.sandbox
from autograder import check, grading
from autograder.assignments import load
from autograder.cli import NOT_GRADED_EXIT, main
from autograder.grading import collect, grade
from autograder.limits import Limits
from autograder.sandbox import Isolation, isolation

REPO = Path(__file__).resolve().parents[1]
FIXTURES = REPO / "tests" / "fixtures" / "a1"
A1 = load("a1")
LIMITS = Limits(cpu_seconds=8, memory_mb=600, load_timeout=10.0, case_timeout=2.0)
NOBODY = 65534
A1_MAX = 24  # with the hidden tests
KERNEL_LEVELS = [level for level in (Isolation.BUBBLEWRAP, Isolation.CHROOT)
                 if isolation().rank <= level.rank and (level is Isolation.BUBBLEWRAP
                                                        or os.geteuid() == 0)]
ROOT = pytest.mark.skipif(os.geteuid() != 0 or sys.platform != "linux",
                          reason="leased user ids need a root grader on Linux")


def source(name: str) -> str:
    text = (FIXTURES / f"{name}.py").read_text()
    if text.startswith("# extends: reference.py"):
        text = (FIXTURES / "reference.py").read_text() + "\n\n" + text
    return text


def class_folder(root: Path, students: dict[str, str]) -> Path:
    """One folder per student holding ``a1_rotations.py`` made from a fixture."""
    for student, fixture in students.items():
        (root / student).mkdir(parents=True)
        (root / student / "a1_rotations.py").write_text(source(fixture))
    return root


def rows(out: Path) -> dict[str, dict[str, str]]:
    with open(out / "grades.csv", newline="") as f:
        return {r["submission"]: r for r in csv.DictReader(f)}


@pytest.fixture
def nobody_holding_threads():
    """A host process running as ``nobody`` that holds 40 threads (a daemon, or what an
    earlier grader's sandbox left): before user ids were leased at the bubblewrap level,
    every sandbox's bwrap ran as that same user, and its 32-thread limit was already full."""
    code = ("import os, sys, threading, time\n"
            f"os.setgroups([]); os.setgid({NOBODY}); os.setuid({NOBODY})\n"
            "for _ in range(40):\n"
            "    threading.Thread(target=time.sleep, args=(120,), daemon=True).start()\n"
            "print('holding', flush=True)\n"
            "sys.stdin.read()\n")
    holder = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "holding\n"
        threads = len(os.listdir(f"/proc/{holder.pid}/task"))
        assert threads > 32, threads
        yield holder
    finally:
        holder.kill()
        holder.wait()


@ROOT
@pytest.mark.parametrize("level", KERNEL_LEVELS)
def test_a_daemon_running_as_nobody_costs_a_submission_nothing(level, nobody_holding_threads):
    result = check("a1", FIXTURES / "reference.py", limits=LIMITS, isolation=level)
    assert result.isolation == level
    assert not result.not_graded and not result.problems, str(result)
    assert result.score == result.max_score, str(result)


@ROOT
@pytest.mark.parametrize("level", KERNEL_LEVELS)
def test_a_classmate_holding_every_thread_it_may_costs_no_one_a_point(level, tmp_path):
    """Three correct submissions graded at once beside one that holds as many threads as its
    sandbox lets it start, on each of its calls: every one gets full marks, the holder too."""
    students = {"holder": "adv_threads", **{f"honest{i}": "reference" for i in range(3)}}
    subs = collect([class_folder(tmp_path / "class", students)], A1)
    out = tmp_path / "out"
    grade(A1, subs, out, jobs=4, seed="threads-seed", limits=LIMITS, level=level,
          progress=None)
    got = rows(out)
    assert {n: (r["status"], r["score"]) for n, r in got.items()} == {
        n: ("graded", str(float(A1_MAX))) for n in students}, got



@pytest.fixture
def machine_refuses(monkeypatch):
    """Every start of a sandbox for a source holding ``# the machine refuses`` fails as
    bubblewrap does when the kernel refuses it a namespace (its words on stderr, exit 1,
    before the submission's first instruction)."""
    command = autograder.sandbox.Sandbox._command
    starts: list[str] = []

    def refusing(self, config, program=None):
        cmd, fds = command(self, config, program)
        if "# the machine refuses" not in self.source:
            return cmd, fds
        starts.append(self.source)
        return ["/bin/sh", "-c", 'echo "bwrap: Can\'t fork for pid 1: Resource temporarily '
                'unavailable" >&2; exit 1', "sh", *cmd], fds

    monkeypatch.setattr(autograder.sandbox.Sandbox, "_command", refusing)
    monkeypatch.setattr(autograder.runner, "MACHINE_PAUSE", 0.0)
    return starts


def test_a_sandbox_that_never_starts_is_not_graded_and_resume_grades_it(
        tmp_path, machine_refuses, monkeypatch, capsys):
    folder = class_folder(tmp_path / "class", {"alice": "reference", "bob": "reference"})
    bob = folder / "bob" / "a1_rotations.py"
    bob.write_text(bob.read_text() + "\n# the machine refuses\n")
    seed_file = tmp_path / "seed"
    seed_file.write_text("fault-seed\n")
    out = tmp_path / "out"
    args = ["grade", "--assignment", "a1", str(folder), "--out", str(out), "--jobs", "2",
            "--seed-file", str(seed_file), "--lms", "canvas"]
    assert main(args) == NOT_GRADED_EXIT
    said = capsys.readouterr().err
    assert "graded 1 of 2 submissions" in said
    assert ("error: 1 submission not graded, the grading machine's fault (no score written): "
            "bob. Run the same command again with --resume to grade exactly those.") in said
    starts = len(machine_refuses)
    assert starts == autograder.sandbox.START_ATTEMPTS * autograder.runner.MACHINE_ATTEMPTS

    got = rows(out)
    assert got["alice"]["status"] == "graded" and got["alice"]["score"] == "24.0"
    bob_row = got["bob"]
    assert bob_row["status"] == "not graded" and bob_row["score"] == ""
    assert all(bob_row[t.name] == "" for t in A1.tests if t.points)
    assert "bwrap: Can't fork for pid 1" in bob_row["reason"]
    results = json.loads((out / "bob" / "results.json").read_text())
    assert "score" not in results and results["tests"] == []
    assert "Not graded: the sandbox could not start" in results["output"]
    assert not (out / "bob" / grading.STATE).exists()  # nothing to resume from
    with open(out / "grades-canvas.csv", newline="") as f:  # an LMS keeps bob's grade as is
        exported = list(csv.DictReader(f))
    assert len(exported) == 2 and "24.0" in exported[1].values()  # points possible + alice
    summary = (out / "summary.html").read_text()
    assert "2 submissions, 1 graded, 0 refused, 1 not graded" in summary

    # the machine is mended: --resume grades bob, and bob alone
    monkeypatch.undo()
    graded: list[str] = []
    grade_one = grading._grade_one

    def counting(assignment, s, *a):
        graded.append(s.name)
        return grade_one(assignment, s, *a)

    monkeypatch.setattr(grading, "_grade_one", counting)
    assert main([*args, "--resume"]) == 0
    assert graded == ["bob"]
    got = rows(out)
    assert got["bob"]["status"] == "graded" and got["bob"]["score"] == "24.0"
    assert (out / "bob" / grading.STATE).exists()


def test_a_grader_fault_is_not_graded_either(tmp_path, monkeypatch):
    """A bug of ours is no more the student's than the machine's: no score, resumable."""
    def broken(*args, **kwargs):
        raise KeyError("a bug")

    monkeypatch.setattr(grading, "run", broken)
    out = tmp_path / "out"
    folder = class_folder(tmp_path / "class", {"carol": "reference"})
    grade(A1, collect([folder], A1), out, progress=None)
    row = rows(out)["carol"]
    assert row["status"] == "not graded" and row["score"] == ""
    assert "the grader failed (KeyError: 'a bug'); please report this" in row["reason"]


def test_the_pool_and_the_cluster_give_one_score_under_load(tmp_path):
    """The honest and hostile a1 fixtures, graded with one seed three times by the local pool
    and three times by a cluster of two worker processes, the pool and the cluster running at
    the same time (each the other's load): every submission gets the same row every time."""
    pytest.importorskip("distributed")
    # (no fixture whose score a case's wall-clock limit decides: an endless loop, a slow one)
    names = ["reference", "legit_stdlib_heavy", "mutant_mul_reversed", "adv_exits",
             "adv_threads", "adv_fork", "adv_memory_bomb", "adv_garbage_bytes",
             "adv_huge_answer", "adv_hook_tampering", "adv_fake_refusal", "adv_forged_recursion",
             "adv_tcl_exec"]
    subs = collect([class_folder(tmp_path / "class", {n: n for n in names})], A1)
    runs: dict[str, list[dict[str, tuple[str, ...]]]] = {"pool": [], "cluster": []}

    def graded(out: Path) -> dict[str, tuple[str, ...]]:
        return {n: (r["status"], r["score"], *(r[t.name] for t in A1.tests if t.points))
                for n, r in rows(out).items()}

    for attempt in range(3):
        pool_out, cluster_out = tmp_path / f"pool{attempt}", tmp_path / f"cluster{attempt}"
        pool = threading.Thread(target=grade, args=(A1, subs, pool_out), kwargs=dict(
            jobs=2, seed="one-seed", limits=LIMITS, progress=None))
        pool.start()
        grade(A1, subs, cluster_out, seed="one-seed", limits=LIMITS, scheduler="local:2",
              progress=None)
        pool.join()
        runs["pool"].append(graded(pool_out))
        runs["cluster"].append(graded(cluster_out))
    first = runs["pool"][0]
    differ = {f"{way} {i}": {n: row for n, row in got.items() if row != first[n]}
              for way, each in runs.items() for i, got in enumerate(each)}
    assert not any(differ.values()), (first, differ)
    assert not [n for n, row in first.items() if row[0] == "not graded"]
    assert first["reference"][1] == first["adv_threads"][1] == "24.0"
