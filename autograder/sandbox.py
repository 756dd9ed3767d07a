"""Run a submission's functions in a separate, limited interpreter.

One :class:`Sandbox` per submission holds a private temporary folder (the child's log, and
below the bubblewrap level its working directory) and at most one live child. How the child
is isolated depends on what the machine allows (:class:`Isolation`, strongest first; the
guarantees of each are in ``docs/sandbox.md``):

``bubblewrap`` (Linux with ``bwrap`` and libseccomp; the grader may be root or not)
    The kernel is the boundary. ``bwrap`` runs as an unprivileged user (the grader's own, or
    when the grader is root a user id leased for this submission alone, as at the ``chroot``
    level, so that no process count or signal is shared with a classmate or a host daemon)
    and starts the child in new user, mount, PID, network, IPC, UTS and cgroup namespaces,
    as uid :data:`SANDBOX_UID` inside, with
    every capability dropped, ``no_new_privs`` set, nested user namespaces disabled and the
    seccomp filter of :mod:`autograder.seccomp` (no new processes, no mounts, no ptrace, no
    sockets but AF_UNIX...). Its root file system is entered with ``pivot_root`` and holds
    only the minimal runtime of :mod:`autograder.runtime` (this interpreter, the standard
    library a submission may use, numpy, their shared libraries), the dynamic loader, the
    child's two files and ``/sandbox/work``, a tmpfs of ``Limits.disk_mb``: the one writable
    place. No host path, ``/proc`` included, exists there.
``chroot`` (Linux, grader running as root, no user namespaces: Docker's default seccomp
    profile, Gradescope, Ubuntu 24.04's AppArmor rule)
    The kernel is the boundary here too, with the privileges a stock container's root has
    (:mod:`autograder.enter_jail`): the child enters the runtime's ``jail/`` with
    ``chroot`` (no ``/proc``, no ``/dev/shm``, no host path), becomes a user id of its own
    (:mod:`autograder.jail`: leased per submission, never shared), sets ``no_new_privs``
    and the same seccomp filter, which here also keeps every signal to its own process.
    Its one writable place is its own folder, watched to ``Limits.disk_mb``; every process
    of its user is killed after each child.
``plain`` (any other POSIX system)
    the grader's own interpreter as the grader's own user, with the limits below and the
    audit hook.
``portable`` (Windows, older macOS Pythons, anything without the POSIX process controls of
    :func:`posix_controls`)
    the audit hook alone and wall-clock deadlines: no memory or CPU-time limit.

In every case the child runs as ``python -I -S -B -u`` (isolated mode, no site-packages, no
bytecode writes) with a minimal environment (no seed, no paths), and talks to the grader over
its own standard input and output (the child moves them out of the submission's reach). Each
case has a wall-clock deadline enforced here, by waiting for the child's answer on a thread
(:class:`Replies`), and the whole submission a wall-clock budget (``Limits.budget``) after
which what is left scores 0. At the POSIX levels the child also limits its address space,
CPU time (for its whole life, sized for all its cases), file size and thread count. A case
that hangs, crashes the interpreter or answers with garbage is *fatal*: the child is killed
and a fresh one runs the remaining cases, so one slow or crashing case costs only itself
(after ``Limits.max_fatal`` of them in one test, or one forged answer, the rest of it is
skipped).
"""

from __future__ import annotations

import enum
import json
import math
import os
import queue
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, replace
from functools import cache
from importlib.util import find_spec
from pathlib import Path
from typing import IO, Any

import numpy as np

from . import jail, runtime, seccomp
from .judging import Outcome
from .limits import ISOLATION_NOTES, Limits
from .protocol import (
    MAX_FRAME,
    ProtocolError,
    Value,
    decode_value,
    encode_args,
    numbers_in,
    read_frame,
    write_frame,
)
from .safe_text import printable

FATAL = ("timeout", "crash", "garbage")
INSIDE = "/sandbox"  # where the runtime, the child's files and the working directory appear
SANDBOX_UID = 65534  # the child's user inside bwrap's user namespace (nobody)


class Isolation(str, enum.Enum):
    """How strongly a submission is kept from the grader; members compare equal to their
    names (``Isolation.PLAIN == "plain"``) and are ordered strongest first."""

    BUBBLEWRAP = "bubblewrap"
    CHROOT = "chroot"
    PLAIN = "plain"
    PORTABLE = "portable"

    __str__ = str.__str__
    # Formats as its value, as a str does (Enum's own __format__ is typed for Enum).
    __format__ = str.__format__  # type: ignore[assignment]

    @property
    def rank(self) -> int:
        """0 for the strongest level."""
        return list(Isolation).index(self)

    @property
    def posix(self) -> bool:
        """Process groups, ``wait4`` and resource limits are used."""
        return self is not Isolation.PORTABLE

    @property
    def staged(self) -> bool:
        """The child runs the minimal runtime of :mod:`autograder.runtime`."""
        return self in (Isolation.BUBBLEWRAP, Isolation.CHROOT)

    @property
    def note(self) -> str:
        """What a report says of this level ("" for the strongest)."""
        return ISOLATION_NOTES[self.value]


LEVELS = tuple(level.value for level in Isolation)
# The weakest level a class is graded at unless the instructor lowers it by name: a kernel
# boundary that a stock Docker container's root can have (docs/sandbox.md).
FLOOR = Isolation.CHROOT
# RLIMIT_NPROC of the child: its threads (both levels refuse new processes; the count is per
# user namespace with bubblewrap, per leased user at the chroot level).
TASKS = {Isolation.BUBBLEWRAP: 32, Isolation.CHROOT: 32}
START_ATTEMPTS = 3  # starts of one child that bubblewrap itself may refuse before we give up


class Unavailable(Exception):
    """The sandbox could not run the submission at all, for a reason of the grading machine
    (the child ended or hung before the submission's first instruction, its runtime could
    not be staged, no user id could be leased): nothing about the submission is known, so
    it is not graded rather than scored. The message says what the sandbox said."""


@dataclass
class Probe:
    """The strongest level this machine gives, and why no stronger one."""

    level: Isolation
    why_not_stronger: str = ""


@cache
def probe() -> Probe:
    """Start a child at each level in turn, strongest first, until one loads an empty
    submission (probed once per process)."""
    if not posix_controls():
        return Probe(Isolation.PORTABLE, "this system lacks the POSIX process controls")
    why = ""
    candidates = [Isolation.PLAIN]
    if sys.platform == "linux":
        candidates[:0] = [Isolation.BUBBLEWRAP] + ([Isolation.CHROOT]
                                                     if os.geteuid() == 0 else [])
    for level in candidates:
        missing = _missing_for(level)
        if missing:
            why = why or missing
            continue
        try:
            with Sandbox("", [], Limits(load_timeout=20.0), frozenset(), level=level) as box:
                started = box.start()
                if started.status == "ok":
                    return Probe(level, why)
                refusal = started.message or started.status
        except Unavailable as exc:
            refusal = str(exc)
        why = why or f"the {level} sandbox did not start here: {refusal}"
    return Probe(Isolation.PLAIN, why)


def _missing_for(level: Isolation) -> str:
    """What this machine lacks for ``level`` (the package to install), or ""."""
    if not level.staged:
        return ""
    if level is Isolation.BUBBLEWRAP and not shutil.which("bwrap"):
        return "bubblewrap is not installed (Debian/Ubuntu: apt-get install bubblewrap)"
    if not seccomp.available():
        return "libseccomp is not installed (Debian/Ubuntu: apt-get install libseccomp2)"
    return ""


def isolation() -> Isolation:
    """The strongest level of :class:`Isolation` that starts a working child here."""
    return probe().level


def posix_controls() -> bool:
    """Whether this system has what the levels above ``"portable"`` use: process groups
    (``os.killpg``), a child's exit status without reaping it (``os.waitid``, missing on
    macOS before Python 3.13) and its CPU time (``os.wait4``), and resource limits."""
    return os.name == "posix" and find_spec("resource") is not None and all(
        hasattr(os, f) for f in ("killpg", "waitid", "wait4"))


def level_for(requested: str | None, floor: str | None = None) -> Isolation:
    """``requested`` if this machine offers it (it or a stronger level), else ValueError;
    None: the strongest, :func:`isolation`. With ``floor`` (a level's name: grading a
    class), a level weaker than it is refused with a ValueError that says what is missing
    and how to get it, never used in silence."""
    for name, value in (("isolation", requested), ("min-isolation", floor)):
        if value is not None and value not in LEVELS:
            raise ValueError(f"{name}: {value!r} is not one of {', '.join(LEVELS)}")
    best = Isolation(isolation())
    level = best if requested is None else Isolation(requested)
    if level is Isolation.CHROOT and not (sys.platform == "linux" and os.geteuid() == 0):
        raise ValueError("isolation: 'chroot' needs a grader running as root on Linux (it "
                         "leases a user id per submission)")
    if level.rank < best.rank:
        raise ValueError(f"isolation: {requested!r} is not available on this machine (the "
                         f"strongest here is {best!r}: {probe().why_not_stronger})")
    if floor is not None and level.rank > Isolation(floor).rank:
        raise ValueError(below_floor(level, Isolation(floor)))
    return level


def below_floor(level: Isolation, floor: Isolation) -> str:
    """Why grading at ``level`` is refused, what would give this machine ``floor``, and how
    to grade at ``level`` anyway."""
    best = Isolation(isolation())
    if level is not best:
        why = f"--isolation {level} asked for it"
        fix = f"leave out --isolation (this machine reaches {best})"
    else:
        why = probe().why_not_stronger or f"{level} is the strongest level here"
        fix = _how_to_reach(floor)
    return (f"refusing to grade at isolation {level}, below the floor {floor}: {why}. To fix "
            f"it, {fix}. To grade anyway with {level}'s weaker boundary, lower the floor by "
            f"name: --min-isolation {level}")


def _how_to_reach(floor: Isolation) -> str:
    """What gives this machine ``floor`` or a stronger level."""
    if sys.platform != "linux":
        return f"grade on Linux ({floor} needs it; a container run as root will do)"
    if os.geteuid() != 0:
        return ("install bubblewrap and libseccomp2 and allow user namespaces, or run the "
                "grader as root in a container (its chroot level needs no more than Docker "
                "gives)")
    return "install libseccomp2 (and bubblewrap)"


def weaker_warning(level: Isolation) -> str | None:
    """What ``grade`` warns when ``level`` is not the strongest level there is, with what
    would give this machine a stronger one."""
    if level.rank <= FLOOR.rank:
        return None
    best = probe()
    text = f"warning: isolation is weaker on this machine ({level}): {level.note.strip('()')}"
    if best.level.rank < level.rank:
        return text + f" (--isolation {best.level} is available here.)"
    return text + f" For a private file system per submission: {best.why_not_stronger}."


class Replies:
    """The child's frames from ``stream``, each read on a thread when it is asked for, so
    that waiting for one can end at a deadline on every platform (``select`` cannot wait on
    a pipe on Windows), and a child writing frames in a loop only fills its pipe."""

    def __init__(self, stream: IO[bytes]):
        self.stream = stream
        self._asked = threading.Semaphore(0)
        self._got: queue.SimpleQueue[tuple[Any, Exception | None]] = queue.SimpleQueue()
        self._pending = False  # a frame was asked for and has not come yet
        self.parse_at_most = MAX_FRAME  # longer frames are read and dropped unparsed
        self._closed = False
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()

    def _read(self) -> None:
        while True:
            self._asked.acquire()
            if self._closed:
                return
            try:
                frame, error = read_frame(self.stream.fileno(), self.parse_at_most), None
            except ProtocolError as exc:
                frame, error = None, exc
            except OSError:  # the pipe is gone: as good as its end
                frame, error = None, None
            self._got.put((frame, error))
            if frame is None:
                return

    def get(self, deadline: float, parse_at_most: int = MAX_FRAME) -> Any | None:
        """The next frame; None at end of file (the child is gone); ``TimeoutError`` past
        ``deadline`` (monotonic); ``ProtocolError`` for a malformed one."""
        if not self._pending:
            self._pending = True
            self.parse_at_most = parse_at_most
            self._asked.release()
        try:
            frame, error = self._got.get(timeout=max(0.0, deadline - time.monotonic()))
        except queue.Empty:
            raise TimeoutError from None
        self._pending = False
        if error is not None:
            raise error
        return frame

    def close(self) -> None:
        """Stop the thread (once the child is gone, its read ends) and close the pipe."""
        self._closed = True
        self._asked.release()
        self._thread.join(timeout=1.0)
        if not self._thread.is_alive():  # else a process still holds the pipe: leave it be
            self.stream.close()


class Sandbox:
    """A submission's source, a private temporary folder, and the child that runs it.

    Use as a context manager; :meth:`call` starts a child when none is running. ``cases``
    is how many cases the child will answer in all (it sizes the CPU-time backstop);
    ``level`` overrides :func:`isolation`. The wall-clock budget (``limits.budget``) runs
    from construction.
    """

    def __init__(self, source: str, functions: list[str], limits: Limits,
                 allowed_imports: frozenset[str], cases: int = 0, level: str | None = None):
        self.limits = limits
        self.functions = functions
        self.allowed = sorted(allowed_imports)
        self.level = Isolation(level) if level is not None else isolation()
        self.memory_mb = limits.memory_mb if self.level.posix else None  # None: no limit
        self.cpu_seconds = math.ceil(limits.cpu_seconds if limits.cpu_seconds is not None
                                     else limits.load_timeout + limits.case_timeout * cases)
        self.deadline = time.monotonic() + limits.budget
        self.source = source
        # the real, long path (no symbolic link, no Windows ~1 name): what the child's hook sees
        self.root = Path(os.path.realpath(tempfile.mkdtemp(prefix="sandbox-",
                                                           dir=runtime.workspace())))
        self.stdout = self.root / "stdout.txt"
        self.proc: subprocess.Popen[bytes] | None = None
        self.missing: list[str] = []
        self.load_error: dict[str, Any] | None = None
        self._replies: Replies | None = None
        self._lease: jail.Lease | None = None
        self._watch: jail.DiskWatch | None = None
        self._spawned: subprocess.Popen[bytes] | None = None  # the last child started
        self._starting = threading.Lock()  # a child starts, or the disk watch empties its folder
        self.work = self.root / "work"
        try:
            if self.level.staged and os.geteuid() == 0:
                # a user id of its own (for bwrap too): no process count, signal or file is
                # shared with a classmate's sandbox or with a host daemon running as nobody
                self._lease = jail.Lease()
            if self.level is Isolation.CHROOT:
                self.work = runtime.staged().work / self.root.name
            if self.level is not Isolation.BUBBLEWRAP:
                self._make_work()
        except OSError as exc:  # no free user id, no runtime: the machine's
            self.__exit__()
            raise Unavailable(f"the sandbox could not be prepared ({exc})") from None
        except BaseException:
            self.__exit__()
            raise

    def _make_work(self) -> None:
        """The child's working folder, holding the submission (bubblewrap's is a tmpfs made
        inside the sandbox)."""
        work = self.work
        if self.level is Isolation.CHROOT:  # the leased user's alone
            assert self._lease is not None
            work.mkdir(mode=0o700)
            os.chown(work, self._lease.uid, self._lease.uid)
        else:
            runtime_dir = self.root / "runtime"
            runtime_dir.mkdir()
            # explicit modes: the grader's copy may be its owner's alone (setup.sh)
            for f in runtime.CHILD_FILES:
                (runtime_dir / f.name).write_bytes(f.read_bytes())
                os.chmod(runtime_dir / f.name, 0o644)
            work.mkdir()
        (work / "submission.py").write_text(self.source, encoding="utf-8")

    def _disk_full(self) -> None:
        """The disk watch's call (on its thread): the child wrote past ``limits.disk_mb``;
        stop it and give the next child the folder as it was."""
        with self._starting:
            proc = self._spawned
            if proc is not None and proc.returncode is None:
                try:
                    os.killpg(proc.pid, signal.SIGKILL)
                except (ProcessLookupError, PermissionError):
                    pass
            assert self._lease is not None
            jail.reap(self._lease.uid)
            remove_tree(self.work)
            self._make_work()

    def __enter__(self) -> Sandbox:
        return self

    def __exit__(self, *exc: object) -> None:
        if self._watch is not None:
            self._watch.close()
        self.stop()
        if self._lease is not None:
            self._lease.release()  # after its processes are gone
            remove_tree(self.work)
        remove_tree(self.root)

    # --- lifecycle ---------------------------------------------------------------------------

    def _command(self, config: dict[str, Any], program: list[str] | None = None
                 ) -> tuple[list[str], list[int]]:
        """The command that starts the child, and the descriptors it must inherit (the
        bubblewrap level reads its files and filter from them). ``program``: the
        interpreter's arguments instead of the child's (the tests' raw attacks)."""
        level = self.level
        if level.staged:
            rt = runtime.staged()
            base, python = INSIDE, f"{INSIDE}/python/bin/python3"
            numpy_path, stdlib = f"{INSIDE}/lib", f"{INSIDE}/python/lib/python{rt.version}"
        else:
            base, python = str(self.root), os.path.realpath(sys.executable)
            numpy_path = str(Path(np.__file__).resolve().parent.parent)
            stdlib = ""
        work = f"{INSIDE}/work/{self.work.name}" if level is Isolation.CHROOT else f"{base}/work"
        config.update(cwd=work, submission=f"{work}/submission.py",
                      protocol=f"{base}/runtime/protocol.py", numpy_path=numpy_path,
                      numpy_dirs=[f"{numpy_path}/numpy", f"{numpy_path}/numpy.libs"],
                      stdlib=stdlib)
        cmd = [python, *(program or ["-I", "-S", "-B", "-u", f"{base}/runtime/child.py",
                                     json.dumps(config)])]
        limits = config.get("limits") or {}
        prlimit = shutil.which("prlimit") if level.staged else None
        # The limits hold from the interpreter's first instruction, not from the child's own
        # setrlimit calls: prlimit sets them on what it starts, and they pass on from there.
        # RLIMIT_NPROC counts every task of bwrap's host user: a leased one's are this
        # submission's alone, but the grader's own user (a grader not root) has its desktop's
        # too, and bwrap could not start; there the child sets it itself, where it counts the
        # tasks of its own user namespace only.
        nproc = [] if level is Isolation.BUBBLEWRAP and self._lease is None else [
            f"--nproc={limits.get('tasks')}"]
        cap = [prlimit, f"--as={limits['memory_mb'] << 20}",
               f"--cpu={limits['cpu_seconds']}:{limits['cpu_seconds'] + 1}",
               f"--fsize={limits['file_mb'] << 20}", "--core=0", "--nofile=64",
               *nproc, "--"] if prlimit and limits else []
        if level is Isolation.CHROOT:
            assert self._lease is not None
            return [*cap, *jail.launcher("run", str(self._lease.uid), str(rt.jail), work,
                                         "--", *cmd)], []
        if level is not Isolation.BUBBLEWRAP:
            return [*cap, *cmd], []
        fds = [_memfd(seccomp.program()), _memfd(self.source.encode("utf-8"))]
        fds += [_memfd(f.read_bytes()) for f in runtime.CHILD_FILES]
        uid = str(SANDBOX_UID)
        return [*cap, "bwrap", "--unshare-all", "--unshare-user", "--disable-userns",
                "--die-with-parent", "--new-session", "--uid", uid, "--gid", uid,
                "--hostname", "sandbox",
                "--ro-bind", rt.loader, rt.loader,
                "--ro-bind", str(rt.python_home), f"{INSIDE}/python",
                "--ro-bind", str(rt.numpy_path), f"{INSIDE}/lib",
                "--ro-bind-data", str(fds[2]), f"{INSIDE}/runtime/child.py",
                "--ro-bind-data", str(fds[3]), f"{INSIDE}/runtime/protocol.py",
                "--size", str(self.limits.disk_mb << 20), "--tmpfs", f"{INSIDE}/work",
                "--file", str(fds[1]), f"{INSIDE}/work/submission.py",
                # /dev's own tmpfs (its shm/) would be writable past the disk limit
                "--dev", "/dev", "--remount-ro", "/dev", "--remount-ro", "/",
                "--seccomp", str(fds[0]), "--chdir", f"{INSIDE}/work", "--", *cmd], fds

    def start(self) -> Outcome:
        """Start a child and wait until the submission is loaded (status ``ok`` if it is, or
        the submission's own failure to load).

        A child that ends or hangs before the submission's first instruction (the child's
        ``started`` frame: bwrap refused a namespace or a fork for want of a resource, the
        interpreter could not start) is the machine's: that start is tried again
        (:data:`START_ATTEMPTS` in all), and then :class:`Unavailable` says what the sandbox
        said last."""
        said = ""
        for _ in range(START_ATTEMPTS):
            logged = self._logged()
            started = self._start_once()
            if started.status == "crash":  # while the submission loaded: its last line says why
                last = self._last_words(logged, drop=False)
                return replace(started, message=started.message + (
                    f" (the last line it wrote: {last})" if last else ""))
            if started.status != "unstarted":
                return started
            said = self._last_words(logged, drop=True) or started.message
        raise Unavailable(f"the sandbox could not start ({said})")

    def _logged(self) -> int:
        """How many bytes the child's output log holds now."""
        try:
            return os.path.getsize(self.stdout)
        except OSError:
            return 0

    def _last_words(self, logged: int, drop: bool) -> str:
        """The last line written to the log after its first ``logged`` bytes: bwrap's reason,
        the interpreter's last error, the submission's last output. ``drop``: remove them
        from the log (the sandbox's words, not the submission's output)."""
        try:
            with open(self.stdout, "rb") as f:
                f.seek(max(logged, self._logged() - 4096))
                text = f.read(4096).decode("utf-8", "replace")
            if drop:
                os.truncate(self.stdout, logged)
        except OSError:
            return ""
        lines = [line.strip() for line in text.splitlines() if line.strip()]
        return printable(lines[-1])[:300] if lines else ""

    def _start_once(self) -> Outcome:
        if time.monotonic() >= self.deadline:
            return Outcome("timeout", message=self._budget_message())
        config = {"functions": self.functions, "allowed": self.allowed,
                  "limits": {"cpu_seconds": self.cpu_seconds, "memory_mb": self.memory_mb,
                             "file_mb": self.limits.disk_mb, "tasks": TASKS.get(self.level)}
                  if self.level.posix else None}
        try:
            with open(self.stdout, "ab") as log:
                self.proc = self.spawn(config, stdout=subprocess.PIPE, stderr=log)
        except OSError as exc:  # the runtime could not be staged, say
            return Outcome("crash", message=f"the sandbox could not be prepared ({exc})")
        assert self.proc.stdout is not None
        self._replies = Replies(self.proc.stdout)
        deadline = time.monotonic() + self.limits.load_timeout
        began = self._began(deadline)
        if began:
            return began
        first = self._receive(deadline, "your file")
        if first.status != "ok":
            return first
        frame: dict[str, Any] = first.value if isinstance(first.value, dict) else {}
        if frame.get("op") == "load_error":
            try:
                self.load_error = _error(frame.get("error"))
            except ProtocolError:
                self.load_error = None
            self.stop()
            if self.load_error is None:
                return Outcome("garbage", message="the sandbox sent an unexpected message")
            return Outcome("error", error=self.load_error)
        missing = frame.get("missing")
        if (frame.get("op") != "ready" or not isinstance(missing, list)
                or not all(m in self.functions for m in missing if isinstance(m, str))
                or not all(isinstance(m, str) for m in missing)):
            self.stop()
            return Outcome("garbage", message="the sandbox sent an unexpected message")
        self.missing = list(missing)
        return Outcome("ok")

    def _began(self, deadline: float) -> Outcome | None:
        """None once the child says it started (the submission runs next); otherwise an
        ``unstarted`` outcome saying how it ended, or the budget's timeout if that ran out."""
        assert self._replies is not None
        try:
            frame = self._replies.get(min(deadline, self.deadline))
        except TimeoutError:
            frame = "timeout"
        except ProtocolError:
            frame = "garbage"
        if frame == {"op": "started"}:
            return None
        code = self._reap(1.0)[0] if frame is None else None
        self.stop()
        if time.monotonic() >= self.deadline:
            return Outcome("timeout", message=self._budget_message())
        how = (f"it did not start within {self.limits.load_timeout:g} s" if frame == "timeout"
               else f"it ended with code {code}" if frame is None
               else "its first message was not the child's")
        return Outcome("unstarted", message=how)

    def spawn(self, config: dict[str, Any], program: list[str] | None = None,
              **popen: Any) -> subprocess.Popen[bytes]:
        """Start the child's process as :meth:`_command` says, as the leased user when the
        grader is root (a submission never runs as root), with a pipe for its input."""
        cmd, fds = self._command(config, program)
        if self.level is Isolation.BUBBLEWRAP and self._lease is not None:
            popen.update(user=self._lease.uid, group=self._lease.uid, extra_groups=[])
        env = _environment(config["cwd"])
        if self.level.staged:
            env["LD_LIBRARY_PATH"] = f"{INSIDE}/python/lib"
        if self.level is Isolation.CHROOT and self._watch is None:
            self._watch = jail.DiskWatch(self.work, self.limits.disk_mb << 20, self._disk_full)
        try:
            with self._starting:
                self._spawned = subprocess.Popen(
                    cmd, cwd=self.root, env=env, stdin=subprocess.PIPE, bufsize=0,
                    start_new_session=self.level.posix, pass_fds=fds,
                    creationflags=getattr(subprocess, "CREATE_NO_WINDOW", 0),  # no console
                    **popen)
                return self._spawned
        finally:
            for fd in fds:
                os.close(fd)

    def stop(self) -> None:
        """Kill the child (at the POSIX levels its whole process group, and with bubblewrap
        its PID namespace)."""
        if self.proc is None:
            return
        self._reap(None)
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        if self._replies is not None:
            self._replies.close()
        self._replies = None
        self.proc = None

    def _reap(self, timeout: float | None) -> tuple[int | None, float | None]:
        """End the child: wait up to ``timeout`` s for it to exit by itself (None: kill it
        now), kill what is left of its process group, and reap it. Returns its exit code
        (negative for a signal, as :class:`subprocess.Popen` has it) and the CPU seconds it
        and its descendants used (None at the portable level), or ``(None, None)`` if it is
        still running."""
        proc = self.proc
        if proc is None or proc.returncode is not None:
            return (None, None) if proc is None else (proc.returncode, None)
        if not self.level.posix:  # no process group (it may start no process), no rusage
            if timeout is not None:
                try:
                    proc.wait(timeout)
                except subprocess.TimeoutExpired:
                    return None, None
            proc.kill()  # nothing once it has exited
            return proc.wait(), None
        deadline = None if timeout is None else time.monotonic() + timeout
        while deadline is not None:  # exited? (WNOWAIT: not reaped, so its group id stays ours)
            if os.waitid(os.P_PID, proc.pid, os.WEXITED | os.WNOWAIT | os.WNOHANG) is not None:
                break
            if time.monotonic() >= deadline:
                return None, None
            time.sleep(0.01)
        try:  # bwrap's own processes: killing them ends the PID namespace (--die-with-parent)
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        try:
            _, status, usage = os.wait4(proc.pid, 0)
        except ChildProcessError:  # reaped elsewhere
            proc.returncode = -signal.SIGKILL
            return proc.returncode, None
        code = os.waitstatus_to_exitcode(status)
        if self.level is Isolation.BUBBLEWRAP and code > 128:  # bwrap's 128 + n: signal n
            code = 128 - code
        proc.returncode = code
        return code, usage.ru_utime + usage.ru_stime

    # --- calls -------------------------------------------------------------------------------

    def call(self, fn: str, cases: list[tuple[Any, ...]],
             sizes: list[int] | None = None) -> list[Outcome]:
        """Evaluate ``fn`` on each argument tuple. ``sizes[i]``: the most numbers case ``i``
        may return (a larger answer is not decoded; see :func:`_bounded`). After a fatal
        case a fresh child runs the rest, and is stopped when they are done; after
        ``limits.max_fatal`` fatal cases (or forged frames) the rest are skipped, and so is
        everything once the budget is spent."""
        sizes = sizes if sizes is not None else [MAX_NUMBERS] * len(cases)
        outcomes: list[Outcome] = []
        while len(outcomes) < len(cases):
            if time.monotonic() >= self.deadline:
                break
            if self.proc is None:
                started = self.start()
                if started.status != "ok":
                    outcomes.append(started)
                    break
            done = len(outcomes)
            outcomes += self._run(fn, cases[done:], sizes[done:])
            fatal = sum(o.status in FATAL for o in outcomes)
            if outcomes[-1].status == "garbage" or fatal >= self.limits.max_fatal:
                break
        if any(o.status in FATAL for o in outcomes):
            # the fresh child that ran the rest has spent this test's CPU time and memory:
            # the next test gets its own, so it is never charged for this one
            self.stop()
        left = len(cases) - len(outcomes)
        if left and time.monotonic() >= self.deadline:
            return outcomes + [Outcome("skipped", message=self._budget_message())] * left
        fatal = sum(o.status in FATAL for o in outcomes)
        skipped = Outcome("skipped", message=f"not run: {fatal} case{'s' * (fatal > 1)} of this "
                                             "test stopped the interpreter")
        return outcomes + [skipped] * left

    def _run(self, fn: str, cases: list[tuple[Any, ...]], sizes: list[int]) -> list[Outcome]:
        """One request to the live child: the outcomes up to and including a fatal one."""
        nonce = secrets.token_hex(16)
        assert self.proc is not None and self.proc.stdin is not None
        try:
            write_frame(self.proc.stdin.fileno(), {"fn": fn, "nonce": nonce, "most": sizes,
                                                   "cases": [encode_args(a) for a in cases]})
        except OSError:
            return [self._fatal("crash", fn)]
        outcomes: list[Outcome] = []
        for i in range(len(cases)):
            # JSON spends at most ~25 bytes on a number: a longer answer is dropped unread
            got = self._receive(time.monotonic() + self.limits.case_timeout, fn,
                                32 * sizes[i] + 4096)
            if got.status != "ok":
                return outcomes + [got]
            frame = got.value
            if isinstance(frame, dict) and set(frame) == {"oversized"}:
                outcomes.append(_too_many(f"{frame['oversized']} bytes", sizes[i]))
                continue
            if not isinstance(frame, dict) or frame.get("nonce") != nonce or frame.get("case") != i:
                return outcomes + [self._fatal("garbage", _forged(fn))]
            counted = frame.get("value")
            if isinstance(counted, dict) and counted.get("kind") == "oversized":
                outcomes.append(_too_many(f"{counted.get('numbers')!s:.20} numbers", sizes[i]))
                continue
            try:
                outcomes.append(
                    Outcome("ok", value=_bounded(frame["value"], sizes[i]))
                    if frame.get("ok") is True else Outcome("error", error=_error(frame["error"])))
            except (ProtocolError, KeyError, TypeError) as exc:
                return outcomes + [self._fatal("garbage", _forged(fn) + f" ({exc})")]
        done = self._receive(time.monotonic() + self.limits.case_timeout, fn)
        # _receive's value is the raw frame (a dict), not a decoded Value.
        if done.status != "ok" or done.value != {  # type: ignore[comparison-overlap]
                "done": True, "nonce": nonce}:
            bad = done if done.status != "ok" else self._fatal("garbage", _forged(fn))
            return [bad] * len(cases)
        return outcomes

    def _receive(self, deadline: float, what: str, parse_at_most: int = MAX_FRAME) -> Outcome:
        """The next frame as ``Outcome("ok", value=frame)``, or a fatal outcome; ``what`` is
        running (a function's name, or "your file" while loading) for the messages. The
        submission's budget cuts every deadline short."""
        assert self._replies is not None
        try:
            frame = self._replies.get(min(deadline, self.deadline), parse_at_most)
        except TimeoutError:
            if time.monotonic() >= self.deadline:
                return self._fatal("timeout", self._budget_message())
            if what == "your file":
                return self._fatal("timeout", f"your file did not finish loading within "
                                              f"{self.limits.load_timeout:g} s")
            return self._fatal("timeout", f"{what} did not finish within "
                                          f"{self.limits.case_timeout:g} s on this case (an "
                                          "endless loop, or too slow?)")
        except ProtocolError as exc:
            return self._fatal("garbage", _forged(what) + f" ({exc})")
        if frame is None:
            return self._fatal("crash", what)
        return Outcome("ok", value=frame)

    def _budget_message(self) -> str:
        return (f"not run: your submission used its whole time budget ({self.limits.budget:g} s "
                "for all tests, besides a rollout test's own time); what was left scores 0")

    def _fatal(self, status: str, what: str) -> Outcome:
        code = cpu = None
        if status == "crash":
            code, cpu = self._reap(1.0)
        self.stop()
        if status == "crash" and self._watch is not None and self._watch.exceeded:
            self._watch.exceeded = False
            return Outcome("crash", message=f"{what} wrote more than the {self.limits.disk_mb} "
                                            "MB of files a submission may write; it was stopped")
        if status == "crash":
            return Outcome("crash", message=_crash_message(code, cpu, what, self.cpu_seconds,
                                                           self.memory_mb))
        return Outcome(status, message=what)

    def output(self, limit: int = 2000) -> str:
        """The first ``limit`` characters the submission printed (stdout and stderr)."""
        try:
            with open(self.stdout, "rb") as f:
                return f.read(limit).decode("utf-8", "replace")
        except OSError:
            return ""


MAX_NUMBERS = 1 << 20  # the most numbers any answer may hold, whatever it is expected to be


def _too_many(what: str, limit: int) -> Outcome:
    return Outcome("ok", value=Value("other", f"answer of {what} (far more numbers than the "
                                              f"{limit} that could make sense here)"))


def _bounded(obj: Any, limit: int) -> Value:
    """The child's value decoded, unless it declares more numbers than ``limit`` (then it is
    described, not decoded: no answer costs the grader more than its expected size)."""
    n = numbers_in(obj)
    if n > limit:
        return Value("other", f"array of {n} numbers (too large: at most {limit} make sense "
                              "here)")
    return decode_value(obj)


def _memfd(data: bytes) -> int:
    """A file holding ``data`` that exists only as a descriptor, read from the start."""
    fd = os.memfd_create("autograder", 0)  # inheritable: bwrap reads it
    os.write(fd, data)
    os.lseek(fd, 0, os.SEEK_SET)
    return fd


def remove_tree(path: Path) -> None:
    """Remove the folder ``path`` and everything in it, however deep and whatever the modes
    a submission left: folders are moved up to ``path`` one level at a time (two open
    descriptors, no recursion, no long paths) and removed once empty."""
    try:
        top = os.open(path, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
    except OSError:
        return
    stuck: set[str] = set()
    moved = 0
    try:
        while True:
            names = [e.name for e in os.scandir(top) if e.name not in stuck]
            if not names:
                break
            for name in names:
                if _unlink_or_empty(name, top):
                    continue
                try:
                    sub = _open_dir(name, top)
                except OSError:
                    stuck.add(name)
                    continue
                try:
                    for entry in os.scandir(sub):
                        if not _unlink_or_empty(entry.name, sub):
                            moved += 1
                            os.rename(entry.name, f".moved-{moved}", src_dir_fd=sub,
                                      dst_dir_fd=top)
                except OSError:
                    stuck.add(name)
                finally:
                    os.close(sub)
    finally:
        os.close(top)
    try:
        os.rmdir(path)
    except OSError:
        pass


def _unlink_or_empty(name: str, parent: int) -> bool:
    """Remove ``name`` if it is a file or an empty folder; False if it is a folder that is
    not empty (or could not be removed)."""
    try:
        os.unlink(name, dir_fd=parent)
        return True
    except IsADirectoryError:
        pass
    except OSError:
        return False
    try:
        os.rmdir(name, dir_fd=parent)
        return True
    except OSError:
        return False


def _open_dir(name: str, parent: int) -> int:
    try:
        return os.open(name, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW, dir_fd=parent)
    except PermissionError:  # a folder its maker closed to everyone
        os.chmod(name, 0o700, dir_fd=parent)
        return os.open(name, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW, dir_fd=parent)


def _environment(cwd: str) -> dict[str, str]:
    """The child's whole environment: no seed, no paths but the system's, one BLAS thread
    (Windows needs its SYSTEMROOT to start)."""
    env = {"PATH": "/usr/bin:/bin:/usr/sbin:/sbin", "HOME": cwd, "PWD": cwd, "TMPDIR": cwd,
           "LANG": "C.UTF-8", "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1"}
    if os.name == "nt":
        env.update(SYSTEMROOT=os.environ.get("SYSTEMROOT", r"C:\Windows"), TEMP=cwd, TMP=cwd,
                   USERPROFILE=cwd)
    return env


def _error(e: Any) -> dict[str, Any]:
    if not isinstance(e, dict):
        raise ProtocolError("bad error report")
    where = e.get("where")
    if where is not None and not (isinstance(where, dict) and isinstance(where.get("line"), int)):
        where = None
    return {"type": str(e.get("type", "Exception"))[:60],
            "message": str(e.get("message", ""))[:300],
            "where": where and {"line": where["line"], "code": str(where.get("code", ""))[:120]}}


def _forged(what: str) -> str:
    if what == "your file":
        return ("while your file loaded, something else wrote to the grader's private result "
                "channel; nothing can be graded")
    return (f"while {what} ran, something else wrote to the grader's private result channel; "
            "this test scores 0")


def _crash_message(code: int | None, cpu: float | None, what: str, cpu_limit: float,
                   memory_mb: int | None) -> str:
    """Why the interpreter stopped: the CPU time it used comes first, since the kernel ends a
    process over its CPU limit with SIGXCPU or SIGKILL and a wrapper may report either.
    ``memory_mb`` None: no memory limit (the portable level)."""
    out_of_cpu = (f"{what} ran out of CPU time: the interpreter used its {cpu_limit:g} s of CPU "
                  "time for all cases (threads still running?)")
    if cpu is not None and cpu >= 0.9 * cpu_limit:
        return out_of_cpu
    if code is None:
        return f"the interpreter stopped responding while {what} ran"
    if code < 0:  # a signal: POSIX only (Windows codes are unsigned)
        if -code == signal.SIGXCPU:
            return out_of_cpu
        if -code == signal.SIGKILL:
            limit = f"the limit is {memory_mb} MB" if memory_mb else "there is no limit here"
            return f"the interpreter was killed while {what} ran (out of memory? {limit})"
        name = signal.Signals(-code).name if -code in signal.valid_signals() else -code
        return f"the interpreter crashed ({name}) while {what} ran"
    if code >= 0xC0000000:  # a Windows exception status (0xC0000005: access violation)
        return f"the interpreter crashed (0x{code:08X}) while {what} ran"
    return (f"the interpreter exited (code {code}) while {what} ran; does your code call "
            "sys.exit(), exit() or os._exit()?")
