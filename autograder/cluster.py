"""Grade a class on a Dask distributed cluster (``grade ... --scheduler ADDRESS``).

The grading process reads every submission and sends each to the cluster as a task holding
its bytes and name (:class:`autograder.records.Job`), never a path: a worker needs no shared
file system. The worker writes the files into a temporary folder of its own, grades them in
its own sandbox (:mod:`autograder.sandbox`, the strongest level it reaches) and sends back the
batch's record of the submission, plain data (:func:`autograder.batch.record`); the
grading process writes every output file.

Before any work, each worker reports the isolation level it reached, and a worker weaker than
``min_isolation`` (default: the strongest the scheduler's own machine gives, and never below
:data:`autograder.sandbox.FLOOR`) stops the batch
with its name; a worker that joins later checks the same before each task. A worker that dies
while grading costs only a retry of the submissions it held: the scheduler runs them again
elsewhere, up to its ``distributed.scheduler.allowed-failures`` times (:data:`RETRIES` on a
``local`` cluster); a submission that kills every worker it meets, or that the machine could
not grade, is *not graded* (no score; ``grade`` exits non-zero and ``--resume`` grades it again).
A task that raises is tried again :data:`RETRIES` times too.

``local[:N]`` starts a ``LocalCluster`` of N single-threaded worker processes on this machine
(N: one per CPU when not given). Dask is the optional extra ``cluster``
(``pip install .[cluster]``) and is imported only here.
"""

from __future__ import annotations

import logging
import os
import socket
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .batch import record
from .limits import Limits
from .records import Job, grader_failed, not_graded
from .sandbox import FLOOR, LEVELS, Isolation, probe

if TYPE_CHECKING:
    from distributed import Client

    from .spec import Assignment

RETRIES = 2  # attempts after the first, for a task that raised or whose worker died
LOCAL = "local"


class WeakWorker(RuntimeError):
    """A worker's sandbox is weaker than the batch requires."""


def worker_level() -> str:
    """The isolation level the sandbox reaches on this machine (run on each worker)."""
    return probe().level.value


def grade_job(key: str, job: Job, seed: str | None, limits: Limits,
              minimum: str) -> dict[str, Any]:
    """Grade ``job`` of assignment ``key`` here, at the strongest isolation this worker
    reaches (a :class:`WeakWorker` if that is weaker than ``minimum``); the batch's record."""
    level = probe().level
    if level.rank > Isolation(minimum).rank:
        raise WeakWorker(f"worker {socket.gethostname()} (pid {os.getpid()}) reaches only "
                         f"{level} isolation, weaker than the required {minimum}")
    from .assignments import load
    from .runner import run

    with tempfile.TemporaryDirectory(prefix="autograder-job-") as tmp:
        for name, data in job.files.items():
            (Path(tmp) / name).write_bytes(data)
        result = run(load(key), Path(tmp) / job.file, seed, limits, level)
    result.submission = Path(job.label)  # the report names the file the instructor gave
    return record(job.name, result, job.digest)


def grade_on_cluster(assignment: Assignment, jobs: list[Job], scheduler: str, *,
                     seed: str | None, limits: Limits,
                     min_isolation: str | None) -> Iterator[tuple[str, dict[str, Any]]]:
    """``(name, record)`` of each job as the cluster at ``scheduler`` grades it (see the
    module's docstring). A ``ValueError`` for a bad address or a worker too weak."""
    if not jobs:
        return
    try:
        from distributed import KilledWorker, as_completed
    except ImportError:
        raise ValueError("--scheduler: Dask is not installed here (pip install "
                         "'course-kinematics[cluster]')") from None

    with _client(scheduler) as client:
        minimum = _minimum(client, min_isolation)
        refuse_weak(client.run(worker_level), minimum)
        futures = {client.submit(grade_job, assignment.key, job, seed, limits, minimum,
                                 key=f"autograder-{job.name}-{job.digest[:12]}",
                                 pure=False, retries=RETRIES): job for job in jobs}
        try:
            for future in as_completed(futures):
                job = futures[future]
                try:
                    rec = future.result()
                except WeakWorker as exc:
                    raise ValueError(f"--min-isolation {minimum}: {exc}") from None
                except KilledWorker:
                    rec = record(job.name, not_graded(
                        assignment, Path(job.label), seed, Isolation(minimum),
                        "every worker that graded this submission died while grading it "
                        f"({1 + _allowed_failures(client)} attempts): the sandbox should make "
                        "that impossible; please report this"))
                except Exception as exc:  # a bug of ours, raised on every attempt
                    rec = record(job.name, grader_failed(assignment, Path(job.label), seed,
                                                         Isolation(minimum), exc))
                yield job.name, rec
        finally:
            client.cancel(list(futures))


@contextmanager
def _client(scheduler: str) -> Iterator[Client]:
    """A client of the scheduler at ``scheduler``, or of a new ``local[:N]`` cluster."""
    import dask
    from distributed import Client, LocalCluster

    name, _, n = scheduler.partition(":")
    if name != LOCAL:
        try:
            client = Client(scheduler, timeout="30s")
        except (OSError, ValueError, TypeError) as exc:
            raise ValueError(f"--scheduler: cannot reach {scheduler!r} ({exc})") from None
        with client:
            client.wait_for_workers(1, timeout=120)
            yield client
        return
    if n and not (n.isdigit() and int(n) > 0):
        raise ValueError(f"--scheduler: {scheduler!r}: N in local:N must be a positive integer")
    workers = int(n) if n else os.cpu_count() or 1
    with dask.config.set({"distributed.scheduler.allowed-failures": RETRIES}):
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=":0", silence_logs=logging.ERROR)
    with cluster, Client(cluster) as client:
        yield client


def _minimum(client: Client, requested: str | None) -> str:
    """``requested``, else the strongest level the scheduler's machine reaches, or
    :data:`~autograder.sandbox.FLOOR` if that is weaker."""
    if requested is not None:
        if requested not in LEVELS:
            raise ValueError(f"--min-isolation: {requested!r} is not one of {', '.join(LEVELS)}")
        return requested
    try:
        level = Isolation(client.run_on_scheduler(worker_level))
        return min(level, FLOOR, key=lambda x: x.rank).value
    except Exception as exc:  # autograder not installed beside the scheduler, say
        raise ValueError("--min-isolation: the scheduler could not say which isolation its "
                         f"machine reaches ({type(exc).__name__}: {exc}); give "
                         "--min-isolation") from None


def refuse_weak(levels: dict[str, str], minimum: str) -> None:
    """A ``ValueError`` naming every worker (address: level) weaker than ``minimum``."""
    weak = {w: level for w, level in levels.items()
            if Isolation(level).rank > Isolation(minimum).rank}
    if weak:
        named = ", ".join(f"{w} reaches only {level}" for w, level in sorted(weak.items()))
        raise ValueError(f"--min-isolation {minimum}: {len(weak)} of {len(levels)} workers are "
                         f"weaker ({named}); install bubblewrap there, or lower "
                         "--min-isolation knowingly")


def _allowed_failures(client: Client) -> int:
    try:
        return int(client.run_on_scheduler(_scheduler_allowed_failures))
    except Exception:  # a scheduler that cannot run our function: its default
        return 3


def _scheduler_allowed_failures(dask_scheduler: Any = None) -> int:
    failures: int = dask_scheduler.allowed_failures
    return failures
