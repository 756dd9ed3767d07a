"""The sandbox itself: the audit hook's own robustness (POSIX and Windows paths), the private
file system of bubblewrap, the fallbacks down to the portable level (what Windows gets,
run here on request), per-case limits and what the reports say when a limit is hit."""

from __future__ import annotations

import dis
import json
import ntpath
import os
import select
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_autograder_fixtures import A1, REPO, submission

from autograder import Limits, check
from autograder.checks import Check, QuatCheck, StringsCheck, TupleCheck
from autograder.child import make_hook
from autograder.cli import main
from autograder.findings import describe_args
from autograder.judging import judge, prepare
from autograder.protocol import (
    ProtocolError,
    decode_value,
    encode_value,
    read_frame,
    write_frame,
)
from autograder.sandbox import (
    INSIDE,
    SANDBOX_UID,
    Isolation,
    Outcome,
    Replies,
    _bounded,
    _crash_message,
    isolation,
)
from autograder.spec import Case, Function

LIMITS = Limits(cpu_seconds=5, memory_mb=600, load_timeout=5.0, case_timeout=0.5)
BUBBLEWRAP = pytest.mark.skipif(isolation() != "bubblewrap",
                                reason="no bubblewrap sandbox on this machine")


def one_line(result) -> str:
    return " ".join(str(result).split())


# --- the audit hook ----------------------------------------------------------------------------


@pytest.fixture
def hook(tmp_path):
    work, stdlib = tmp_path / "work", tmp_path / "stdlib"
    (stdlib / "site-packages" / "scipy").mkdir(parents=True)
    (stdlib / "json").mkdir()
    work.mkdir()
    (work / "mine.py").write_text("")
    os.symlink(REPO / "course" / "rotations" / "quaternion.py", work / "link.py")
    return make_hook(str(work), (str(tmp_path / "numpy"), str(stdlib)),
                     (str(stdlib / "site-packages"),), frozenset({"numpy", "json"})), work


def refused(hook, event: str, *args) -> str:
    with pytest.raises((PermissionError, ImportError)) as info:
        hook(event, args)
    return str(info.value)


def helpers(f) -> dict[str, object]:
    """The hook's own functions among its defaults, and theirs, by name."""
    found = {}
    for d in f.__defaults__ or ():
        if getattr(d, "__qualname__", "").startswith("make_hook."):
            found[d.__name__] = d
            found.update(helpers(d))
    return found


@pytest.mark.parametrize("paths", ["posix", "nt"])
def test_the_hook_reads_no_global_and_has_no_cell_to_overwrite(paths, hook, nt_hook):
    """Rebinding a builtin, os.path or the child's globals cannot change what the hook does,
    and its frame (which a refusal's traceback shows) holds nothing mutable."""
    h = hook[0] if paths == "posix" else nt_hook
    found = helpers(h)
    assert set(found) == {"resolve", "locate", "within", "may_read"}
    for f in [h, *found.values()]:
        ops = {i.opname for i in dis.get_instructions(f)}
        assert not ops & {"LOAD_GLOBAL", "LOAD_NAME", "LOAD_DEREF", "LOAD_CLOSURE"}, f.__name__
        assert f.__closure__ is None
        assert all(isinstance(d, (str, int, tuple, frozenset, type)) or callable(d)
                   for d in f.__defaults__), f.__name__


def test_the_hook_checks_the_file_that_will_really_be_opened(hook, tmp_path):
    h, work = hook
    h("open", (str(work / "mine.py"), "r", 0))
    h("open", (str(work / "new.txt"), "w", os.O_WRONLY | os.O_CREAT))
    h("open", (str(tmp_path / "stdlib" / "json" / "x.py"), "r", 0))
    h("os.listdir", (str(tmp_path / "stdlib" / "json"),))
    h("import", ("json.decoder",))
    assert "open" in refused(h, "open", str(work / "link.py"), "r", 0)  # a link to the reference
    assert "open" in refused(h, "open", str(work / ".." / "stdlib" / "json" / "x.py"), "w", 1)
    assert "open" in refused(h, "open", str(tmp_path / "stdlib" / "site-packages" / "scipy"
                                            / "x.py"), "r", 0)
    h("open", (str(work), "w", os.O_TMPFILE | os.O_RDWR))  # tempfile.TemporaryFile does this
    # a descriptor of a readable folder would let dir_fd= paths reach beyond it
    assert "directory" in refused(h, "open", str(tmp_path / "stdlib"), None, os.O_RDONLY)

    class Shifty:
        def __fspath__(self):
            return str(work / "mine.py")

    class Lying(str):
        def startswith(self, *a):
            return True

    for path in (Shifty(), Lying(str(REPO / "README.md"))):
        assert "plain str or bytes" in refused(h, "open", path, "r", 0)
    assert "not allowed" in refused(h, "import", Lying("numpy"))
    assert "ctypes.string_at" in refused(h, "ctypes.string_at", 1, 8)
    assert "os.chdir" in refused(h, "os.chdir", str(work))
    assert "os.symlink" in refused(h, "os.symlink", "a", "b", -1)
    assert "replace code objects" in refused(h, "object.__setattr__", len, "__code__", None)
    assert "outside" in refused(h, "os.listdir", "/")


# A Windows machine as the nt functions show it: the real (long, exact-case) paths that exist,
# and the aliases Windows resolves (an 8.3 short name, a junction into the course).
NT_WORK = r"C:\Users\Ann\AppData\Local\Temp\autograder-x\work"
NT_STDLIB = r"C:\Python311\Lib"
NT_FILES = {NT_WORK, NT_WORK + r"\mine.py", NT_STDLIB, NT_STDLIB + r"\json\decoder.py",
            NT_STDLIB + r"\site-packages", NT_STDLIB + r"\site-packages\scipy\x.py",
            r"C:\course", r"C:\course\_checks.py"}
NT_ALIASES = {NT_STDLIB + r"\SITE-P~1": NT_STDLIB + r"\site-packages",
              NT_WORK + r"\j": r"C:\course"}


def _nt_full(path: str) -> str:
    """nt._getfullpathname: absolute (from the working directory), '.', '..' resolved."""
    path = path.replace("/", "\\")
    return ntpath.normpath(path if path[1:3] == ":\\" or path.startswith("\\")
                           else NT_WORK + "\\" + path)


def _nt_final(path: str) -> str:
    """nt._getfinalpathname: the real path of an existing file, in its own case."""
    for alias, real in NT_ALIASES.items():
        if path.lower().startswith(alias.lower()):
            path = real + path[len(alias):]
    for real in NT_FILES:
        if real.lower() == path.lower():
            return "\\\\?\\" + real
    raise FileNotFoundError(path)


@pytest.fixture
def nt_hook():
    return make_hook(NT_WORK, (NT_STDLIB,), (NT_STDLIB + r"\site-packages",),
                     frozenset({"numpy"}), nt_paths=(_nt_full, _nt_final))


def test_windows_paths_are_checked_where_windows_opens_them(nt_hook):
    """On Windows the kernel's own resolution decides: case and slashes do not matter, and
    a short name, a junction or a stream cannot lead anywhere the folders do not allow."""
    h = nt_hook
    h("open", ("mine.py", "r", 0))
    h("open", ("c:/users/ann/appdata/local/temp/autograder-x/WORK/new.txt", "w", 1))
    h("open", (NT_STDLIB.lower() + r"\json\decoder.py", "r", 0))
    for path, mode in [(NT_STDLIB + r"\SITE-PACKAGES\scipy\x.py", "r"),
                       (NT_STDLIB + r"\SITE-P~1\scipy\x.py", "r"),
                       (r"j\_checks.py", "r"),
                       (r"..\..\..\..\..\..\..\course\_checks.py", "r"),
                       (NT_STDLIB + r"\json\decoder.py", "w"),
                       (r"\\server\share\_checks.py", "r")]:
        assert "does not let submissions open" in refused(h, "open", path, mode, 0), path
    for path in ("mine.py:hidden", r"\\?\C:\course\_checks.py", r"\\.\C:\course"):
        assert "does not let submissions name" in refused(h, "open", path, "r", 0), path
    assert "outside" in refused(h, "os.mkdir", r"C:\Python311\x", 0o777, -1)
    assert "_winapi.CreateJunction" in refused(h, "_winapi.CreateJunction", "a", "b")
    assert "os.startfile" in refused(h, "os.startfile", "x.exe")


def test_ordinary_code_is_not_refused(tmp_path):
    """The standard library and numpy's corners work in the sandbox as they do anywhere."""
    result = check("a1", submission("legit_stdlib_heavy.py", tmp_path), limits=LIMITS)
    assert result.score == 12 and not result.problems, str(result)


# --- the private file system -------------------------------------------------------------------


@BUBBLEWRAP
def test_the_repository_and_everything_else_are_absent_from_the_sandbox(tmp_path):
    """Beyond the hook: in bubblewrap the checkout, numpy's real folder, /proc, the installed
    packages and every other interpreter do not exist, whatever the submission tries."""
    paths = [str(REPO), str(REPO / "course"), str(Path(np.__file__).parent), "/proc/self",
             str(tmp_path), f"{os.path.dirname(os.__file__)}/site-packages/scipy",
             "/usr/bin/python3", "/bin/sh", "/etc/passwd", "/tmp"]
    src = ("import os\n\n\ndef quat_mul(a, b):\n"
           f"    raise RuntimeError(str([os.path.exists(p) for p in {paths!r}]) + ' ' + "
           "os.getcwd() + ' ' + str(os.getuid()))\n")
    (tmp_path / "a1_rotations.py").write_text(src)
    result = check("a1", tmp_path / "a1_rotations.py", limits=LIMITS)
    assert result.isolation == "bubblewrap"
    assert f"RuntimeError: {[False] * len(paths)} {INSIDE}/work {SANDBOX_UID}" in one_line(result)


NOTES = {"plain": "No Linux namespaces here", "portable": "but memory and CPU time are not limited"}


@pytest.mark.parametrize("level", ["plain", "portable"])
def test_weaker_isolation_still_holds_and_says_so(level, tmp_path, capsys):
    """A weaker level holds what its audit hook holds and says so; ``grade`` refuses it
    unless the instructor lowers the floor to it by name, and then warns."""
    if Isolation(level).rank < isolation().rank:
        pytest.skip(f"no {level} isolation on this machine")
    result = check("a1", submission("adv_reads_reference.py", tmp_path), limits=LIMITS,
                   isolation=level)
    assert result.score == 0 and "does not let submissions open" in one_line(result)
    assert result.isolation == level and NOTES[level] in one_line(result)
    argv = ["grade", "--assignment", "a1", str(REPO / "tests/fixtures/a1/reference.py"),
            "--out", str(tmp_path / "out"), "--isolation", level]
    with pytest.raises(SystemExit):
        main(argv)
    err = capsys.readouterr().err
    assert f"refusing to grade at isolation {level}, below the floor chroot" in err
    assert f"--min-isolation {level}" in err and not (tmp_path / "out").exists()
    assert main([*argv, "--min-isolation", level]) == 0
    assert f"warning: isolation is weaker on this machine ({level})" in capsys.readouterr().err
    assert f",{level}," in (tmp_path / "out" / "grades.csv").read_text()


def test_an_isolation_this_machine_lacks_is_refused():
    with pytest.raises(ValueError, match="isolation: 'sealed' is not one of"):
        check("a1", REPO / "tests/fixtures/a1/reference.py", isolation="sealed")
    if isolation() != "bubblewrap":
        with pytest.raises(ValueError, match="not available on this machine"):
            check("a1", REPO / "tests/fixtures/a1/reference.py", isolation="bubblewrap")


# --- the portable level ------------------------------------------------------------------------


@pytest.mark.parametrize("key", ["a1", "a2", "a3"])
def test_the_references_get_full_marks_at_the_portable_level(key):
    result = check(key, REPO / f"tests/fixtures/{key}/reference.py", seed="portable-seed",
                   limits=Limits(case_timeout=2.0), isolation="portable")
    assert result.isolation == "portable" and not result.problems
    assert {t.status for t in result.tests} == {"passed"}, str(result)


def test_the_portable_child_loads_no_posix_only_module(tmp_path):
    """What Windows lacks is never imported by the child (numpy's own imports included)."""
    posix_only = ("resource", "fcntl", "select", "termios", "pwd", "grp", "_posixsubprocess")
    src = ("import sys\n\n\ndef quat_mul(a, b):\n"
           f"    raise RuntimeError(str([m for m in {posix_only!r} if m in sys.modules]))\n")
    (tmp_path / "a1_rotations.py").write_text(src)
    result = check("a1", tmp_path / "a1_rotations.py", limits=LIMITS, isolation="portable")
    assert "quat_mul raised RuntimeError: []" in one_line(result)


def test_without_posix_process_controls_the_portable_level_is_chosen_and_holds(
        tmp_path, monkeypatch):
    """As on Windows: no process groups, wait4, waitid or select on pipes. The portable level
    is chosen, and a timeout or a crash still costs only its own case."""
    import autograder.sandbox

    isolation()  # probed with everything there
    for name in ("killpg", "wait4", "waitid"):
        monkeypatch.delattr(os, name)

    def no_select(*args):
        raise AssertionError("select() on a pipe: Windows has none")

    monkeypatch.setattr(select, "select", no_select)
    assert autograder.sandbox.probe.__wrapped__().level == "portable"
    result = check("a1", submission("adv_infinite_loop.py", tmp_path), limits=LIMITS,
                   isolation="portable")
    mul = [t for t in result.tests if t.test.function == "quat_mul"]
    assert {c.kind for t in mul for c in t.cases} == {"timeout", "skipped"}
    assert result.score == 10  # every other function's tests ran, in fresh interpreters
    assert ("quat_mul did not finish within 0.5 s on this case (an endless loop, or too "
            "slow?)") in one_line(result)
    result = check("a1", submission("adv_exits.py", tmp_path), limits=LIMITS,
                   isolation="portable")
    assert result.score == 6 and ("the interpreter exited (code 0) while slerp ran; does your "
                                  "code call") in one_line(result)


def _frame(obj) -> bytes:
    r, w = os.pipe()
    write_frame(w, obj)
    os.close(w)
    data = os.read(r, 1 << 16)
    os.close(r)
    return data


def test_replies_wait_with_a_deadline_and_read_only_what_is_asked_for():
    """The reader thread behind every level's deadlines: a frame late by more than the
    deadline is a TimeoutError, it is still the next one returned, nothing is read ahead,
    and garbage and the end of the pipe are told apart."""
    r, w = os.pipe()
    replies = Replies(os.fdopen(r, "rb", buffering=0))
    late = threading.Timer(0.3, os.write, (w, _frame({"n": 1})))
    late.start()
    with pytest.raises(TimeoutError):
        replies.get(time.monotonic() + 0.05)
    assert replies.get(time.monotonic() + 5) == {"n": 1}
    os.write(w, _frame({"n": 2}) + _frame({"n": 3}))
    assert replies.get(time.monotonic() + 5) == {"n": 2}
    assert select.select([r], [], [], 0.1)[0]  # frame 3 is still in the pipe, unread
    assert replies.get(time.monotonic() + 5) == {"n": 3}
    os.write(w, b"\x00\x00\x00\x03abc")
    with pytest.raises(ProtocolError, match="not JSON"):
        replies.get(time.monotonic() + 5)
    os.close(w)
    replies.close()
    r2, w2 = os.pipe()
    ended = Replies(os.fdopen(r2, "rb", buffering=0))
    os.close(w2)
    assert ended.get(time.monotonic() + 5) is None
    ended.close()
    assert ended.stream.closed


def test_crash_messages_name_signals_and_windows_statuses():
    assert "crashed (0xC0000005)" in _crash_message(0xC0000005, None, "f", 9, None)
    assert "exited (code 3)" in _crash_message(3, None, "f", 9, None)
    assert "out of memory? there is no limit here" in _crash_message(-9, None, "f", 9, None)
    assert "out of memory? the limit is 600 MB" in _crash_message(-9, None, "f", 9, 600)


# --- limits per case ---------------------------------------------------------------------------


def test_a_slow_but_correct_function_gets_full_marks(tmp_path):
    """0.15 s of CPU per call, 20 calls: within every case's limit; the CPU backstop is
    sized for all cases together."""
    limits = Limits(memory_mb=600, load_timeout=5.0, case_timeout=0.5)
    result = check("a1", submission("slow_correct_euler.py", tmp_path), limits=limits)
    assert result.score == 12, str(result)


@pytest.mark.parametrize("level", ["default", "plain"])
def test_running_out_of_cpu_time_says_so(level, tmp_path, monkeypatch):
    import autograder.sandbox

    if level == "plain":
        monkeypatch.setattr(autograder.sandbox, "isolation", lambda: "plain")
    limits = Limits(cpu_seconds=1, memory_mb=600, load_timeout=5.0, case_timeout=5.0)
    result = check("a1", submission("slow_correct_euler.py", tmp_path), limits=limits)
    euler = [t for t in result.tests if t.test.function == "matrix_from_euler"]
    assert all(t.status == "partial" for t in euler)  # a fresh interpreter ran the rest
    # and the tests after it start with interpreters of their own: never charged for it
    assert result.score == pytest.approx(10 + sum(t.score for t in euler))
    text = one_line(result)
    assert ("matrix_from_euler ran out of CPU time: the interpreter used its 1 s of CPU time "
            "for all cases") in text
    assert "exited (code" not in text and not result.output  # no "Killed", no "sigprocmask"


def test_a_forged_frame_nested_too_deeply_is_refused(tmp_path):
    body = b"[" * 200000 + b"]" * 200000
    (tmp_path / "frame").write_bytes(len(body).to_bytes(4, "big") + body)
    fd = os.open(tmp_path / "frame", os.O_RDONLY)
    with pytest.raises(ProtocolError, match="nested too deeply"):
        read_frame(fd)
    os.close(fd)
    deep = {"kind": "none"}
    for _ in range(6):
        deep = {"kind": "seq", "items": [deep]}
    with pytest.raises(ProtocolError, match="nested too deeply"):
        decode_value(deep)


def test_the_child_counts_an_answer_too_large_to_send():
    """Beyond the case's bound an array is counted, not encoded (a million numbers would cost
    the case's time), alone or inside a tuple; the grader reads it as an object."""
    sent = encode_value((np.zeros(3), np.zeros(1 << 20)), most=80)
    assert sent["items"][1] == {"kind": "oversized", "numbers": 1 << 20}
    got = decode_value(sent)
    assert got.items[0].array.shape == (3,) and got.items[1].kind == "other"
    assert "1048576 numbers (too large)" in got.items[1].type_name
    assert encode_value(np.zeros(80), most=80)["kind"] == "array"


# --- messages ----------------------------------------------------------------------------------


def test_messages_print_plain_strings_and_enough_digits():
    fn = Function("matrix_from_euler", ("angles", "order"), lambda *a: None, None)
    assert describe_args(fn, Case("x", (np.zeros(3), np.str_("ZYX")))) == (
        "angles = [0, 0, 0], order = 'ZYX'")
    got, want = np.array([0.21429, 0.14286, 0.07143]), np.array([0.21414, 0.14286, 0.07143])
    assert Check(None).decimals(got, want) == 5 and Check(None).decimals(got, got) == 3
    assert Check(None).decimals(-want, want) == 3  # a sign flip shows at 3 decimals
    pair = TupleCheck((Check(None), Check(None)), ("a", "b"))
    assert pair.decimals((got, np.ones(2)), (want, np.ones(2))) == 5
    q = np.array([0.5, 0.5, 0.5, 0.5])
    assert QuatCheck().decimals(-q - 1e-6, q) == 7  # q ~ -q: the 1e-6 is what differs
    assert StringsCheck().decimals(("a",), ("b",)) == 3


def test_a_dls_step_slightly_off_shows_the_difference(tmp_path):
    src = ((REPO / "tests/fixtures/a3/reference.py").read_text()
           + "\n\ndef dls_step(J, error, damping):\n"
             "    m = J.shape[0]\n"
             "    return J.T @ np.linalg.solve(J @ J.T + (damping**2 + 1e-4) * np.eye(m), error)\n")
    (tmp_path / "a3.py").write_text(src)
    result = check("a3", tmp_path / "a3.py", limits=Limits(memory_mb=600, case_timeout=1.0))
    first = next(t for t in result.tests if t.test.function == "dls_step").first_failure
    returned, expected = first.reason.split("returned ")[1].split(", expected ")
    assert returned != expected.split(":")[0]  # the two printouts differ where the values do


def test_no_sandbox_folder_is_left_behind(tmp_path, monkeypatch):
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    check("a1", submission("adv_hook_tampering.py", tmp_path), limits=LIMITS)
    assert not list((tmp_path / "tmp").iterdir())


# --- forged frames, fuzzed ---------------------------------------------------------------------


def _read(data: bytes, tmp: Path):
    path = tmp / "frame"
    path.write_bytes(len(data).to_bytes(4, "big") + data)
    fd = os.open(path, os.O_RDONLY)
    try:
        return read_frame(fd)
    finally:
        os.close(fd)


def test_numbers_no_float_can_hold_are_forged_frames(tmp_path):
    """An integer of 5000 digits (Python refuses to parse one past 4300 with a ValueError)
    and one of 10**400 (an OverflowError as a float): both are refused as forged, not raised
    in the grader."""
    for digits in ("9" * 5000, str(10**400), "-" + "1" * 20):
        body = ('{"kind":"array","type":"ndarray","dtype":"float64","shape":[1],"data":['
                + digits + "]}").encode()
        with pytest.raises(ProtocolError, match="an integer of"):
            _read(body, tmp_path)
    with pytest.raises(ProtocolError):
        decode_value({"kind": "oversized", "numbers": float("inf")})
    with pytest.raises(ProtocolError):  # a shape that does not hold its data
        decode_value({"kind": "array", "shape": [10**18, 0], "data": [1.0], "dtype": "f"})
    assert _read(b'{"kind":"array","shape":[1],"data":[1e400],"dtype":"f"}', tmp_path)[
        "data"] == [float("inf")]


_JSON_ATOMS = st.one_of(
    st.none(), st.booleans(), st.integers(min_value=-10**500, max_value=10**500),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=30),
    st.sampled_from(["array", "seq", "str", "none", "other", "oversized"]))
_JSON = st.recursive(_JSON_ATOMS, lambda inner: st.one_of(
    st.lists(inner, max_size=6),
    st.dictionaries(st.sampled_from(["kind", "shape", "data", "items", "value", "type",
                                     "dtype", "numbers", "x"]), inner, max_size=6)),
    max_leaves=40)
_ARRAYS = st.fixed_dictionaries({
    "kind": st.just("array"), "type": st.just("ndarray"), "dtype": st.just("float64"),
    "shape": st.just([3, 3]),
    "data": st.lists(st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                               st.integers(min_value=-10**30, max_value=10**30)),
                     min_size=9, max_size=9)})


@settings(max_examples=300, derandomize=True, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(value=st.one_of(_JSON, _ARRAYS), garble=st.booleans())
def test_any_frame_costs_its_case_at_most_never_the_grader(tmp_path, value, garble):
    """Whatever bytes a child sends as an answer, the grader's decoding ends in a Value or
    a ProtocolError, and judging the Value ends in a verdict: nothing else is raised."""
    body = json.dumps({"value": value}).encode()
    if garble:
        body = body[: len(body) // 2]
    try:
        frame = _read(body, tmp_path)
        got = _bounded(frame["value"], 64)
    except ProtocolError:
        return
    test = next(p for p in prepare(A1, None) if p.test.function == "matrix_from_quat")
    fn = A1.function("matrix_from_quat")
    verdict = judge(fn, test.cases[0], test.expected[0], Outcome("ok", value=got), 600,
                    str, A1.misconceptions_of(fn.name))
    assert verdict.kind in ("pass", "wrong", "invalid") and verdict.reason is not None


REFUSAL = "bwrap: Creating new namespace failed: Resource temporarily unavailable"


@BUBBLEWRAP
@pytest.mark.parametrize("refusals", [2, 99])
def test_a_start_bubblewrap_refused_is_tried_again_and_then_named(refusals, monkeypatch):
    """bubblewrap that cannot build the box exits with code 1 and says why on stderr before
    the submission runs: the start is tried again, and if it never succeeds the report
    names bubblewrap's reason instead of blaming the student's code."""
    import autograder.runner
    import autograder.sandbox

    starts = []
    command = autograder.sandbox.Sandbox._command

    def refusing(self, config, program=None):
        cmd, fds = command(self, config, program)
        starts.append(cmd)
        if len(starts) > refusals:
            return cmd, fds
        return ["/bin/sh", "-c", f'echo "{REFUSAL}" >&2; exit 1', "sh", *cmd], fds

    monkeypatch.setattr(autograder.sandbox.Sandbox, "_command", refusing)
    monkeypatch.setattr(autograder.runner, "MACHINE_PAUSE", 0.0)
    result = check("a1", REPO / "tests/fixtures/a1/reference.py", limits=LIMITS)
    if refusals < autograder.sandbox.START_ATTEMPTS:
        assert result.score == result.max_score, str(result)
        assert not result.output  # bwrap's words are not shown as the student's
        return
    # every start of every attempt refused: not graded, with bwrap's own words, and no score
    assert len(starts) == autograder.sandbox.START_ATTEMPTS * autograder.runner.MACHINE_ATTEMPTS
    assert result.not_graded and not result.problems
    text = one_line(result)
    assert (f"Not graded: the sandbox could not start ({REFUSAL}) on each of 3 attempts. This "
            "is the grading machine's fault, not your code's") in text
    assert "Not graded: no score (of 12 points)" in text
    assert "exited (code" not in text and "Score:" not in text and "0/1" not in text
