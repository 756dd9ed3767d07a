"""The time and memory a submission may use: set by whoever grades, enforced by the sandbox
(:mod:`autograder.sandbox`), and kept by the notebooks' own checks for their calls' time;
and what a report says of the limits an isolation level leaves out.

Plain data, so that reading a limit loads no sandbox."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Limits:
    """Resource limits for one submission.

    ``case_timeout`` is the wall-clock time one case may take and ``budget`` the wall-clock
    time of the whole submission (loading and every case; what is left when it runs out
    scores 0). ``cpu_seconds`` is the CPU time one interpreter may use over its whole life, a
    backstop for work the deadlines do not see (threads); None sizes it for every case to
    use its ``case_timeout``. ``memory_mb`` bounds the submission's address space (one
    process at the bubblewrap level, where it can start no other), ``disk_mb`` its writable
    tmpfs (bubblewrap) or any one file it writes (below). The ``"portable"`` level keeps the
    wall-clock limits only.
    """

    cpu_seconds: float | None = None
    memory_mb: int = 1024
    load_timeout: float = 10.0  # wall seconds to start and import the submission
    case_timeout: float = 2.0  # wall seconds per case
    budget: float = 120.0  # wall seconds for the whole submission
    disk_mb: int = 16
    max_fatal: int = 2  # cases of one test that may stop the interpreter before the rest skip


DEFAULT_LIMITS = Limits()


#: What a report says of each isolation level (:class:`autograder.sandbox.Isolation`, by its
#: name: a :class:`~autograder.results.Result` holds the name): "" where every limit holds.
ISOLATION_NOTES: dict[str, str] = {
    "bubblewrap": "",
    "chroot": "",
    "plain": "(No Linux namespaces here: the sandbox still limits time, memory, files "
             "and imports, with its audit hook alone.)",
    "portable": "(Weaker isolation on this system: the sandbox's audit hook alone keeps "
                "files, imports, sockets and processes out of reach, and each case "
                "still has its time limit, but memory and CPU time are not limited.)",
}
