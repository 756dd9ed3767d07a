"""Grading on a Dask cluster: a LocalCluster of 2 worker processes gives the local pool's
results, a worker killed mid-batch loses no submission, ``--resume`` skips what is unchanged,
and workers weaker than ``--min-isolation`` are refused by name."""

from __future__ import annotations

import csv
import json
import logging
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

distributed = pytest.importorskip("distributed")

import cloudpickle  # noqa: E402  (installed with distributed)
import dask  # noqa: E402
from distributed import Client, LocalCluster  # noqa: E402
from distributed.diagnostics.plugin import WorkerPlugin  # noqa: E402

from autograder import Limits, grading  # noqa: E402
from autograder.assignments import load  # noqa: E402
from autograder.cluster import refuse_weak  # noqa: E402
from autograder.grading import collect, grade  # noqa: E402
from autograder.sandbox import probe  # noqa: E402

FIXTURES = Path(__file__).parent / "fixtures" / "a1"
REPO = Path(__file__).resolve().parents[1]
A1 = load("a1")
SEED = "cluster-seed-1"
#: generous per-case time: these tests compare two ways of running the same grading, and on a
#: loaded machine (the suite's other worker beside two Dask workers) a 0.5 s case limit let a
#: case time out on one path and not the other
LIMITS = Limits(cpu_seconds=5, memory_mb=600, load_timeout=10.0, case_timeout=2.0)
CLASS = ["reference", "mutant_mul_reversed", "mutant_slerp_lerp", "mutant_axis_degrees",
         "adv_exits", "adv_import_course"]
cloudpickle.register_pickle_by_value(sys.modules[__name__])  # the plugin below, on workers


def class_folder(root: Path, names: list[str] = CLASS) -> Path:
    """One folder per student holding ``a1_rotations.py`` made from a fixture (fragments
    marked ``# extends: reference.py`` appended to the reference)."""
    for name in names:
        src = (FIXTURES / f"{name}.py").read_text().replace("@REPO@", str(REPO))
        if src.startswith("# extends: reference.py"):
            src = (FIXTURES / "reference.py").read_text() + "\n\n" + src
        (root / name).mkdir(parents=True)
        (root / name / "a1_rotations.py").write_text(src)
    return root


def outputs(out: Path) -> tuple[list[dict], dict[str, dict]]:
    """grades.csv's rows and every results.json, without the times they took."""
    with open(out / "grades.csv", newline="") as f:
        rows = [{k: v for k, v in r.items() if k != "seconds"} for r in csv.DictReader(f)]
    results = {}
    for r in rows:
        data = json.loads((out / r["submission"] / "results.json").read_text())
        data.pop("execution_time")
        for test in data["tests"]:
            test["extra_data"].pop("execution_time")
        results[r["submission"]] = data
    return rows, results


@pytest.fixture(scope="module")
def cluster():
    with dask.config.set({"distributed.scheduler.allowed-failures": 2}):
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                          dashboard_address=":0", silence_logs=logging.ERROR) as c:
            yield c


@pytest.fixture(scope="module")
def students(tmp_path_factory):
    return collect([class_folder(tmp_path_factory.mktemp("class"))], A1)


class Killer(WorkerPlugin):
    """Kills its worker process (SIGKILL) as the task of a victim starts executing: on the
    first attempt only if ``marker`` is given (the file records that it happened), else on
    every attempt."""

    name = "killer"

    def __init__(self, victim: str, marker: str = ""):
        self.victim, self.marker = victim, marker

    def transition(self, key, start, finish, **kwargs):
        if finish != "executing" or not str(key).startswith(f"autograder-{self.victim}-"):
            return
        if self.marker:
            try:
                os.close(os.open(self.marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY))
            except FileExistsError:
                return
        os.kill(os.getpid(), signal.SIGKILL)


def test_a_local_cluster_gives_the_local_pools_results(cluster, students, tmp_path):
    here, there = tmp_path / "here", tmp_path / "there"
    grade(A1, students, here, jobs=2, seed=SEED, limits=LIMITS, progress=None)
    grade(A1, students, there, seed=SEED, limits=LIMITS, progress=None,
          scheduler=cluster.scheduler_address)
    rows, results = outputs(there)
    rows_here, results_here = outputs(here)
    differ = [r["submission"] for r, h in zip(rows, rows_here, strict=True) if r != h]
    assert not differ, f"the cluster graded {differ} differently: {rows} != {rows_here}"
    assert results == results_here
    assert {r["submission"]: float(r["score"]) for r in rows}["reference"] == 24
    assert len(rows) == len(CLASS) and len({r["score"] for r in rows}) > 3
    assert (there / "summary.html").read_text() == (here / "summary.html").read_text()


def test_a_worker_killed_mid_batch_costs_only_a_retry(cluster, students, tmp_path):
    marker = tmp_path / "killed-once"
    three = [s for s in students if s.name in CLASS[:3]]
    with Client(cluster) as client:
        client.register_plugin(Killer("mutant_slerp_lerp", str(marker)))
        try:
            grade(A1, three, tmp_path / "out", seed=SEED, limits=LIMITS, progress=None,
                  scheduler=cluster.scheduler_address)
        finally:
            client.unregister_worker_plugin(Killer.name)
        client.wait_for_workers(2, timeout=60)
    assert marker.exists()  # a worker did die
    rows, _ = outputs(tmp_path / "out")
    assert [r["submission"] for r in rows] == sorted(CLASS[:3])
    lerp = next(r for r in rows if r["submission"] == "mutant_slerp_lerp")
    assert lerp["status"] == "graded" and "slerp:lerp" in lerp["misconceptions"]


def test_a_submission_that_kills_every_worker_is_reported_not_lost(cluster, students,
                                                                    tmp_path):
    one = [s for s in students if s.name == "reference"]
    with Client(cluster) as client:
        client.run_on_scheduler(_allow_failures, n=1)
        client.register_plugin(Killer("reference"))
        try:
            grade(A1, one, tmp_path / "out", seed=SEED, limits=LIMITS, progress=None,
                  scheduler=cluster.scheduler_address)
        finally:
            client.unregister_worker_plugin(Killer.name)
            client.run_on_scheduler(_allow_failures, n=2)
        client.wait_for_workers(2, timeout=60)
    (row,), results = outputs(tmp_path / "out")
    # the machine's fault, not the student's: no score, and --resume grades it again
    assert row["submission"] == "reference" and row["score"] == ""
    assert row["status"] == "not graded"
    assert "died while grading it (2 attempts)" in row["reason"]
    assert "died while grading it" in results["reference"]["output"]
    assert "score" not in results["reference"]
    assert not (tmp_path / "out" / "reference" / grading.STATE).exists()


def _allow_failures(dask_scheduler=None, n: int = 2) -> None:
    dask_scheduler.allowed_failures = n


def test_resume_skips_what_is_unchanged_and_regrades_what_changed(cluster, tmp_path,
                                                                   monkeypatch):
    subs = collect([class_folder(tmp_path / "class", CLASS[:3])], A1)
    out = tmp_path / "out"
    grade(A1, subs, out, seed=SEED, limits=LIMITS, progress=None,
          scheduler=cluster.scheduler_address)  # the cluster's records are resumable here
    first, _ = outputs(out)
    graded: list[str] = []
    real_run = grading.run
    monkeypatch.setattr(grading, "run", lambda a, path, *args: graded.append(path.parent.name)
                        or real_run(a, path, *args))
    again = grade(A1, subs, out, seed=SEED, limits=LIMITS, progress=None, resume=True)
    assert graded == [] and outputs(out)[0] == first and len(again) == 3
    (tmp_path / "class" / "reference" / "a1_rotations.py").write_text(
        "import numpy as np\n")  # a resubmission: nothing left
    grade(A1, subs, out, seed=SEED, limits=LIMITS, progress=None, resume=True)
    assert graded == ["reference"]
    rows, _ = outputs(out)
    assert {r["submission"]: float(r["score"]) for r in rows}["reference"] == 0
    others = [r for r in first if r["submission"] != "reference"]
    assert [r for r in rows if r["submission"] != "reference"] == others
    graded.clear()
    grade(A1, subs, out, seed="another-seed", limits=LIMITS, progress=None, resume=True)
    assert sorted(graded) == sorted(CLASS[:3])  # other hidden cases: everyone again


@pytest.mark.skipif(probe().level != "bubblewrap", reason="needs a machine with bubblewrap")
def test_workers_weaker_than_min_isolation_are_refused_by_name(tmp_path):
    subs = collect([class_folder(tmp_path / "class", ["reference"])], A1)
    # no bwrap on the worker's PATH: it reaches a weaker level than this machine
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0",
                      silence_logs=logging.ERROR, env={"PATH": "/nonexistent"}) as weak:
        with pytest.raises(ValueError, match=r"--min-isolation bubblewrap: 1 of 1 workers are "
                                             r"weaker \(tcp://[^ ]+ reaches only "):
            grade(A1, subs, tmp_path / "out", seed=SEED, limits=LIMITS, progress=None,
                  scheduler=weak.scheduler_address)
    assert not (tmp_path / "out" / "reference").exists()  # nothing graded


def test_refuse_weak_names_every_weak_worker():
    refuse_weak({"tcp://a:1": "bubblewrap", "tcp://b:2": "plain"}, "plain")
    with pytest.raises(ValueError, match=r"2 of 3 workers are weaker \(tcp://b:2 reaches only "
                                         r"plain, tcp://c:3 reaches only portable\)"):
        refuse_weak({"tcp://a:1": "bubblewrap", "tcp://b:2": "plain", "tcp://c:3": "portable"},
                    "chroot")


def test_without_a_scheduler_dask_is_never_imported(tmp_path):
    class_folder(tmp_path / "class", ["adv_import_course"])  # refused before any sandbox
    code = ("import sys\nfrom autograder.cli import main\n"
            f"code = main(['grade', '--assignment', 'a1', {str(tmp_path / 'class')!r}, "
            f"'--out', {str(tmp_path / 'out')!r}, '--lms', 'canvas'])\n"
            "assert code == 0, code\n"
            "assert not {'dask', 'distributed'} & set(sys.modules), 'dask imported'\n")
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "out" / "grades-canvas.csv").exists()


def test_the_command_line_refuses_flags_that_do_not_go_together(capsys, tmp_path):
    from autograder.cli import main

    for argv, phrase in [(["--scheduler", "local:1", "--isolation", "plain"], "--isolation"),
                         (["--isolation", "plain"], "below the floor chroot: --isolation "
                                                     "plain asked for it")]:
        with pytest.raises(SystemExit):
            main(["grade", "--assignment", "a1", str(FIXTURES), "--out", "x", *argv])
        assert phrase in capsys.readouterr().err
    class_folder(tmp_path / "class", ["reference"])
    assert main(["grade", "--assignment", "a1", str(tmp_path / "class"), "--out",
                 str(tmp_path / "out"), "--scheduler", "local:two"]) == 1
    assert "N in local:N must be a positive integer" in capsys.readouterr().err
