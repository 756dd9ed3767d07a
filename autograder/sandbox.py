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
``"plain"`` (macOS, containers without namespaces)
    a separate process group only; the child's audit hook alone keeps files, sockets and
    processes out of reach. Reports say so.

In every case the child runs as ``python -I -S -B -u`` (isolated mode, no site-packages, no
bytecode writes) with a minimal environment (no seed, no paths), a fresh working directory,
address-space and file-size limits, and a CPU-time limit for its whole life sized for all
its cases (a backstop); each case has a wall-clock deadline enforced here. A case that
hangs, crashes the interpreter or answers with garbage is *fatal*: the child is killed and a
fresh one runs the remaining cases, so one slow or crashing case costs only itself (after
``Limits.max_fatal`` of them in one test, or one forged answer, the rest of it is skipped).
"""

from __future__ import annotations

import glob
import json
import math
import os
import secrets
import shutil
import signal
import site
import subprocess
import sys
import sysconfig
import tempfile
import time
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from .protocol import ProtocolError, Value, decode_value, encode_args, read_frame, write_frame

RUNTIME = (Path(__file__).with_name("child.py"), Path(__file__).with_name("protocol.py"))
UNSHARE = ["unshare", "--user", "--map-root-user", "--net", "--pid", "--fork", "--kill-child"]
LEVELS = ("namespaces", "unshare", "plain")
FATAL = ("timeout", "crash", "garbage")
INSIDE = "/sandbox"  # where the working directory, the child's code and numpy appear
# The shell stays the namespace's first process and exits with the child's status (128 + n
# for a signal n), so the status of a child killed by a signal is never lost. The child's
# stderr is the shell's, kept on a spare descriptor ($1); the shell's own (its "Killed"
# notices, printed outside the subshell that runs the child) goes to /dev/null.
WAIT_SCRIPT = r"""
spare=$1
shift
eval "exec $spare>&2 2>/dev/null"
eval "(exec \"\$@\" 2>&$spare $spare>&-)"
exit $?
"""
# Arguments: the new root (a skeleton of empty mount points, made by Sandbox), the spare
# descriptor, (kind, source, target) triples, then "--" and the command. One process per
# mount; then the command runs as in WAIT_SCRIPT.
MOUNT_SCRIPT = r"""
set -eu
root=$1
spare=$2
shift 2
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
eval "exec $spare>&2 2>/dev/null"
eval "(exec chroot \"\$root\" \"\$@\" 2>&$spare $spare>&-)"
exit $?
"""


@dataclass(frozen=True)
class Limits:
    """Resource limits for one submission's child interpreter.

    ``case_timeout`` is the wall-clock time one case may take; ``cpu_seconds`` the CPU time
    one interpreter may use over its whole life, a backstop for work the deadlines do not
    see (threads); None sizes it for every case to use its ``case_timeout``.
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
}


@cache
def isolation() -> str:
    """The strongest level of :data:`LEVELS` that starts a working child here (probed once:
    a child is started at each level in turn until one loads an empty submission)."""
    for level in LEVELS[:-1]:
        if sys.platform != "linux" or not shutil.which("unshare"):
            break
        with Sandbox("", [], Limits(load_timeout=20.0), frozenset(), level=level) as box:
            if box.start().status == "ok":
                return level
    return "plain"


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
        self.level = level
        self.cpu_seconds = math.ceil(limits.cpu_seconds if limits.cpu_seconds is not None
                                     else limits.load_timeout + limits.case_timeout * cases)
        self.root = Path(tempfile.mkdtemp(prefix="autograder-"))
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
        self._fds: tuple[int, ...] = ()
        self._wrapped = False  # a shell between us and the child (see WAIT_SCRIPT)

    def __enter__(self) -> Sandbox:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()
        shutil.rmtree(self.root, ignore_errors=True)

    # --- lifecycle ---------------------------------------------------------------------------

    def _command(self, level: str, config: dict) -> list[str]:
        python = os.path.realpath(sys.executable)
        # a descriptor the shell may use (one digit, not one of the child's pipes)
        spare = str(next(n for n in range(3, 10) if n not in (config["req_fd"],
                                                               config["res_fd"])))
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
            return [*UNSHARE, "--mount", "sh", "-c", MOUNT_SCRIPT, "sh", str(fs), spare,
                    *(x for m in mounts if m[0] != "link" for x in m), "--", *cmd]
        if level == "unshare":
            return [*UNSHARE, "sh", "-c", WAIT_SCRIPT, "sh", spare, *cmd]
        return cmd

    def start(self) -> Outcome:
        """Start a child and wait until the submission is loaded (status ``ok`` if it is)."""
        level = self.level or isolation()
        req_r, self._req = os.pipe()
        self._res, res_w = os.pipe()
        self._fds = (self._req, self._res)
        config = {"req_fd": req_r, "res_fd": res_w, "functions": self.functions,
                  "allowed": self.allowed, "cpu_seconds": self.cpu_seconds,
                  "memory_mb": self.limits.memory_mb}
        cmd = self._command(level, config)
        self._wrapped = level != "plain"
        env = {"PATH": "/usr/bin:/bin:/usr/sbin:/sbin", "HOME": config["cwd"],
               "PWD": config["cwd"], "TMPDIR": config["cwd"], "LANG": "C.UTF-8",
               "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
        with open(self.stdout, "ab") as out:
            self.proc = subprocess.Popen(
                cmd, cwd=self.work, env=env, stdin=subprocess.DEVNULL, stdout=out,
                stderr=subprocess.STDOUT, pass_fds=(req_r, res_w), start_new_session=True,
            )
        os.close(req_r)
        os.close(res_w)
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
        """Kill the child's whole process group (and, under unshare, its PID namespace)."""
        if self.proc is None:
            return
        self._reap(None)
        self._close()

    def _close(self) -> None:
        for fd in self._fds:
            try:
                os.close(fd)
            except OSError:
                pass
        self._fds = ()
        self.proc = None

    def _reap(self, timeout: float | None) -> tuple[int | None, float | None]:
        """End the child: wait up to ``timeout`` s for it to exit by itself (None: kill it
        now), kill what is left of its process group, and reap it. Returns its exit code
        (negative for a signal, as :class:`subprocess.Popen` has it) and the CPU seconds it
        and its descendants used, or ``(None, None)`` if it is still running."""
        proc = self.proc
        if proc is None or proc.returncode is not None:
            return (None, None) if proc is None else (proc.returncode, None)
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
        try:
            write_frame(self._req, {"fn": fn, "cases": [encode_args(a) for a in cases],
                                    "nonce": nonce})
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
        try:
            frame = read_frame(self._res, deadline)
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
                                                           self.limits))
        return Outcome(status, message=what)

    def output(self, limit: int = 2000) -> str:
        """The first ``limit`` characters the submission printed (stdout and stderr)."""
        try:
            with open(self.stdout, "rb") as f:
                return f.read(limit).decode("utf-8", "replace")
        except OSError:
            return ""


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
                   limits: Limits) -> str:
    """Why the interpreter stopped: the CPU time it used comes first, since the kernel ends a
    process over its CPU limit with SIGXCPU or SIGKILL and a wrapper may report either."""
    if cpu is not None and cpu >= 0.9 * cpu_limit:
        return (f"{what} ran out of CPU time: the interpreter used its {cpu_limit:g} s of CPU "
                "time for all cases (threads still running?)")
    if code is None:
        return f"the interpreter stopped responding while {what} ran"
    if code == -signal.SIGXCPU:
        return f"{what} ran out of CPU time ({cpu_limit:g} s for all cases)"
    if code == -signal.SIGKILL:
        return f"the interpreter was killed while {what} ran (out of memory? the limit is " \
               f"{limits.memory_mb} MB)"
    if code < 0:
        name = signal.Signals(-code).name if -code in signal.valid_signals() else -code
        return f"the interpreter crashed ({name}) while {what} ran"
    return (f"the interpreter exited (code {code}) while {what} ran; does your code call "
            "sys.exit(), exit() or os._exit()?")
