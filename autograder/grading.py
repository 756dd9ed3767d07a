"""Grade a whole class: many submissions in parallel, one result file each, one CSV.

Each submission runs in its own sandboxed child, so threads are enough here: the
grading process only sends inputs, compares arrays and writes files. A submission that
breaks anything only loses its own points; the batch always finishes.
"""

from __future__ import annotations

import json
import sys
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path
from typing import TextIO

from .report import csv_header, csv_row, gradescope, write_csv
from .runner import Result, TestResult, prepare, run
from .sandbox import DEFAULT_LIMITS, Limits, level_for
from .spec import Assignment

SUFFIXES = (".py", ".ipynb")


def collect(paths: list[Path], template: str) -> list[tuple[str, Path]]:
    """``(name, file)`` per submission: files as given; in a directory, its ``.py`` and
    ``.ipynb`` files (named by their stem) and its subdirectories holding the template or
    a single such file (named by the subdirectory, as in a Gradescope or LMS export)."""
    found: list[tuple[str, Path]] = []
    for p in paths:
        if p.is_file():
            found.append((p.stem, p))
        elif p.is_dir():
            for child in sorted(p.iterdir()):
                if child.is_file() and child.suffix in SUFFIXES:
                    found.append((child.stem, child))
                elif child.is_dir():
                    inner = _one_submission(child, template)
                    if inner:
                        found.append((child.name, inner))
        else:
            raise ValueError(f"submissions: {p} does not exist")
    names: dict[str, int] = {}
    unique = []
    for name, path in found:
        names[name] = names.get(name, 0) + 1
        unique.append((name if names[name] == 1 else f"{name}-{names[name]}", path))
    return unique


def _one_submission(folder: Path, template: str) -> Path | None:
    stem = Path(template).stem
    for suffix in SUFFIXES:
        if (folder / f"{stem}{suffix}").is_file():
            return folder / f"{stem}{suffix}"
    files = [f for f in folder.rglob("*") if f.is_file() and f.suffix in SUFFIXES]
    return files[0] if len(files) == 1 else None


def grade(assignment: Assignment, submissions: list[tuple[str, Path]], out: Path, *,
          jobs: int = 1, seed: str | None = None, limits: Limits = DEFAULT_LIMITS,
          progress: TextIO | None = sys.stderr, level: str | None = None) -> list[dict]:
    """Grade every submission; write ``out/<name>/results.json`` and ``out/grades.csv``.
    ``level``: the sandbox's isolation (default: the strongest here)."""
    out.mkdir(parents=True, exist_ok=True)
    prepare(assignment, seed)  # once, before the threads start
    level = level_for(level)  # probed once, too
    bar = Progress(len(submissions), progress)
    rows: dict[str, dict] = {}
    header = None
    with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        futures = {pool.submit(_grade_one, assignment, path, seed, limits, level): (name, path)
                   for name, path in submissions}
        for future in as_completed(futures):
            name, path = futures[future]
            result = future.result()
            folder = out / name
            folder.mkdir(exist_ok=True)
            (folder / "results.json").write_text(json.dumps(gradescope(result), indent=1))
            rows[name] = csv_row(name, result)
            header = header or csv_header(result)
            bar.step(name, result)
    bar.close()
    ordered = [rows[name] for name, _ in submissions]
    if header:
        write_csv(out / "grades.csv", header, ordered)
    return ordered


def _grade_one(assignment: Assignment, path: Path, seed: str | None, limits: Limits,
               level: str) -> Result:
    try:
        return run(assignment, path, seed, limits, level)
    except Exception as exc:  # a bug of ours must not stop the class's grading
        tests = [TestResult(p.test, assignment.function(p.test.function),
                            note="not run: the grader failed on this submission")
                 for p in prepare(assignment, seed)]
        return Result(assignment, path, tests, seed is not None, isolation=level,
                      problems=[f"the grader failed ({type(exc).__name__}: {exc}); "
                                "please report this"])


class Progress:
    """A one-line progress bar on a terminal; a line per tenth of the work otherwise."""

    def __init__(self, total: int, stream: TextIO | None, width: int = 30):
        self.total, self.stream, self.width = total, stream, width
        self.done = 0
        self.start = time.monotonic()
        self.tty = bool(stream and stream.isatty())

    def step(self, name: str, result: Result) -> None:
        self.done += 1
        if not self.stream:
            return
        elapsed = time.monotonic() - self.start
        if self.tty:
            fill = self.width * self.done // max(self.total, 1)
            self.stream.write(f"\r[{'#' * fill}{'.' * (self.width - fill)}] "
                              f"{self.done}/{self.total}  {elapsed:.0f} s  {name[:30]:<30}")
        elif self.done == self.total or self.done % max(1, self.total // 10) == 0:
            self.stream.write(f"graded {self.done}/{self.total} ({elapsed:.0f} s)\n")
        self.stream.flush()

    def close(self) -> None:
        if self.stream and self.tty:
            self.stream.write("\n")
            self.stream.flush()
