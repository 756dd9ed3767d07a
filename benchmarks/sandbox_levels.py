"""The sandbox's kernel levels side by side: child start-up, and a class graded.

Run (as root, for the chroot level):
    .venv/bin/python benchmarks/sandbox_levels.py [--starts 20] [--n 100] [--jobs 2]

Figures (wall-clock; the machine may be shared, so the levels alternate and medians are
kept), each level against ``bubblewrap`` as the baseline:

- start-up: one child started and its (empty) submission loaded, then stopped; at the
  chroot level that includes leasing a user and ending its processes on release;
- a class: ``--n`` honest submissions of a3 (the reference, each with its own comment),
  graded with a seed at ``--jobs``, the budget being 2 minutes for 100 at 2 jobs.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

from autograder.assignments import load
from autograder.grading import collect, grade
from autograder.sandbox import Limits, Sandbox, isolation

REPO = Path(__file__).resolve().parents[1]
LEVELS = ("bubblewrap", "chroot")


def start_up(level: str) -> float:
    t = time.perf_counter()
    with Sandbox("", [], Limits(), frozenset(), level=level) as box:
        assert box.start().status == "ok"
    return time.perf_counter() - t


def a_class(level: str, n: int, jobs: int) -> float:
    spec = load("a3")
    reference = (REPO / "tests" / "fixtures" / "a3" / "reference.py").read_text()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for i in range(n):
            folder = root / "class" / f"student{i:03d}"
            folder.mkdir(parents=True)
            (folder / spec.template).write_text(f"# student {i}\n{reference}")
        t = time.perf_counter()
        rows = grade(spec, collect([root / "class"], spec.template), root / "out", jobs=jobs,
                     seed="benchmark-seed", level=level, progress=None)
        elapsed = time.perf_counter() - t
    assert all(r["score"] >= r["max_score"] and r["isolation"] == level for r in rows)  # bonus
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--starts", type=int, default=20)
    parser.add_argument("--n", type=int, default=100)
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    levels = [lv for lv in LEVELS if lv != "bubblewrap" or isolation() == "bubblewrap"]
    for level in levels:
        start_up(level)  # stage the runtime once
    starts: dict[str, list[float]] = {lv: [] for lv in levels}
    for _ in range(args.starts):
        for level in levels:
            starts[level].append(start_up(level))
    base = statistics.median(starts[levels[0]])
    for level in levels:
        m = statistics.median(starts[level])
        print(f"start-up {level:10s}: median {1000 * m:6.1f} ms  "
              f"(min {1000 * min(starts[level]):.1f}, max {1000 * max(starts[level]):.1f}); "
              f"{m / base:.2f} x {levels[0]}")
    for level in levels:
        s = a_class(level, args.n, args.jobs)
        print(f"{args.n} honest a3, --jobs {args.jobs}, {level:10s}: {s:6.1f} s "
              f"(budget 120 s)")


if __name__ == "__main__":
    main()
