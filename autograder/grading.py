"""Grade a whole class: many submissions in parallel, one result file each, one CSV, the
class summary (:mod:`autograder.summary`) and the LMS exports (:mod:`autograder.lms`).

Each submission runs in its own sandboxed child, so threads are enough here: the
grading process only sends inputs, compares arrays and writes files (its judging shares one
interpreter lock, though: ``benchmarks/grading.py`` finds a ``--scheduler local:N`` cluster
of N processes faster than N threads on a3). A submission that breaks anything only loses its
own points; the batch always finishes. Each graded submission is kept as plain data
(:func:`autograder.batch.record`), which a cluster's worker sends back
(:mod:`autograder.cluster`) and ``--resume`` reads again.

File names, links and folders come from students too. Folders are searched without
following links, to a bounded depth and number of entries; a link, pipe or device where a
submission should be is refused when read (:func:`autograder.submission.read_regular`),
with a row saying so. Each submission's name becomes a folder of the output: it is made
safe (:func:`safe_name`) and unique, and every file written is proven inside ``out``.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import os
import re
import stat
import sys
import time
from collections.abc import Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import asdict, replace
from functools import cache
from pathlib import Path
from typing import Any, TextIO

from .batch import record
from .intake import SUFFIXES, choose, is_dir
from .judging import prepare
from .limits import DEFAULT_LIMITS, Limits
from .lms import FILES as LMS_FILES
from .lms import export
from .output import create, write_csv
from .records import Job, Submission, grader_failed, not_run
from .report import NOT_GRADED
from .results import Result
from .runner import run
from .safe_text import printable
from .sandbox import FLOOR, level_for
from .spec import Assignment
from .submission import SubmissionError, read_regular

MAX_LISTED = 100_000  # entries of a folder of submissions
MAX_NAME_BYTES = 200  # of a name, as UTF-8; with "-N" it stays a valid file name everywhere
RESERVED = frozenset({"grades.csv", "summary.html", *LMS_FILES.values()})  # beside the folders
STATE = "grading.json"  # beside results.json: what --resume needs of a graded submission
MAX_STATE = 1 << 20  # bytes of a grading.json
WINDOWS_DEVICES = frozenset({"CON", "PRN", "AUX", "NUL", *(f"COM{i}" for i in range(1, 10)),
                             *(f"LPT{i}" for i in range(1, 10))})


def collect(paths: list[Path], spec: Assignment) -> list[Submission]:
    """The submissions in ``paths``: files as given; in a directory, its ``.py`` and
    ``.ipynb`` files (named by their stem) and its subdirectories, each the file that
    :func:`autograder.intake.choose` picks (named by the subdirectory, as in a Gradescope
    or LMS export).

    No link is followed into and no file read here: a link or special file given, or where
    a file or a student's folder would be, is a submission that :func:`grade` refuses with
    a reason.
    Names are made safe and unique (:func:`unique`). A ``ValueError`` says which of
    ``paths`` does not exist or cannot be listed.
    """
    found: list[Submission] = []
    for p in paths:
        try:
            mode = os.lstat(p).st_mode
        except OSError as exc:
            raise ValueError(f"submissions: {printable(p)} "
                             + ("does not exist" if isinstance(exc, FileNotFoundError)
                                else f"cannot be read ({exc.strerror})")) from None
        if stat.S_ISDIR(mode):
            found += _in_folder(p, spec)
        else:
            found.append(Submission(p.stem, p))
    return unique(found)


def _in_folder(folder: Path, spec: Assignment) -> list[Submission]:
    try:
        with os.scandir(folder) as it:
            entries = sorted(itertools.islice(it, MAX_LISTED + 1), key=lambda e: e.name)
    except OSError as exc:
        raise ValueError(f"submissions: {printable(folder)} cannot be listed "
                         f"({exc.strerror})") from None
    if len(entries) > MAX_LISTED:
        raise ValueError(f"submissions: {printable(folder)} has more than {MAX_LISTED} "
                         "entries: give its subfolders separately")
    found = []
    for e in entries:
        path = Path(e.path)
        if is_dir(e):
            inner = _one_submission(path, spec)
            if inner:
                found.append(replace(inner, folder=path))
        elif path.suffix in SUFFIXES:  # a link, pipe or socket too: refused when read
            found.append(Submission(path.stem, path))
        elif e.is_symlink() and os.path.isdir(path):  # a student's folder as a link
            found.append(Submission(e.name, path))
    return found


def _one_submission(folder: Path, spec: Assignment) -> Submission | None:
    """A student's folder: the file :func:`autograder.intake.choose` picks, a refusal saying
    why none can be, or None if it holds no ``.py``/``.ipynb`` file."""
    choice = choose(folder, spec.template, [f.name for f in spec.functions])
    if choice.path is not None:
        return Submission(folder.name, choice.path)
    return Submission(folder.name, folder, choice.refused) if choice.refused else None


def safe_name(raw: str) -> str:
    """``raw`` (a file's stem or a folder's name) as a name that is one plain folder inside
    the output on every system, and a harmless line in a terminal: control and invisible
    characters removed, bytes that are not UTF-8 shown as ``_xe9``, path separators and
    characters Windows forbids as ``_``, no leading dot, no ``..``, at most
    :data:`MAX_NAME_BYTES` bytes; ``"submission"`` if nothing is left."""
    out = []
    for ch in os.fsdecode(raw):
        code = ord(ch)
        if 0xDC80 <= code <= 0xDCFF:  # os.fsdecode's stand-in for a byte that is not UTF-8
            out.append(f"_x{code - 0xDC00:02x}")
        elif ch in '/\\<>:"|?*':
            out.append("_")
        elif ch.isprintable():  # drops control, format (U+202E), separator and surrogate
            out.append(ch)
    name = re.sub(r"\.{2,}", "_", "".join(out)).strip(". ")
    while len(name.encode()) > MAX_NAME_BYTES:
        name = name[:-1].rstrip(". ")
    if name.partition(".")[0].upper() in WINDOWS_DEVICES:
        name = "_" + name
    return name or "submission"


def unique(submissions: list[Submission]) -> list[Submission]:
    """``submissions`` with safe names (:func:`safe_name`), unique without regard to case
    (one folder on Windows and macOS): a name taken again gets the first ``-2``, ``-3``, ...
    that no other submission has, so a real ``dup-2`` keeps its own. Already unique safe
    names are kept as they are."""
    bases = [safe_name(s.name) for s in submissions]
    taken = {b.casefold() for b in bases} | RESERVED
    used: set[str] = set()
    out = []
    for s, base in zip(submissions, bases, strict=True):
        name = base
        if base.casefold() in used or base.casefold() in RESERVED:
            n = 2
            while f"{base}-{n}".casefold() in taken:
                n += 1
            name = f"{base}-{n}"
            taken.add(name.casefold())
        used.add(name.casefold())
        out.append(replace(s, name=name))
    return out


def inside(root: Path, name: str) -> Path:
    """``root / name``, proven to be an entry of ``root`` (a resolved folder) once links
    are resolved; a ``ValueError`` otherwise."""
    path = root / name
    if name in ("", ".", "..") or path.parent != root or path.resolve().parent != root:
        raise ValueError(f"{printable(path)} is not inside {printable(root)}")
    return path


def grade(assignment: Assignment, submissions: Sequence[Submission | tuple[str, Path]],
          out: Path,
          *, jobs: int = 1, seed: str | None = None, limits: Limits = DEFAULT_LIMITS,
          progress: TextIO | None = sys.stderr, level: str | None = None,
          scheduler: str | None = None, min_isolation: str | None = None,
          resume: bool = False, lms: Sequence[str] = ()) -> list[dict[str, Any]]:
    """Grade every submission; write ``out/<name>/results.json``, ``out/grades.csv``, the
    class summary ``out/summary.html`` and an ``out/grades-<lms>.csv`` per name in ``lms``
    (:mod:`autograder.lms`). Returns the rows of ``grades.csv``.

    ``level``: the sandbox's isolation here (default: the strongest here); below
    ``min_isolation`` (default :data:`~autograder.sandbox.FLOOR`) nothing is graded: a
    ``ValueError`` says what is missing. ``scheduler``: a Dask scheduler's address, or
    ``local[:N]``, to grade on a cluster instead (:mod:`autograder.cluster`, whose workers
    must reach ``min_isolation``); without it no Dask is imported. ``resume``: a submission
    whose files, assignment, seed, limits and grader are those recorded in
    ``out/<name>/grading.json`` is not graded again (one *not graded*, the machine's or the
    grader's fault, always is: its row's status says so and its score is empty).

    Names are made safe and unique again (:func:`unique`: unchanged for :func:`collect`'s);
    a submission that cannot be read gets score 0 and the reason, like any refused one.
    Nothing is written through a link in ``out``: a ``results.json`` is then skipped with a
    warning, and ``grades.csv`` is an ``OSError``. An LMS export whose students cannot be
    told apart is a ``ValueError`` (after ``grades.csv`` and the summary are written).
    """
    subs = unique([s if isinstance(s, Submission) else Submission(*s) for s in submissions])
    here = level_for(level, min_isolation or FLOOR) if not scheduler else level_for(level)
    out.mkdir(parents=True, exist_ok=True)
    root = out.resolve()
    prepare(assignment, seed)  # once, before the threads start
    context = _context(assignment, seed, limits)
    records: dict[str, dict[str, Any]] = {}
    todo: list[tuple[Submission, Job | None]] = []
    for s in subs:
        job = None if s.refused else _job(s, assignment.template, context)
        stored = _stored(root, s.name, job.digest) if resume and job else None
        if stored:
            records[s.name] = stored
        else:
            todo.append((s, job))
    bar = Progress(len(todo), progress)
    graded: Iterator[tuple[str, dict[str, Any]]]
    if scheduler:
        from .cluster import grade_on_cluster

        local = [s for s, job in todo if job is None]  # refused or unreadable: nothing to send
        remote = [job for _, job in todo if job is not None]
        graded = itertools.chain(
            _on_pool(assignment, [(s, None) for s in local], 1, seed, limits, here),
            grade_on_cluster(assignment, remote, scheduler, seed=seed, limits=limits,
                             min_isolation=min_isolation))
    else:
        graded = _on_pool(assignment, todo, jobs, seed, limits, here)
    for name, rec in graded:
        _write_results(root, name, rec)
        records[name] = rec
        bar.step(name)
    bar.close()
    ordered = [records[s.name] for s in subs]
    if ordered:
        write_csv(_output(root, "grades.csv"), ordered[0]["header"], [r["row"] for r in ordered])
        _write_summary(_output(root, "summary.html"), assignment, [r["facts"] for r in ordered])
        for kind in lms:  # a submission not graded is left out: its LMS grade stays as it is
            export(kind, _output(root, LMS_FILES[kind]), assignment,
                   [(s, r["row"]) for s, r in zip(subs, ordered, strict=True)
                    if r["row"]["status"] != NOT_GRADED])
    return [r["row"] for r in ordered]


def _output(root: Path, name: str) -> Path:
    """``root / name`` for a file of the whole class; an ``OSError`` if a link was planted
    there."""
    try:
        return inside(root, name)
    except ValueError as exc:
        raise OSError(f"{name} not written: {exc}") from None


def _write_summary(path: Path, assignment: Assignment, facts: list[dict[str, Any]]) -> None:
    from .summary import summary_html

    with create(path) as f:
        f.write(summary_html(assignment, facts))


def _job(s: Submission, template: str, context: str) -> Job | None:
    """``s`` read into a :class:`Job`, or None if one of its files cannot be read (the
    local grader then says why, as it would without a cluster)."""
    paths = [s.path]
    beside = s.path.parent / template
    if s.path.suffix == ".ipynb" and os.path.lexists(beside):
        paths.append(beside)
    try:  # as the grader reads them: a link, a pipe, too large, not UTF-8 is refused
        files = {p.name: read_regular(p).encode() for p in paths}
    except SubmissionError:
        return None
    digest = hashlib.sha256(context.encode())
    for name, data in files.items():
        digest.update(f"\0{len(name)}:{name}:{len(data)}:".encode(errors="surrogateescape"))
        digest.update(data)
    return Job(s.name, str(s.path), s.path.name, files, digest.hexdigest())


def _context(assignment: Assignment, seed: str | None, limits: Limits) -> str:
    """What else decides a grade: the assignment, the seed, the limits and the grader's own
    code (a fix to a test regrades everyone)."""
    return json.dumps([assignment.key, seed or "", asdict(limits), _grader_digest()])


@cache
def _grader_digest() -> str:
    here = Path(__file__).parent
    digest = hashlib.sha256()
    for path in sorted(here.rglob("*.py")):
        digest.update(str(path.relative_to(here)).encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()


def _on_pool(assignment: Assignment, todo: list[tuple[Submission, Job | None]], jobs: int,
             seed: str | None, limits: Limits, level: str
             ) -> Iterator[tuple[str, dict[str, Any]]]:
    """``(name, record)`` of each submission as it is graded here, by ``jobs`` threads.

    With more than one, numpy's BLAS runs on one thread of its own. A thread that starts a
    sandbox as root does it with fork() (Popen's user switch rules out vfork), and OpenBLAS's
    fork handler stops its worker threads under any product another thread is computing:
    a5's diagnosis then never returned from ``inv`` (--jobs 2, an hour at 100 % CPU).
    """
    from threadpoolctl import threadpool_limits

    with (threadpool_limits(1 if jobs > 1 else None, user_api="blas"),
          ThreadPoolExecutor(max_workers=max(1, jobs)) as pool):
        futures = {pool.submit(_grade_one, assignment, s, seed, limits, level): (s, job)
                   for s, job in todo}
        for future in as_completed(futures):
            s, job = futures[future]
            yield s.name, record(s.name, future.result(), job.digest if job else "")


def _write_results(root: Path, name: str, rec: dict[str, Any]) -> None:
    """``root/name/results.json`` and, for a resumable record, ``grading.json`` after it (so
    that a batch stopped in between grades the submission again), if they are really there
    (not links out of ``root``)."""
    try:
        folder = inside(root, name)
        folder.mkdir(exist_ok=True)
        with create(inside(folder, "results.json")) as f:
            f.write(json.dumps(rec["results"], indent=1))
        state = inside(folder, STATE)
        if rec["digest"]:
            with create(state) as f:
                f.write(json.dumps({k: rec[k] for k in ("digest", "row", "header", "facts")}))
        elif os.path.lexists(state):
            os.unlink(state)
    except (OSError, ValueError) as exc:  # a link planted in --out, say: write nothing there
        print(f"warning: results of {name} not written: {exc}", file=sys.stderr)


def _stored(root: Path, name: str, digest: str) -> dict[str, Any] | None:
    """The record kept in ``root/name/grading.json`` if it is of ``digest`` and its
    ``results.json`` is there; None otherwise (anything amiss: grade again)."""
    try:
        folder = inside(root, name)
        if not stat.S_ISREG(os.lstat(inside(folder, "results.json")).st_mode):
            return None
        kept = json.loads(read_regular(inside(folder, STATE), MAX_STATE))
    except (OSError, ValueError):  # SubmissionError and JSONDecodeError are ValueErrors
        return None
    if not (isinstance(kept, dict) and kept.get("digest") == digest
            and isinstance(kept.get("row"), dict) and isinstance(kept.get("header"), list)
            and isinstance(kept.get("facts"), dict)):
        return None
    return kept


def _grade_one(assignment: Assignment, s: Submission, seed: str | None, limits: Limits,
               level: str) -> Result:
    if s.refused:
        return not_run(assignment, s.path, seed, level, s.refused,
                       "not run: the submission was refused (see above)")
    try:
        return run(assignment, s.path, seed, limits, level)
    except Exception as exc:  # a bug of ours must not stop the class's grading
        return grader_failed(assignment, s.path, seed, level, exc)


class Progress:
    """A one-line progress bar on a terminal; a line per tenth of the work otherwise."""

    def __init__(self, total: int, stream: TextIO | None, width: int = 30):
        self.total, self.stream, self.width = total, stream, width
        self.done = 0
        self.start = time.monotonic()
        self.tty = bool(stream and stream.isatty())

    def step(self, name: str) -> None:
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
