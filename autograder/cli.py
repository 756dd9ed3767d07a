"""Command line: ``python -m autograder check a1``, ``python -m autograder grade ...`` and
``python -m autograder gradescope a1 --out a1_autograder.zip``."""

from __future__ import annotations

import argparse
import os
import stat
import sys
import time
from pathlib import Path
from typing import Any

from .assignments import KEYS, load
from .findings import Findings
from .grading import collect, grade
from .lms import FILES as LMS_FILES
from .report import NOT_GRADED, text
from .runner import default_submission, read_seed, run, seed_from_env
from .safe_text import printable
from .sandbox import FLOOR, LEVELS, Isolation, level_for, weaker_warning
from .spec import Assignment

NOT_GRADED_EXIT = 3  # grade's exit status when a submission could not be graded


def main(argv: list[str] | None = None) -> int:
    """Run ``python -m autograder`` with ``argv``: check, gradescope or grade; the exit
    status (a bad argument exits 2 with argparse's message naming it)."""
    parser = _parser()
    args = parser.parse_args(argv)
    if args.command == "gradescope":
        return _gradescope(parser, args)
    spec = load(args.assignment)
    try:
        seed = _seed(args)
        floor = None if args.command == "check" or args.scheduler else (
            args.min_isolation or FLOOR)
        level = level_for(args.isolation, floor)
    except ValueError as exc:
        parser.error(str(exc))
    if args.command == "check":
        return _check(parser, args, spec, seed, level)
    return _grade(parser, args, spec, seed, level)


def _parser() -> argparse.ArgumentParser:
    """The three commands and their arguments."""
    parser = argparse.ArgumentParser(prog="python -m autograder", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)

    c = sub.add_parser("check", help="check your own implementation (visible tests)")
    c.add_argument("assignment", choices=KEYS)
    c.add_argument("--submission", type=Path, help="a .py or .ipynb file (default: the "
                   "template, e.g. assignments/a1_rotations.py)")
    c.add_argument("--seed-file", help="instructors: a file holding the secret seed (- for "
                   "standard input), to add the hidden tests")
    c.add_argument("--seed", help=argparse.SUPPRESS)  # deprecated: argv is readable by all
    c.add_argument("--isolation", choices=LEVELS, help="the sandbox's isolation (default: the "
                   "strongest this machine allows)")

    z = sub.add_parser("gradescope", help="build the zip Gradescope's autograder takes "
                       "(instructors)")
    z.add_argument("assignment", choices=KEYS)
    z.add_argument("--out", required=True, type=Path, help="the zip to write")
    z.add_argument("--seed-file", type=Path, help="a file holding the secret seed (default: "
                   "a new one, printed once)")

    g = sub.add_parser("grade", help="grade many submissions (instructors)")
    g.add_argument("--assignment", required=True, choices=KEYS)
    g.add_argument("submissions", nargs="+", type=Path, help=".py/.ipynb files or folders")
    g.add_argument("--out", required=True, type=Path, help="folder for the results")
    g.add_argument("--jobs", type=int, default=1, help="submissions graded at once")
    g.add_argument("--seed-file", help="a file holding the secret seed of the hidden tests "
                   "(- for standard input; or $AUTOGRADER_SEED)")
    g.add_argument("--seed", help=argparse.SUPPRESS)  # deprecated: argv is readable by all
    g.add_argument("--isolation", choices=LEVELS, help="the sandbox's isolation (default: the "
                   "strongest this machine allows)")
    g.add_argument("--scheduler", metavar="ADDRESS", help="grade on a Dask cluster: a "
                   "scheduler's address, or local[:N] for N worker processes here (needs the "
                   "'cluster' extra)")
    g.add_argument("--min-isolation", choices=LEVELS, help=f"refuse to grade (here, or on a "
                   f"--scheduler's workers) below this level (default: {FLOOR}; with "
                   "--scheduler, the strongest the scheduler's machine gives if stronger)")
    g.add_argument("--resume", action="store_true", help="skip submissions already graded "
                   "in --out and unchanged since")
    g.add_argument("--lms", action="append", default=[], choices=LMS_FILES, help="also write "
                   "the totals as this LMS imports them (grades-<lms>.csv; may be repeated)")
    return parser


def _gradescope(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """``gradescope``: build the bundle's zip."""
    from .gradescope.bundle import build, built_message  # only this command needs them

    try:
        made = build(args.assignment, args.out, args.seed_file)
    except ValueError as exc:
        parser.error(str(exc))
    print(built_message(args.out, made), file=sys.stderr)
    return 0


def _grade(parser: argparse.ArgumentParser, args: argparse.Namespace, spec: Assignment,
           seed: str | None, level: Isolation) -> int:
    """``grade``: a class's submissions, on a local pool or a cluster."""
    if args.scheduler and args.isolation:
        parser.error("--isolation: with --scheduler each worker grades at its strongest; "
                     "give --min-isolation instead")
    try:
        submissions = collect(args.submissions, spec)
    except ValueError as exc:
        parser.error(str(exc))
    if not submissions:
        parser.error("submissions: no .py or .ipynb files found")
    if not seed:
        print("warning: no --seed-file or $AUTOGRADER_SEED: grading the visible tests only",
              file=sys.stderr)
    warning = weaker_warning(level)
    if warning:
        print(warning, file=sys.stderr)
    try:
        args.out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        parser.error(f"--out: cannot make the folder {printable(args.out)} ({exc.strerror})")
    start = time.monotonic()
    try:
        rows = grade(spec, submissions, args.out, jobs=args.jobs, seed=seed, level=level,
                     scheduler=args.scheduler, min_isolation=args.min_isolation,
                     resume=args.resume, lms=args.lms)
    except (OSError, ValueError) as exc:  # grades.csv cannot be written, a worker too weak...
        print(f"error: {exc}", file=sys.stderr)
        return 1
    return _graded(rows, args.out, time.monotonic() - start)


def _check(parser: argparse.ArgumentParser, args: argparse.Namespace, spec: Assignment,
           seed: str | None, level: Isolation) -> int:
    """``check``: one submission's report; exit status 0 for full marks, 1 for fewer,
    :data:`NOT_GRADED_EXIT` if the machine could not grade it."""
    path = args.submission or default_submission(spec)
    try:
        mode = os.lstat(path).st_mode  # a link or pipe is refused in the report
    except OSError as exc:
        parser.error(f"submission: {printable(path)} "
                     + ("does not exist" if isinstance(exc, FileNotFoundError)
                        else f"cannot be read ({exc.strerror})"))
    if stat.S_ISDIR(mode):
        parser.error(f"submission: {printable(path)} is a folder: give a .py or .ipynb "
                     "file")
    result = run(spec, path, seed, level=level)
    print(text(Findings.of(result)))
    if level.rank > FLOOR.rank:  # a laptop: fine for one's own work, not for a class
        print(f"(Checked at isolation {level}: fine for your own code; a class is graded "
              f"at {FLOOR} or stronger.)", file=sys.stderr)
    if result.not_graded:
        return NOT_GRADED_EXIT
    return 0 if result.score >= result.max_score else 1


def _graded(rows: list[dict[str, Any]], out: Path, seconds: float) -> int:
    """What ``grade`` says at the end, and its exit status: :data:`NOT_GRADED_EXIT` if a
    submission could not be graded."""
    missed = [r for r in rows if r["status"] == NOT_GRADED]
    scores = [r["score"] for r in rows if r["status"] != NOT_GRADED]
    mean = f"{sum(scores) / len(scores):.2f}" if scores else "-"
    some = f"{len(scores)} of " if missed else ""
    print(f"graded {some}{len(rows)} submissions in {seconds:.1f} s; mean score "
          f"{mean} / {rows[0]['max_score']:g}; results in {printable(out / 'grades.csv')}",
          file=sys.stderr)
    if missed:
        names = ", ".join(printable(r["submission"]) for r in missed[:10])
        more = f" and {len(missed) - 10} more" if len(missed) > 10 else ""
        print(f"error: {len(missed)} submission{'s' * (len(missed) > 1)} not graded, the "
              f"grading machine's fault (no score written): {names}{more}. Run the same "
              "command again with --resume to grade exactly those.", file=sys.stderr)
        return NOT_GRADED_EXIT
    return 0


def _seed(args: argparse.Namespace) -> str | None:
    """The secret seed: ``--seed-file``, else the deprecated ``--seed`` (with a warning),
    else ``$AUTOGRADER_SEED``."""
    if args.seed_file and args.seed:
        raise ValueError("--seed: give --seed-file or --seed, not both")
    if args.seed_file:
        return read_seed(args.seed_file)
    if args.seed:
        print("warning: --seed puts the secret seed in the command line, which every process "
              "of this machine can read (/proc/PID/cmdline); use --seed-file FILE (or - for "
              "standard input). --seed will be removed in the next release.", file=sys.stderr)
    return seed_from_env(args.seed)
