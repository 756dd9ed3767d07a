"""Run a submission's functions in a separate, limited interpreter.

One :class:`Sandbox` per submission holds a temporary directory with a copy of the code and
at most one live child (:mod:`autograder.child`). The child is started as

    [unshare --user --map-root-user --net --pid --fork --kill-child]  python -I -S -B -u child.py

* ``unshare`` (Linux, when user namespaces are allowed): no network at all, and a PID
  namespace, so every process the submission forks dies with the child even if it
  escaped the process group; without it, the child's audit hook still refuses sockets
  and ``fork``, and the whole process group is killed;
* ``-I -S -B``: isolated mode, no site-packages (so no editable ``course``), no bytecode
  writes; the working directory is fresh and the environment minimal (no seed, no paths);
* CPU time, address space and file size limits, set by the child before loading the code,
  and a wall-clock deadline per case enforced here.

A case that hangs, crashes the interpreter or answers with garbage is *fatal*: the child is
killed and the next call starts a fresh one, so the other tests still run.
"""

from __future__ import annotations

import json
import os
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from .protocol import ProtocolError, Value, decode_value, encode_args, read_frame, write_frame

CHILD = Path(__file__).with_name("child.py")
UNSHARE = ["unshare", "--user", "--map-root-user", "--net", "--pid", "--fork", "--kill-child"]


@dataclass(frozen=True)
class Limits:
    """Resource limits for one submission's child interpreter."""

    cpu_seconds: int = 10
    memory_mb: int = 1024
    load_timeout: float = 10.0  # wall seconds to start and import the submission
    case_timeout: float = 2.0  # wall seconds per case


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


@cache
def isolation() -> str:
    """``"unshare"`` if network and PID namespaces are available here, else ``"plain"``."""
    if sys.platform != "linux" or not shutil.which("unshare"):
        return "plain"
    try:
        ok = subprocess.run([*UNSHARE, "true"], capture_output=True, timeout=5).returncode == 0
    except (OSError, subprocess.SubprocessError):
        ok = False
    return "unshare" if ok else "plain"


def _numpy_dirs() -> tuple[str, list[str]]:
    pkg = Path(np.__file__).resolve().parent
    dirs = [str(pkg)] + [str(p) for p in pkg.parent.glob("numpy.libs")]
    return str(pkg.parent), dirs


class Sandbox:
    """A submission's source in a private directory, and the child that runs it.

    Use as a context manager; :meth:`call` starts a child when none is running.
    """

    def __init__(self, source: str, functions: list[str], limits: Limits,
                 allowed_imports: frozenset[str]):
        self.limits = limits
        self.functions = functions
        self.allowed = sorted(allowed_imports)
        self.root = Path(tempfile.mkdtemp(prefix="autograder-"))
        self.work = self.root / "work"
        self.work.mkdir()
        (self.work / "submission.py").write_text(source, encoding="utf-8")
        self.proc: subprocess.Popen | None = None
        self.missing: list[str] = []
        self.load_error: dict[str, Any] | None = None
        self.stdout = self.root / "stdout.txt"

    def __enter__(self) -> Sandbox:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()
        shutil.rmtree(self.root, ignore_errors=True)

    # --- lifecycle ---------------------------------------------------------------------------

    def start(self) -> Outcome:
        """Start a child and wait until the submission is loaded (status ``ok`` if it is)."""
        req_r, self._req = os.pipe()
        self._res, res_w = os.pipe()
        numpy_path, numpy_dirs = _numpy_dirs()
        config = {
            "req_fd": req_r, "res_fd": res_w, "submission": str(self.work / "submission.py"),
            "functions": self.functions, "allowed": self.allowed, "numpy_path": numpy_path,
            "numpy_dirs": numpy_dirs, "cpu_seconds": self.limits.cpu_seconds,
            "memory_mb": self.limits.memory_mb,
        }
        cmd = [sys.executable, "-I", "-S", "-B", "-u", str(CHILD), json.dumps(config)]
        if isolation() == "unshare":
            cmd = UNSHARE + cmd
        env = {"PATH": "/usr/bin:/bin", "HOME": str(self.work), "TMPDIR": str(self.work),
               "LANG": "C.UTF-8", "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
               "MKL_NUM_THREADS": "1"}
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
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        self.proc.wait()
        for fd in (self._req, self._res):
            try:
                os.close(fd)
            except OSError:
                pass
        self.proc = None

    # --- calls -------------------------------------------------------------------------------

    def call(self, fn: str, cases: list[tuple[Any, ...]]) -> list[Outcome]:
        """Evaluate ``fn`` on each argument tuple; after a fatal case the rest are skipped."""
        if self.proc is None:
            started = self.start()
            if started.status != "ok":
                return [started] + [Outcome("skipped")] * (len(cases) - 1)
        nonce = secrets.token_hex(16)
        try:
            write_frame(self._req, {"fn": fn, "cases": [encode_args(a) for a in cases],
                                    "nonce": nonce})
        except OSError:
            return [self._fatal("crash", fn)] + [
                Outcome("skipped")] * (len(cases) - 1)
        outcomes: list[Outcome] = []
        for i in range(len(cases)):
            got = self._receive(time.monotonic() + self.limits.case_timeout, fn)
            if got.status != "ok":
                outcomes.append(got)
                break
            frame = got.value
            if not isinstance(frame, dict) or frame.get("nonce") != nonce or frame.get("case") != i:
                outcomes.append(self._fatal("garbage", _forged(fn)))
                break
            try:
                outcomes.append(
                    Outcome("ok", value=decode_value(frame["value"])) if frame.get("ok") is True
                    else Outcome("error", error=_error(frame["error"])))
            except (ProtocolError, KeyError, TypeError) as exc:
                outcomes.append(self._fatal("garbage", _forged(fn) + f" ({exc})"))
                break
        else:
            done = self._receive(time.monotonic() + self.limits.case_timeout, fn)
            if done.status != "ok" or done.value != {"done": True, "nonce": nonce}:
                bad = done if done.status != "ok" else self._fatal("garbage", _forged(fn))
                return [bad] * len(cases)
        return outcomes + [Outcome("skipped")] * (len(cases) - len(outcomes))

    def _receive(self, deadline: float, what: str) -> Outcome:
        """The next frame as ``Outcome("ok", value=frame)``, or a fatal outcome; ``what`` is
        running (a function's name, or "your file" while loading) for the messages."""
        try:
            frame = read_frame(self._res, deadline)
        except TimeoutError:
            budget = (self.limits.load_timeout if what == "your file" else
                                    self.limits.case_timeout)
            return self._fatal("timeout", f"{what} did not finish within {budget:g} s "
                                          "(an endless loop?)")
        except ProtocolError as exc:
            return self._fatal("garbage", _forged(what) + f" ({exc})")
        if frame is None:
            return self._fatal("crash", what)
        return Outcome("ok", value=frame)  # type: ignore[arg-type]

    def _fatal(self, status: str, what: str) -> Outcome:
        proc = self.proc
        code = None
        if proc is not None and status == "crash":
            try:
                code = proc.wait(timeout=1.0)
            except subprocess.TimeoutExpired:
                pass
        self.stop()
        if status == "crash":
            return Outcome("crash", message=_crash_message(code, what, self.limits))
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
    return (f"while {what} ran, something else wrote to the grader's private result channel; "
            "this test scores 0")


def _crash_message(code: int | None, what: str, limits: Limits) -> str:
    if code is None:
        return f"the interpreter stopped responding while {what} ran"
    if code == -signal.SIGXCPU:
        return f"{what} used more than the {limits.cpu_seconds} s of CPU time allowed"
    if code == -signal.SIGKILL:
        return f"the interpreter was killed while {what} ran (out of memory? the limit is " \
               f"{limits.memory_mb} MB)"
    if code < 0:
        name = signal.Signals(-code).name if -code in signal.valid_signals() else -code
        return f"the interpreter crashed ({name}) while {what} ran"
    return (f"the interpreter exited (code {code}) while {what} ran; does your code call "
            "sys.exit(), exit() or os._exit()?")
