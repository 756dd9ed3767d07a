"""Check a notebook exercise with the autograder's judging core, in the student's own kernel.

An exercise (:class:`~course.exercises.spec.Exercise`) is an autograder
:class:`~autograder.spec.Function` (its parameters, reference and
:class:`~autograder.checks.Check`), a generator of visible cases, its own known mistakes and
two hints. A notebook's exercises form one :class:`~autograder.spec.Assignment`, so the
expected answers come from :func:`autograder.judging.prepare`, and the exercise is run by the
grader's own loop over a test's cases, :func:`autograder.judging.run_test`, with the
student's kernel as its executor (:class:`_Kernel`) where the grader has its sandbox: each
call judged and a failing exercise diagnosed against its own mistakes and the shared
catalogue (:mod:`autograder.catalogue`) exactly as the grader would. The feedback is
rendered from the test's :class:`~autograder.findings.TestFindings`, the record the grader's
reports render too. No sandbox, no process: the code is the student's, run by the student,
and none of the autograder's grading run (sandbox, runner, batch) is loaded.
"""

from __future__ import annotations

import ast
import copy
import ctypes
import html
import inspect
import io
import math
import textwrap
import threading
from collections.abc import Callable, Collection
from contextlib import redirect_stdout
from dataclasses import dataclass, replace
from functools import cache
from typing import TYPE_CHECKING, Any

import numpy as np

from .hints import hint
from .registry import exercise, exercises

if TYPE_CHECKING:  # the autograder's judging core loads on the first check, not with the notebook
    from autograder.findings import TestFindings
    from autograder.judging import Outcome
    from autograder.spec import Assignment

_NOT_YET = "… {key}: not yet — write the body, then run this again"
_PRINTED_CHARS = 4000  # of what the student's function prints, shown below the check


@dataclass(frozen=True)
class Feedback:
    """What :func:`check` found: ``status`` is ``"pass"``, ``"fail"`` or ``"not_yet"``;
    ``text`` says it (shown as the cell's output, with a hint button unless it passed)."""

    key: str
    status: str
    text: str

    @property
    def passed(self) -> bool:
        return self.status == "pass"

    def __repr__(self) -> str:
        return self.text

    def _repr_html_(self) -> str:
        color = {"pass": "#1a7f45", "fail": "#b42318"}.get(self.status, "#555")
        return (f"<pre style='white-space:pre-wrap;color:{color};margin:0'>"
                f"{html.escape(self.text)}</pre>")

    def _ipython_display_(self) -> None:
        from IPython.display import display

        display({"text/plain": self.text, "text/html": self._repr_html_()}, raw=True)
        if not self.passed:
            display(hint(self.key))


@cache
def _assignment(notebook: str) -> Assignment:
    """A notebook's exercises as an assignment: one visible test per exercise."""
    from autograder.catalogue import shared_misconceptions
    from autograder.spec import Assignment, Test

    found = exercises(notebook)
    own = Assignment(
        key=f"notebook {notebook}", title=f"notebook {notebook}'s exercises", template="",
        functions=tuple(e.function for e in found),
        tests=tuple(Test(e.key, e.function.name, 1.0, e.cases) for e in found),
        misconceptions=tuple(m for e in found for m in e.mistakes))
    return replace(own, shared=tuple(m for e in found
                                     for m in shared_misconceptions(e.function)))


def check(key: str, student: Callable[..., Any]) -> Feedback:
    """Run the student's function on exercise ``key``'s visible cases and say how it did.

    Parameters
    ----------
    key : str
        ``"<notebook>.<name>"``, e.g. ``"02.fk_step"``.
    student : callable
        The function written in the exercise cell.

    Returns
    -------
    Feedback
        ``pass``; ``fail`` with the first failing case (its inputs, what came back and what
        was expected) and the known mistake that explains every failure, if any; or
        ``not_yet`` while the body is still ``...`` or raises ``NotImplementedError``.

    Each call may take as long as the grader allows a case (2 s); one that takes longer is
    stopped and reported, and the cases after it are not run. What the function prints is
    shown below the check, its first few thousand characters.

    Raises
    ------
    TypeError, UnknownExercise
        If ``key`` is not a string, or names no exercise (the message lists them).
    """
    from autograder.findings import TestFindings
    from autograder.judging import prepare, run_test
    from autograder.results import TestResult

    ex = exercise(key)
    if not callable(student):
        return Feedback(key, "fail", f"✗ {key}: pass the function itself "
                                     f"(got {type(student).__name__})")
    if _unwritten(student):
        return Feedback(key, "not_yet", _NOT_YET.format(key=key))
    notebook = key.partition(".")[0]
    assignment = _assignment(notebook)
    prepared = next(p for p in prepare(assignment, None) if p.test.name == ex.key)
    # the messages name the function as the student did
    tried = TestResult(prepared.test, replace(ex.function, name=getattr(
        student, "__name__", ex.function.name)))
    others = {f.name for f in assignment.functions} - {ex.function.name}
    run_test(assignment, prepared, tried, _Kernel({ex.function.name: student}, others),
             _nowhere)
    return _feedback(key, TestFindings.of(tried))


def _feedback(key: str, t: TestFindings) -> Feedback:
    """What the exercise's test found, as the cell says it."""
    if t.status == "not_implemented":
        return Feedback(key, "not_yet", _NOT_YET.format(key=key))
    first = next((f for f in t.failures if f.kind == "timeout"), t.first)  # the urgent one
    if first is None:
        return Feedback(key, "pass", f"✓ {key}: all {t.cases} cases pass")
    from autograder.checks import show

    inputs = "\n".join(f"    {name} = {show(a) if not isinstance(a, str) else repr(a)}"
                       for name, a in zip(t.spec.params, first.case.args, strict=True))
    lines = [f"✗ {key}: {t.passed} of {t.cases} cases pass",
             f"  first failing case: {first.case.label}", inputs, f"  {first.reason}"]
    if t.mistake is not None:
        lines += [f"  This looks like {t.mistake.title}:",
                  textwrap.fill(t.mistake.explanation, 92, initial_indent="    ",
                                subsequent_indent="    ")]
    return Feedback(key, "fail", "\n".join(lines))


class _Kernel:
    """The student's own kernel as the executor of the judging core's loop
    (:class:`autograder.judging.Executor`), where the grader has its sandbox: ``functions``
    by the assignment's names, called here, in this thread (:func:`_calls`); ``missing``,
    the notebook's other functions (a check is given one). Each call has the grader's time
    for a case and no memory limit; a rollout's ``deadline`` is kept, not enforced here (its
    steps are paced between calls)."""

    memory_mb: int | None = None

    def __init__(self, functions: dict[str, Callable[..., Any]], missing: Collection[str]):
        self.functions = functions
        self.missing = missing
        self.deadline = math.inf

    def call(self, fn: str, cases: list[tuple[Any, ...]],
             sizes: list[int] | None = None) -> list[Outcome]:
        return _calls(self.functions[fn], cases)


def _nowhere(line: int) -> str:
    """Where an error happened, for :func:`~autograder.judging.judge`: the cell's line."""
    return f"line {line}"


def _where(exc: BaseException, student: Callable[..., Any]) -> dict[str, Any] | None:
    """The last line of the student's own code that the error passed through, if any."""
    import traceback

    code = getattr(student, "__code__", None)
    frames = [f for f in traceback.extract_tb(exc.__traceback__)
              if code is not None and f.filename == code.co_filename]
    return {"line": frames[-1].lineno, "code": frames[-1].line or ""} if frames else None


def _calls(student: Callable[..., Any], cases: list[tuple[Any, ...]]) -> list[Outcome]:
    """The student's function on each argument tuple, as :func:`_call` outcomes, with what
    it prints captured and shown afterwards, cut to :data:`_PRINTED_CHARS` (a print in a
    loop can write megabytes, more than a notebook cell can show). After a case that runs
    out of time the rest are skipped: each could take as long again."""
    from autograder.judging import Outcome
    from autograder.limits import Limits

    limit = Limits().case_timeout  # the grader's limit: what is too slow here is too slow there
    printed = _Printed(_PRINTED_CHARS)
    outcomes: list[Outcome] = []
    with redirect_stdout(printed):
        for args in cases:
            outcomes.append(_call(student, args, limit))
            if outcomes[-1].status == "timeout":
                break
    printed.show()
    skipped = Outcome("skipped", message="not run: an earlier case ran out of time")
    return outcomes + [skipped] * (len(cases) - len(outcomes))


def _call(student: Callable[..., Any], args: tuple[Any, ...], limit: float) -> Outcome:
    """The call as the grader's :class:`~autograder.judging.Outcome`: the returned value
    through the sandbox's own encoding (so it is validated the same way), the error, or a
    ``timeout`` if it took longer than ``limit`` seconds."""
    from autograder.judging import Outcome
    from autograder.protocol import decode_value, encode_value

    args = copy.deepcopy(args)  # a function that edits its input in place
    timer = _TimeLimit(limit)
    error = None
    try:
        with np.errstate(all="ignore"), timer:  # the timer innermost: disarmed first
            out = student(*args)
    except _OutOfTime:
        pass  # timer.fired says so
    except Exception as exc:  # the student's code: any error is feedback, not a crash
        error = {"type": type(exc).__name__, "message": _message(exc),
                 "where": _where(exc, student)}
    if timer.fired:  # even if the student's code caught _OutOfTime and went on
        name = getattr(student, "__name__", "your function")
        return Outcome("timeout", message=(
            f"{name} took longer than {limit:g} s on this case and was stopped: an endless "
            "loop, or far more work than the exercise needs? (the grader allows the same time)"))
    if error is not None:
        return Outcome("error", error=error)
    return Outcome("ok", value=decode_value(encode_value(out)))


def _message(exc: BaseException) -> str:
    """The start of ``str(exc)``, or nothing if the student's exception cannot say it (its
    type is reported anyway)."""
    try:
        return str(exc)[:300]
    except Exception:  # a broken __str__ of the student's own exception class
        return ""


class _OutOfTime(BaseException):
    """Raised inside a student's call that ran out of time. A BaseException, so that the
    student's own ``except Exception:`` does not swallow it."""


class _TimeLimit:
    """``with _TimeLimit(seconds):`` raises :class:`_OutOfTime` in this thread if the block
    runs longer than ``seconds``; ``fired`` says whether it did.

    Why this way: the student's code must run in the kernel's main thread (where a Jupyter
    "interrupt" lands, and where plotting and widgets expect it), on Linux, macOS and Windows
    alike: so no SIGALRM and no killable process. A timer thread asks CPython to raise an
    exception in this thread (``PyThreadState_SetAsyncExc``), which happens at its next
    bytecode: a Python loop stops at once, a long call into C (``time.sleep``, a huge matrix
    product) only when it returns, and a C call that never returns cannot be stopped this
    way (interrupt or restart the kernel). The timer fires once, under a lock, only while
    armed; leaving the block disarms it and clears an exception posted but not yet raised,
    so none can surface later. That exception may still arrive while the block is being left:
    catch it around the whole ``with``.
    """

    def __init__(self, seconds: float) -> None:
        self.fired = False
        self._armed = True
        self._lock = threading.Lock()
        self._target = threading.get_ident()
        self._watchdog = threading.Timer(seconds, self._fire)
        self._watchdog.daemon = True

    def __enter__(self) -> _TimeLimit:
        self._watchdog.start()
        return self

    def __exit__(self, *exc: object) -> None:
        with self._lock:
            self._armed = False
            if self.fired:
                _post(self._target, None)
        self._watchdog.cancel()

    def _fire(self) -> None:
        with self._lock:
            if self._armed:
                self.fired = True
                _post(self._target, _OutOfTime)


def _post(thread: int, exc: type[BaseException] | None) -> None:
    """Have CPython raise ``exc`` in ``thread`` at its next bytecode (None: clear a pending
    one)."""
    ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(thread),
                                               None if exc is None else ctypes.py_object(exc))


class _Printed(io.TextIOBase):
    """Text written to it, up to ``keep`` characters; beyond that only counted."""

    def __init__(self, keep: int) -> None:
        super().__init__()
        self.kept: list[str] = []
        self.room, self.dropped = keep, 0

    def writable(self) -> bool:
        return True

    def write(self, text: str) -> int:
        shown = text[:self.room]
        if shown:
            self.kept.append(shown)
        self.room -= len(shown)
        self.dropped += len(text) - len(shown)
        return len(text)

    def show(self) -> None:
        """Print what was kept, and how much was not."""
        print("".join(self.kept), end="")
        if self.dropped:
            print(f"\n… and {self.dropped:,} more characters printed by your function, "
                  "not shown")


def _unwritten(fn: Callable[..., Any]) -> bool:
    """Whether ``fn``'s body is still only ``...`` / ``pass`` (and a docstring): "not yet".

    Without its source (a built-in, a lambda typed at a console) it counts as written.
    """
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(fn)))
    except (OSError, TypeError, SyntaxError):
        return False
    node = tree.body[0] if tree.body else None
    if not isinstance(node, ast.FunctionDef):
        return False
    return all(isinstance(s, ast.Pass) or (isinstance(s, ast.Expr)
                                           and isinstance(s.value, ast.Constant)
                                           and (s.value.value is Ellipsis
                                                or isinstance(s.value.value, str)))
               for s in node.body)
