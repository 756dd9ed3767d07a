"""The ``chroot`` level's own parts: a user of its own per submission, the end of all its
processes, and the watch on its folder's size.

Without namespaces (a container as root, where Docker's default seccomp profile refuses them)
the kernel still separates users: a process can signal, trace or open the files of its own
user only. So each submission runs as a user id that no one else has, leased from a reserved
range (:data:`UIDS`, ``$AUTOGRADER_UIDS`` as ``FIRST-LAST``) under a lock file for as long
as it runs; a user named in the password or group database, or owning any process, is never
leased. :func:`reap` ends every process of that user (``kill(-1, SIGKILL)`` sent *as* that
user reaches exactly those), before a lease is used and after each child.

No mount is possible there, so no tmpfs caps the work folder: :class:`DiskWatch` measures it
every few milliseconds and stops the submission once it holds more than its limit (each file
is also held to that size by ``RLIMIT_FSIZE``); ``docs/sandbox.md`` gives the overshoot
measured.
"""

from __future__ import annotations

import fcntl
import grp
import os
import pwd
import subprocess
import sys
import threading
from collections.abc import Callable
from pathlib import Path

from .runtime import workspace

UIDS_ENV = "AUTOGRADER_UIDS"
UIDS = range(61000, 62000)  # as isolate's 60000+ boxes: far from system and login users
ENTER = Path(__file__).with_name("enter_jail.py")
CLEAN = b"clean\n"  # a lease file's text once its user's processes were all ended
MAX_ENTRIES = 4096  # files and folders a submission may make in its folder


def uid_range() -> range:
    """:data:`UIDS`, or ``$AUTOGRADER_UIDS`` (``FIRST-LAST``); ValueError if that is
    malformed."""
    text = os.environ.get(UIDS_ENV)
    if not text:
        return UIDS
    first, sep, last = text.partition("-")
    if not (sep and first.isdigit() and last.isdigit() and 1000 <= int(first) <= int(last)):
        raise ValueError(f"${UIDS_ENV}: {text!r} is not FIRST-LAST with 1000 <= FIRST <= LAST")
    return range(int(first), int(last) + 1)


def launcher(*args: str) -> list[str]:
    """The command that runs :mod:`autograder.enter_jail` with ``args``."""
    return [os.path.realpath(sys.executable), "-I", "-S", "-B", str(ENTER), *args]


class Lease:
    """A user id of the reserved range that nothing else uses, held until :meth:`release`
    (a lock file in the grader's workspace: a lease dies with its process)."""

    def __init__(self) -> None:
        locks = workspace() / "uids"
        locks.mkdir(mode=0o700, exist_ok=True)
        busy = _process_owners()
        for uid in uid_range():
            if uid in busy or _named(uid):
                continue
            fd = os.open(locks / str(uid), os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o600)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                os.close(fd)
                continue
            self.uid, self._fd = uid, fd
            if os.pread(fd, len(CLEAN), 0) != CLEAN:  # a grader died holding it: end its leftovers
                reap(uid)
            os.ftruncate(fd, 0)
            return
        raise OSError(f"every user id of {uid_range()} is leased or in use: set {UIDS_ENV} "
                      "to a larger free range")

    def release(self) -> None:
        reap(self.uid)
        os.pwrite(self._fd, CLEAN, 0)  # so the next lease need not reap
        os.close(self._fd)


def _named(uid: int) -> bool:
    for lookup in (pwd.getpwuid, grp.getgrgid):
        try:
            lookup(uid)
            return True
        except KeyError:
            pass
    return False


def _process_owners() -> set[int]:
    owners = set()
    for entry in os.scandir("/proc"):
        if entry.name.isdigit():
            try:
                owners.add(entry.stat().st_uid)
            except OSError:  # ended meanwhile
                pass
    return owners


def reap(uid: int) -> None:
    """End every process of ``uid``. OSError if that could not be done."""
    env = {k: v for k, v in os.environ.items() if k == "LD_LIBRARY_PATH"}
    done = subprocess.run(launcher("reap", str(uid)), capture_output=True, text=True,
                          timeout=30, env=env, check=False)
    if done.returncode != 0:
        raise OSError(f"could not end the processes of user {uid}: {done.stderr.strip()}")


class DiskWatch:
    """Measures ``folder`` every ``period`` seconds on a thread of its own; past ``limit``
    bytes (or :data:`MAX_ENTRIES` entries) it sets :attr:`exceeded` and calls ``stop``
    (which empties the folder), and goes on watching."""

    def __init__(self, folder: Path, limit: int, stop: Callable[[], None],
                 period: float = 0.005):
        self.folder, self.limit, self._stop_child, self.period = folder, limit, stop, period
        self.exceeded = False
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True)
        self._thread.start()

    def _watch(self) -> None:
        while not self._done.wait(self.period):
            if usage(self.folder) > self.limit:
                self.exceeded = True
                self._stop_child()

    def close(self) -> None:
        self._done.set()
        self._thread.join()


def usage(folder: Path) -> float:
    """Bytes the files below ``folder`` hold on disk (``inf`` past :data:`MAX_ENTRIES`
    entries: a folder that large is over any limit), without following links."""
    total, seen, todo = 0, 0, [str(folder)]
    while todo:
        try:
            with os.scandir(todo.pop()) as it:
                for e in it:
                    seen += 1
                    if seen > MAX_ENTRIES:
                        return float("inf")
                    try:
                        st = e.stat(follow_symlinks=False)
                    except OSError:
                        continue
                    total += st.st_blocks * 512
                    if e.is_dir(follow_symlinks=False):
                        todo.append(e.path)
        except OSError:  # removed meanwhile
            continue
    return total
