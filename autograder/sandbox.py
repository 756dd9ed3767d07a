"""Run a submission's functions in a separate, limited interpreter.

One :class:`Sandbox` per submission holds a temporary directory with the submission, a copy
of the child's own code (:mod:`autograder.child` and :mod:`autograder.protocol`, so nothing
runs from the repository) and at most one live child. How the child is isolated depends on
what the machine allows (:func:`isolation`), strongest first:

``"namespaces"`` (Linux with user namespaces)
    ``unshare --user --map-root-user --mount --net --pid --fork``: no network, a PID
    namespace (every process the submission forks dies with it), and a private file system
    entered with ``chroot``: read-only bind mounts of the system libraries, the interpreter
    and its standard library (every ``site-packages`` hidden), numpy and the child's code,
    and the working directory, the one writable place. The repository, the reference, the
    grader's output, other submissions, ``/proc`` and the home directory do not exist for
    the submission.
``"unshare"``
    the same without the private file system (when mounts are not allowed).
``"plain"`` (macOS with Python 3.13 or newer, containers without namespaces)
    a separate process group only; the child's audit hook alone keeps files, sockets and
    processes out of reach. Reports say so.
``"portable"`` (Windows, older macOS Pythons, any system without the POSIX process controls
of :func:`posix_controls`)
    the audit hook alone, and no resource limits: no memory or CPU-time limit, and the
    child alone is killed (it may start no process). Reports say so.

In every case the child runs as ``python -I -S -B -u`` (isolated mode, no site-packages, no
bytecode writes) with a minimal environment (no seed, no paths) in a fresh working
directory, and talks to the grader over its own standard input and output (the child moves
them out of the submission's reach); each case has a wall-clock deadline enforced here, by
waiting for the child's answer on a thread (:class:`Replies`), which works on every
platform. At the POSIX levels it also has address-space and file-size limits, and a
CPU-time limit for its whole life sized for all its cases (a backstop). A case that hangs,
crashes the interpreter or answers with garbage is *fatal*: the child is killed and a fresh
one runs the remaining cases, so one slow or crashing case costs only itself (after
``Limits.max_fatal`` of them in one test, or one forged answer, the rest of it is skipped).
The levels differ only in the command that starts the child, whether it limits itself, and
how it is ended (:meth:`Sandbox._reap`).
"""

from __future__ import annotations

import glob
import json
import math
import os
import queue
import secrets
import shutil
import signal
import site
import subprocess
import sys
import sysconfig
import tempfile
import threading
import time
from dataclasses import dataclass, field
from functools import cache
from importlib.util import find_spec
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from .protocol import ProtocolError, Value, decode_value, encode_args, read_frame, write_frame

RUNTIME = (Path(__file__).with_name("child.py"), Path(__file__).with_name("protocol.py"))
UNSHARE = ["unshare", "--user", "--map-root-user", "--net", "--pid", "--fork", "--kill-child"]
LEVELS = ("namespaces", "unshare", "plain", "portable")  # strongest first
FATAL = ("timeout", "crash", "garbage")
INSIDE = "/sandbox"  # where the working directory, the child's code and numpy appear
# The shell stays the namespace's first process and exits with the child's status (128 + n
# for a signal n), so the status of a child killed by a signal is never lost. The child's
# stderr is the shell's, kept on descriptor 3 (free: the grader's pipes are 0 and 1); the
# shell's own (its "Killed" notices, printed outside the subshell that runs the child) goes
# to /dev/null.
WAIT_SCRIPT = r"""
exec 3>&2 2>/dev/null
(exec "$@" 2>&3 3>&-)
exit $?
"""
# Arguments: the new root (a skeleton of empty mount points, made by Sandbox), (kind,
# source, target) triples, then "--" and the command. One process per mount; then the
# command runs as in WAIT_SCRIPT.
MOUNT_SCRIPT = r"""
set -eu
root=$1
shift
mount --rbind "$root" "$root"
while [ "$1" != "--" ]; do
    case $1 in
        ro) mount --rbind -o ro "$2" "$root$3" ;;
        rw) mount --bind "$2" "$root$3" ;;
        hide) if [ -d "$root$3" ]; then mount -t tmpfs -o ro,size=4k hidden "$root$3"; fi ;;
    esac
    shift 3
done
shift
mount -o remount,bind,ro "$root"
set +e
exec 3>&2 2>/dev/null
(exec chroot "$root" "$@" 2>&3 3>&-)
exit $?
"""


@dataclass(frozen=True)
class Limits:
    """Resource limits for one submission's child interpreter.

    ``case_timeout`` is the wall-clock time one case may take; ``cpu_seconds`` the CPU time
    one interpreter may use over its whole life, a backstop for work the deadlines do not
    see (threads); None sizes it for every case to use its ``case_timeout``. The
    ``"portable"`` level keeps the wall-clock limits only.
    """

    cpu_seconds: float | None = None
    memory_mb: int = 1024
    load_timeout: float = 10.0  # wall seconds to start and import the submission
    case_timeout: float = 2.0  # wall seconds per case
    max_fatal: int = 2  # cases of one test that may stop the interpreter before the rest skip


DEFAULT_LIMITS = Limits()


@dataclass
class Outcome:
    """What became of one case: ``status`` is ``ok`` (``value`` holds the return value),
    ``error`` (the function raised; ``error`` has type, message, line), or a fatal
    ``timeout``, ``crash`` or ``garbage`` (``message`` says what happened), or ``skipped``."""

    status: str
    value: Value | None = None
    error: dict[str, Any] = field(default_factory=dict)
    message: str = ""


ISOLATION_NOTES = {
    "namespaces": "",
    "unshare": "(No private file system here: the sandbox has no network and its own "
               "processes, and its audit hook keeps files outside its folder out of reach.)",
    "plain": "(No Linux namespaces here: the sandbox still limits time, memory, files and "
             "imports, with its audit hook alone.)",
    "portable": "(Weaker isolation on this system: the sandbox's audit hook alone keeps "
                "files, imports, sockets and processes out of reach, and each case still has "
                "its time limit, but memory and CPU time are not limited.)",
}


@cache
def isolation() -> str:
    """The strongest level of :data:`LEVELS` that starts a working child here (probed once:
    on Linux with ``unshare`` a child is started at each namespace level in turn until one
    loads an empty submission)."""
    if not posix_controls():
        return "portable"
    if sys.platform == "linux" and shutil.which("unshare"):
        for level in LEVELS[:2]:
            with Sandbox("", [], Limits(load_timeout=20.0), frozenset(), level=level) as box:
                if box.start().status == "ok":
                    return level
    return "plain"


def posix_controls() -> bool:
    """Whether this system has what the levels above ``"portable"`` use: process groups
    (``os.killpg``), a child's exit status without reaping it (``os.waitid``, missing on
    macOS before Python 3.13) and its CPU time (``os.wait4``), and resource limits."""
    return os.name == "posix" and find_spec("resource") is not None and all(
        hasattr(os, f) for f in ("killpg", "waitid", "wait4"))


def level_for(requested: str | None) -> str:
    """``requested`` if this machine offers it (it or a stronger level), else ValueError;
    None: the strongest, :func:`isolation`."""
    best = isolation()
    if requested is None:
        return best
    if requested not in LEVELS:
        raise ValueError(f"isolation: {requested!r} is not one of {', '.join(LEVELS)}")
    if LEVELS.index(requested) < LEVELS.index(best):
        raise ValueError(f"isolation: {requested!r} is not available on this machine (the "
                         f"strongest here is {best!r})")
    return requested


class Replies:
    """The child's frames from ``stream``, each read on a thread when it is asked for, so
    that waiting for one can end at a deadline on every platform (``select`` cannot wait on
    a pipe on Windows), and a child writing frames in a loop only fills its pipe."""

    def __init__(self, stream: BinaryIO):
        self.stream = stream
        self._asked = threading.Semaphore(0)
        self._got: queue.SimpleQueue[tuple[Any, Exception | None]] = queue.SimpleQueue()
        self._pending = False  # a frame was asked for and has not come yet
        self._closed = False
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()

    def _read(self) -> None:
        while True:
            self._asked.acquire()
            if self._closed:
                return
            try:
                frame, error = read_frame(self.stream.fileno()), None
            except ProtocolError as exc:
                frame, error = None, exc
            except OSError:  # the pipe is gone: as good as its end
                frame, error = None, None
            self._got.put((frame, error))
            if frame is None:
                return

    def get(self, deadline: float) -> Any | None:
        """The next frame; None at end of file (the child is gone); ``TimeoutError`` past
        ``deadline`` (monotonic); ``ProtocolError`` for a malformed one."""
        if not self._pending:
            self._pending = True
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


def _numpy_dirs() -> tuple[str, list[str]]:
    """numpy's parent directory (for ``sys.path``) and its package folders."""
    pkg = Path(np.__file__).resolve().parent
    dirs = [str(pkg)] + [str(p) for p in pkg.parent.glob("numpy.libs")]
    return str(pkg.parent), dirs


@cache
def _mounts() -> tuple[tuple[str, str, str], ...]:
    """The (kind, source, target) mounts of the private file system but the sandbox's own
    folders: read-only the system libraries, the interpreter and its standard library and
    numpy (``ro``), two devices (``rw``), every site-packages folder hidden (``hide``), and the
    symbolic links of a merged /usr (``link``, made in the skeleton)."""
    out: list[tuple[str, str, str]] = []

    def add(src: str, dst: str) -> None:
        if not any(dst == b or dst.startswith(b + "/") for k, _, b in out if k == "ro"):
            out.append(("ro", src, dst))

    for d in ("/usr", "/lib", "/lib64", "/lib32", "/libx32"):
        if os.path.islink(d):
            out.append(("link", os.readlink(d), d))
        elif os.path.isdir(d):
            add(d, d)
    if os.path.isfile("/etc/ld.so.cache"):
        add("/etc/ld.so.cache", "/etc/ld.so.cache")
    add(os.path.realpath(sys.executable), os.path.realpath(sys.executable))
    stdlib = os.path.realpath(os.path.dirname(os.__file__))
    for d in (sysconfig.get_config_var("LIBDIR"), stdlib):
        if d and os.path.isdir(d):
            add(os.path.realpath(d), os.path.realpath(d))
    for d in _numpy_dirs()[1]:
        out.append(("ro", d, f"{INSIDE}/lib/{Path(d).name}"))
    out += [("rw", dev, dev) for dev in ("/dev/null", "/dev/urandom")]
    out += [("hide", "-", d) for d in sorted(_site_dirs(stdlib))]
    return tuple(out)


def _skeleton(root: Path, mounts: list[tuple[str, str, str]]) -> None:
    """The empty mount points (folders, or files for files) and links of ``mounts``."""
    for kind, src, dst in mounts:
        target = root / dst.lstrip("/")
        if kind == "link":
            target.parent.mkdir(parents=True, exist_ok=True)
            target.symlink_to(src)
        elif kind in ("ro", "rw") and not os.path.isdir(src):
            target.parent.mkdir(parents=True, exist_ok=True)
            target.touch()
        elif kind in ("ro", "rw"):
            target.mkdir(parents=True, exist_ok=True)


def _site_dirs(stdlib: str) -> set[str]:
    """Every folder of installed packages this interpreter (or the system's) could show."""
    found = {os.path.join(stdlib, "site-packages"), os.path.join(stdlib, "dist-packages"),
             sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    try:
        found.update(site.getsitepackages() + [site.getusersitepackages()])
    except AttributeError:  # an old virtualenv's site module
        pass
    found.update(p for p in sys.path if p and "-packages" in p)
    for pattern in ("/usr/lib*/python3*/*-packages", "/usr/local/lib*/python3*/*-packages"):
        found.update(glob.glob(pattern))
    return {os.path.realpath(d) for d in found if os.path.isdir(d)}


class Sandbox:
    """A submission's source in a private directory, and the child that runs it.

    Use as a context manager; :meth:`call` starts a child when none is running. ``cases``
    is how many cases the child will answer in all (it sizes the CPU-time backstop);
    ``level`` overrides :func:`isolation`.
    """

    def __init__(self, source: str, functions: list[str], limits: Limits,
                 allowed_imports: frozenset[str], cases: int = 0, level: str | None = None):
        self.limits = limits
        self.functions = functions
        self.allowed = sorted(allowed_imports)
        self.level = level or isolation()
        self.posix = self.level != "portable"  # process groups, wait4, rlimits
        self.memory_mb = limits.memory_mb if self.posix else None  # None: no limit
        self.cpu_seconds = math.ceil(limits.cpu_seconds if limits.cpu_seconds is not None
                                     else limits.load_timeout + limits.case_timeout * cases)
        # the real, long path (no symbolic link, no Windows ~1 name): what the child's hook sees
        self.root = Path(os.path.realpath(tempfile.mkdtemp(prefix="autograder-")))
        self.work = self.root / "work"
        self.work.mkdir()
        self.runtime = self.root / "runtime"
        self.runtime.mkdir()
        for f in RUNTIME:
            shutil.copy(f, self.runtime / f.name)
        (self.work / "submission.py").write_text(source, encoding="utf-8")
        self.proc: subprocess.Popen | None = None
        self.missing: list[str] = []
        self.load_error: dict[str, Any] | None = None
        self.stdout = self.root / "stdout.txt"
        self._replies: Replies | None = None
        self._wrapped = self.level in ("namespaces", "unshare")  # a shell, see WAIT_SCRIPT

    def __enter__(self) -> Sandbox:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()
        shutil.rmtree(self.root, ignore_errors=True)

    # --- lifecycle ---------------------------------------------------------------------------

    def _command(self, level: str, config: dict) -> list[str]:
        python = os.path.realpath(sys.executable)
        if level == "namespaces":
            child = f"{INSIDE}/runtime/child.py"
            config.update(cwd=f"{INSIDE}/work", submission=f"{INSIDE}/work/submission.py",
                          protocol=f"{INSIDE}/runtime/protocol.py", numpy_path=f"{INSIDE}/lib",
                          numpy_dirs=[f"{INSIDE}/lib/{Path(d).name}" for d in _numpy_dirs()[1]])
        else:
            child = str(self.runtime / "child.py")
            numpy_path, numpy_dirs = _numpy_dirs()
            config.update(cwd=str(self.work), submission=str(self.work / "submission.py"),
                          protocol=str(self.runtime / "protocol.py"), numpy_path=numpy_path,
                          numpy_dirs=numpy_dirs)
        cmd = [python, "-I", "-S", "-B", "-u", child, json.dumps(config)]
        if level == "namespaces":
            mounts = [*_mounts(), ("ro", str(self.runtime), f"{INSIDE}/runtime"),
                      ("rw", str(self.work), f"{INSIDE}/work")]
            fs = self.root / "fs"
            if not fs.exists():
                _skeleton(fs, mounts)
            return [*UNSHARE, "--mount", "sh", "-c", MOUNT_SCRIPT, "sh", str(fs),
                    *(x for m in mounts if m[0] != "link" for x in m), "--", *cmd]
        if level == "unshare":
            return [*UNSHARE, "sh", "-c", WAIT_SCRIPT, "sh", *cmd]
        return cmd

    def start(self) -> Outcome:
        """Start a child and wait until the submission is loaded (status ``ok`` if it is)."""
        config = {"functions": self.functions, "allowed": self.allowed,
                  "limits": {"cpu_seconds": self.cpu_seconds, "memory_mb": self.memory_mb}
                  if self.posix else None}
        cmd = self._command(self.level, config)
        with open(self.stdout, "ab") as log:
            self.proc = subprocess.Popen(
                cmd, cwd=self.work, env=_environment(config["cwd"]), stdin=subprocess.PIPE,
                stdout=subprocess.PIPE, stderr=log, bufsize=0, start_new_session=self.posix,
                creationflags=getattr(subprocess, "CREATE_NO_WINDOW", 0),  # Windows: no console
            )
        assert self.proc.stdout is not None
        self._replies = Replies(self.proc.stdout)
        first = self._receive(time.monotonic() + self.limits.load_timeout, "your file")
        if first.status != "ok":
            return first
        frame = first.value
        if frame.get("op") == "load_error":
            self.load_error = frame["error"]
            self.stop()
            return Outcome("error", error=frame["error"])
        if frame.get("op") != "ready" or not isinstance(frame.get("missing"), list):
            self.stop()
            return Outcome("garbage", message="the sandbox sent an unexpected message")
        self.missing = [str(m) for m in frame["missing"]]
        return Outcome("ok")

    def stop(self) -> None:
        """Kill the child (at the POSIX levels its whole process group and, under unshare,
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
        if not self.posix:  # no process group (it may start no process), no rusage
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
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        try:
            _, status, usage = os.wait4(proc.pid, 0)
        except ChildProcessError:  # reaped elsewhere
            proc.returncode = -signal.SIGKILL
            return proc.returncode, None
        code = os.waitstatus_to_exitcode(status)
        if self._wrapped and code > 128:  # the shell's 128 + n: the child died of signal n
            code = 128 - code
        proc.returncode = code
        return code, usage.ru_utime + usage.ru_stime

    # --- calls -------------------------------------------------------------------------------

    def call(self, fn: str, cases: list[tuple[Any, ...]]) -> list[Outcome]:
        """Evaluate ``fn`` on each argument tuple. After a fatal case a fresh child runs the
        rest; after ``limits.max_fatal`` fatal cases (or forged frames) the rest are skipped."""
        outcomes: list[Outcome] = []
        while len(outcomes) < len(cases):
            if self.proc is None:
                started = self.start()
                if started.status != "ok":
                    outcomes.append(started)
                    break
            outcomes += self._run(fn, cases[len(outcomes):])
            fatal = sum(o.status in FATAL for o in outcomes)
            if outcomes[-1].status == "garbage" or fatal >= self.limits.max_fatal:
                break
        left = len(cases) - len(outcomes)
        fatal = sum(o.status in FATAL for o in outcomes)
        skipped = Outcome("skipped", message=f"not run: {fatal} case{'s' * (fatal > 1)} of this "
                                             "test stopped the interpreter")
        return outcomes + [skipped] * left

    def _run(self, fn: str, cases: list[tuple[Any, ...]]) -> list[Outcome]:
        """One request to the live child: the outcomes up to and including a fatal one."""
        nonce = secrets.token_hex(16)
        assert self.proc is not None and self.proc.stdin is not None
        try:
            write_frame(self.proc.stdin.fileno(), {"fn": fn, "nonce": nonce,
                                                   "cases": [encode_args(a) for a in cases]})
        except OSError:
            return [self._fatal("crash", fn)]
        outcomes: list[Outcome] = []
        for i in range(len(cases)):
            got = self._receive(time.monotonic() + self.limits.case_timeout, fn)
            if got.status != "ok":
                return outcomes + [got]
            frame = got.value
            if not isinstance(frame, dict) or frame.get("nonce") != nonce or frame.get("case") != i:
                return outcomes + [self._fatal("garbage", _forged(fn))]
            try:
                outcomes.append(
                    Outcome("ok", value=decode_value(frame["value"])) if frame.get("ok") is True
                    else Outcome("error", error=_error(frame["error"])))
            except (ProtocolError, KeyError, TypeError) as exc:
                return outcomes + [self._fatal("garbage", _forged(fn) + f" ({exc})")]
        done = self._receive(time.monotonic() + self.limits.case_timeout, fn)
        if done.status != "ok" or done.value != {"done": True, "nonce": nonce}:
            bad = done if done.status != "ok" else self._fatal("garbage", _forged(fn))
            return [bad] * len(cases)
        return outcomes

    def _receive(self, deadline: float, what: str) -> Outcome:
        """The next frame as ``Outcome("ok", value=frame)``, or a fatal outcome; ``what`` is
        running (a function's name, or "your file" while loading) for the messages."""
        assert self._replies is not None
        try:
            frame = self._replies.get(deadline)
        except TimeoutError:
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
        return Outcome("ok", value=frame)  # type: ignore[arg-type]

    def _fatal(self, status: str, what: str) -> Outcome:
        code = cpu = None
        if status == "crash":
            code, cpu = self._reap(1.0)
        self.stop()
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
    if cpu is not None and cpu >= 0.9 * cpu_limit:
        return (f"{what} ran out of CPU time: the interpreter used its {cpu_limit:g} s of CPU "
                "time for all cases (threads still running?)")
    if code is None:
        return f"the interpreter stopped responding while {what} ran"
    if code < 0:  # a signal: POSIX only (Windows codes are unsigned)
        if -code == signal.SIGXCPU:
            return f"{what} ran out of CPU time ({cpu_limit:g} s for all cases)"
        if -code == signal.SIGKILL:
            limit = f"the limit is {memory_mb} MB" if memory_mb else "there is no limit here"
            return f"the interpreter was killed while {what} ran (out of memory? {limit})"
        name = signal.Signals(-code).name if -code in signal.valid_signals() else -code
        return f"the interpreter crashed ({name}) while {what} ran"
    if code >= 0xC0000000:  # a Windows exception status (0xC0000005: access violation)
        return f"the interpreter crashed (0x{code:08X}) while {what} ran"
    return (f"the interpreter exited (code {code}) while {what} ran; does your code call "
            "sys.exit(), exit() or os._exit()?")
