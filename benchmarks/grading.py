"""Grading a class: the local pool against a Dask ``LocalCluster`` with as many workers.

Run:  .venv/bin/python benchmarks/grading.py [--n 200] [--workers 2] [--assignment a3]

The class is ``--n`` honest submissions of the assignment, generated from the reference
fixture (``tests/fixtures/<assignment>/reference.py``, each with its own comment, so that
every file differs), one folder per student, graded with a seed (hidden tests included).
Figures printed (wall-clock seconds; the machine may be shared, so the two paths are timed
in alternation, ``--repeats`` rounds, and the best of each is kept):

- local pool: ``grade(..., jobs=W)``, the baseline;
- cluster: ``grade(..., scheduler=ADDRESS)`` on a ``LocalCluster`` of W single-threaded
  worker processes already running, and its overhead over the local pool (goal <= 15 %);
- start-up: what ``--scheduler local:W`` adds once per batch (starting the cluster, each
  worker probing its sandbox and importing the assignment);
- throughput per worker and the worker-seconds one submission costs on the cluster path,
  from which the time of 10,000 submissions on 50 workers is projected;
- that the results are the same on both paths.
"""

from __future__ import annotations

import argparse
import csv
import logging
import os
import tempfile
import time
from pathlib import Path

from autograder.assignments import load
from autograder.grading import collect, grade

REPO = Path(__file__).resolve().parents[1]
SEED = "benchmark-seed"


def make_class(root: Path, key: str, n: int) -> Path:
    """``n`` student folders holding the reference, each with its own comment."""
    template = load(key).template
    reference = (REPO / "tests" / "fixtures" / key / "reference.py").read_text()
    for i in range(n):
        folder = root / f"student{i:05d}"
        folder.mkdir(parents=True)
        (folder / template).write_text(f"# student {i}: my own work\n{reference}")
    return root


def scores(out: Path) -> list[tuple[str, str]]:
    with open(out / "grades.csv", newline="") as f:
        return [(r["submission"], r["score"]) for r in csv.DictReader(f)]


def timed(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=200, help="submissions (default 200)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                        help="local threads and cluster workers (default: one per CPU)")
    parser.add_argument("--assignment", default="a3")
    parser.add_argument("--repeats", type=int, default=2, help="rounds of both (default 2)")
    args = parser.parse_args()
    if min(args.n, args.workers, args.repeats) < 1:
        parser.error("--n, --workers and --repeats must be positive")
    import dask
    from distributed import LocalCluster

    assignment = load(args.assignment)
    w = args.workers
    with tempfile.TemporaryDirectory(prefix="grading-bench-") as tmp:
        root = Path(tmp)
        subs = collect([make_class(root / "class", args.assignment, args.n)], assignment.template)
        common = {"seed": SEED, "progress": None}
        start = time.perf_counter()
        with dask.config.set({"distributed.scheduler.allowed-failures": 2}):
            cluster = LocalCluster(n_workers=w, threads_per_worker=1, processes=True,
                                   dashboard_address=":0", silence_logs=logging.ERROR)
        with cluster:
            grade(assignment, subs[:w], root / "warm-up", scheduler=cluster.scheduler_address,
                  **common)  # the workers probe their sandbox and import the assignment
            startup = time.perf_counter() - start
            local, warm = [], []
            for _ in range(args.repeats):
                local.append(timed(lambda: grade(assignment, subs, root / "local", jobs=w,
                                                 **common)))
                warm.append(timed(lambda: grade(assignment, subs, root / "cluster",
                                                scheduler=cluster.scheduler_address, **common)))
        same = scores(root / "local") == scores(root / "cluster")
    local, warm = min(local), min(warm)
    cost = warm * w / args.n  # worker-seconds per submission on the cluster path
    print(f"{args.n} honest {args.assignment} submissions, {w} workers "
          f"({os.cpu_count()} CPUs here)")
    print(f"  local pool (jobs={w}):   {local:7.2f} s   baseline (best of {args.repeats})")
    print(f"  cluster:                {warm:7.2f} s   overhead {100 * (warm / local - 1):+.1f} %"
          "   (goal <= +15 %)")
    print(f"  cluster start-up:       {startup:7.2f} s   once per batch with --scheduler local:{w}")
    print(f"  throughput per worker: local {args.n / local / w:.2f}, cluster "
          f"{args.n / warm / w:.2f} submissions/s; {cost:.3f} worker-s per submission")
    print(f"  projected: 10,000 submissions on 50 workers ~ {10_000 * cost / 50 / 60:.1f} min "
          "(at this machine's per-submission cost, start-up not included)")
    print(f"  same results on both paths: {same}")


if __name__ == "__main__":
    main()
