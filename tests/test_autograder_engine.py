"""The autograder's parts: wire protocol, checks, notebook extraction, seeds, reports, CLI."""

from __future__ import annotations

import csv
import json
import os
from pathlib import Path

import numpy as np
import pytest

from autograder import Limits, check
from autograder.assignments import load
from autograder.checks import MatrixCheck, QuatCheck, TupleCheck
from autograder.cli import main
from autograder.findings import Findings
from autograder.gradescope_json import results_json
from autograder.protocol import (
    ProtocolError,
    Value,
    decode_value,
    encode_value,
    read_frame,
    write_frame,
)
from autograder.spec import case_rng
from autograder.submission import import_problems, source_from_notebook

FIXTURES = Path(__file__).parent / "fixtures" / "a1"
LIMITS = Limits(cpu_seconds=5, memory_mb=600, case_timeout=0.5)
A1 = load("a1")


def test_frames_round_trip_and_garbage_is_refused():
    r, w = os.pipe()
    write_frame(w, {"a": [1.5, float("nan")]})
    os.write(w, b"\x00\x00\x00\x03abc")
    os.close(w)
    first = read_frame(r)
    assert first["a"][0] == 1.5 and np.isnan(first["a"][1])
    with pytest.raises(ProtocolError, match="not JSON"):
        read_frame(r)
    assert read_frame(r) is None
    os.close(r)


def test_returned_values_are_described_as_plain_data():
    v = decode_value(json.loads(json.dumps(encode_value(np.arange(4, dtype=np.int32)))))
    assert v.kind == "array" and v.dtype == "int32" and v.array.dtype == np.float64
    assert decode_value(encode_value([1.0, 2.0])).type_name == "list"
    assert decode_value(encode_value((np.zeros(3), np.zeros(4)))).kind == "seq"
    assert decode_value(encode_value(object())).kind == "other"
    assert decode_value(encode_value(np.zeros(2, dtype=complex))).kind == "other"
    for bad in ({"kind": "array", "shape": [2], "data": [1.0], "dtype": "f"},
                {"kind": "array", "shape": [1], "data": ["x"], "dtype": "f"},
                {"kind": "zip"}, [], {"kind": "seq", "items": 3}):
        with pytest.raises(ProtocolError):
            decode_value(bad)


def _arr(x) -> Value:
    return decode_value(encode_value(np.asarray(x, dtype=float)))


def test_quaternions_compare_up_to_sign_and_must_be_unit():
    c, q = QuatCheck(), np.array([0.5, 0.5, 0.5, 0.5])
    assert c.compare(-q, q) is None
    assert "not a unit quaternion (|q| = 2)" in c.compare(2 * q, q)
    assert "different rotation" in c.compare(np.array([1.0, 0, 0, 0]), q)
    assert c.validate("f", _arr(np.zeros(3))).error == "f returned shape (3,), expected (4,)"
    assert "returned None" in c.validate("f", decode_value(encode_value(None))).error
    nan = c.validate("f", _arr([np.nan, 0, 0, 1]))
    assert nan.array is not None and "NaN or infinity" in nan.error
    assert c.close(np.array([np.nan, 1, 0, 0]), np.array([np.nan, -1, 0, 0]))


def test_tuple_check_validates_each_item():
    c = TupleCheck((MatrixCheck(), QuatCheck()), ("matrix", "quaternion"))
    good = decode_value(encode_value((np.eye(3), np.array([1.0, 0, 0, 0]))))
    v = c.validate("fk", good)
    assert v.error is None and c.compare(v.array, (np.eye(3), -np.array([1.0, 0, 0, 0]))) is None
    bad = decode_value(encode_value((np.eye(3), np.zeros(3))))
    assert c.validate("fk", bad).error == "fk's quaternion returned shape (3,), expected (4,)"
    assert "expected a tuple (matrix, quaternion)" in c.validate("fk", _arr(np.eye(3))).error


def test_notebook_keeps_definitions_and_drops_display_code():
    cells = [
        {"cell_type": "markdown", "source": "# a1"},
        {"cell_type": "code", "source": ["%matplotlib inline\n", "import numpy as np\n",
                                         "import matplotlib.pyplot as plt\n", "EPS = 1e-9\n",
                                         "!pip install scipy\n"]},
        {"cell_type": "code", "source": "def quat_mul(a, b):\n    return a\n\nquat_mul(1, 2)\n"
                                        "fig = plt.figure()\n"},
        {"cell_type": "code", "source": "from autograder import check\ncheck('a1')"},
        {"cell_type": "code", "source": "%%timeit\nthis is not python"},
    ]
    src = source_from_notebook(json.dumps({"cells": cells})).text
    assert "import numpy as np" in src and "EPS = 1e-9" in src and "def quat_mul" in src
    for gone in ("matplotlib", "pip", "check(", "plt.figure", "quat_mul(1, 2)", "timeit"):
        assert gone not in src
    compile(src, "nb", "exec")


def test_static_check_names_the_line_and_the_reason():
    problems = import_problems("import numpy\nimport math\nfrom scipy.spatial import transform"
                               "\nimport subprocess\n", frozenset({"numpy"}), "s.py")
    assert problems == [
        "line 3: `from scipy.spatial import ...` is not allowed: the assignment asks you to "
        "implement the math yourself with numpy",
        "line 4: `import subprocess` is not allowed: the grader runs no native code, other "
        "programs or other interpreters: use numpy and the Python standard library only",
    ]
    assert import_problems("def f(:\n", frozenset(), "s.py")[0].startswith("line 1:")


def test_hidden_cases_depend_on_the_secret_seed_only():
    hidden = next(t for t in A1.tests if t.hidden)
    visible = next(t for t in A1.tests if not t.hidden)
    first = [c.args[0] for c in hidden.cases(case_rng(hidden, "s1"))]
    again = [c.args[0] for c in hidden.cases(case_rng(hidden, "s1"))]
    other = [c.args[0] for c in hidden.cases(case_rng(hidden, "s2"))]
    assert np.array_equal(first, again) and not np.array_equal(first, other)
    assert np.array_equal(visible.cases(case_rng(visible, "s1"))[0].args[0],
                          visible.cases(case_rng(visible, None))[0].args[0])
    with pytest.raises(ValueError, match="secret seed"):
        case_rng(hidden, None)


def test_every_misconception_is_distinguishable_from_the_reference():
    for m in A1.misconceptions:
        fn = A1.function(m.function)
        tests = [t for t in A1.tests if t.function == m.function and not t.hidden]
        cases = [c for t in tests for c in t.cases(case_rng(t, None))]
        with np.errstate(all="ignore"):
            differs = [not fn.check.close(np.asarray(m.wrong(*c.args), dtype=float),
                                          fn.reference(*c.args)) for c in cases]
        assert any(differs), m.key


def test_gradescope_json_hides_hidden_tests_until_published(tmp_path):
    src = (FIXTURES / "reference.py").read_text() + (FIXTURES / "mutant_mul_reversed.py"
                                                     ).read_text()
    (tmp_path / "s.py").write_text(src)
    result = check("a1", tmp_path / "s.py", seed="k", limits=LIMITS)
    data = results_json(Findings.of(result), "Graded s.py.")
    assert data["stdout_visibility"] == "hidden" and data["execution_time"] >= 0
    assert {t["visibility"] for t in data["tests"] if "hidden" in t["name"]} == {"after_published"}
    mul = [t for t in data["tests"] if t["name"].startswith("quat_mul")]
    assert all("the product in the wrong order" in t["output"] for t in mul)
    assert data["score"] == pytest.approx(sum(t["score"] for t in data["tests"]))


def test_html_report_pictures_the_first_failing_rotation(tmp_path):
    src = (FIXTURES / "reference.py").read_text() + (FIXTURES / "mutant_euler_extrinsic.py"
                                                     ).read_text()
    (tmp_path / "s.py").write_text(src)
    page = check("a1", tmp_path / "s.py", limits=LIMITS)._repr_html_()
    assert "data:image/png;base64," in page and "extrinsic instead of intrinsic" in page


class InProcess:
    """An executor of the judging core's loop that calls a module's functions here, their
    answers through the wire's encoding (as a notebook's check does, in the student's
    kernel)."""

    memory_mb = None

    def __init__(self, namespace):
        self.namespace, self.missing, self.deadline = namespace, [], float("inf")

    def call(self, fn, cases, sizes=None):
        from autograder.judging import Outcome

        return [Outcome("ok", value=decode_value(encode_value(self.namespace[fn](*a))))
                for a in cases]


@pytest.mark.parametrize("mutant", ["mutant_mul_reversed.py", "mutant_axis_xyzw.py"])
def test_one_loop_judges_alike_in_the_sandbox_and_in_process(mutant, tmp_path):
    """The case loop is the judging core's (judging.run_test), whatever calls the functions:
    in process it finds what the sandboxed grader finds, and the record says it alike."""
    from autograder.findings import TestFindings
    from autograder.judging import prepare, run_test
    from autograder.results import TestResult

    src = (FIXTURES / "reference.py").read_text() + "\n\n" + (FIXTURES / mutant).read_text()
    (tmp_path / "s.py").write_text(src)
    graded = Findings.of(check("a1", tmp_path / "s.py", seed="k", limits=LIMITS))
    namespace: dict = {}
    exec(compile(src, "s.py", "exec"), namespace)
    here = []
    for p in prepare(A1, "k"):
        tr = TestResult(p.test, A1.function(p.test.function))
        run_test(A1, p, tr, InProcess(namespace), lambda line: f"line {line}")
        here.append(TestFindings.of(tr))
    assert [(t.name, t.status, t.passed, t.mistake, t.lines) for t in here] == [
        (t.name, t.status, t.passed, t.mistake, t.lines) for t in graded.tests]
    assert any(t.mistake for t in here)


def test_the_record_is_built_once_and_frozen(tmp_path):
    import dataclasses

    src = (FIXTURES / "reference.py").read_text() + (FIXTURES / "mutant_mul_reversed.py"
                                                     ).read_text()
    (tmp_path / "s.py").write_text(src)
    report = check("a1", tmp_path / "s.py", limits=LIMITS)
    found = report.findings
    assert found is report.findings  # built on first use, then kept
    with pytest.raises(dataclasses.FrozenInstanceError):
        found.score = 24
    mul = next(t for t in found.tests if t.name.startswith("quat_mul"))
    assert mul.mistake.key == "reversed" and mul.first is mul.failures[0]
    assert mul.call.startswith("quat_mul(a = ") and mul.lines[-2] == f"  {mul.call}"
    assert str(report).startswith("\n".join(found.header))


def test_grade_a_class_in_parallel(tmp_path, capsys):
    subs = tmp_path / "subs"
    subs.mkdir()
    ref = (FIXTURES / "reference.py").read_text()
    (subs / "alice.py").write_text(ref)
    nb = {"cells": [{"cell_type": "code", "source": ref + "\ncheck('a1')\n"}]}
    (subs / "bob.ipynb").write_text(json.dumps(nb))
    (subs / "carol.py").write_text("def quat_mul(a, b):\n  return (\n")  # a syntax error
    (subs / "dave").mkdir()
    (subs / "dave" / "a1_rotations.py").write_text(ref + (FIXTURES / "adv_exits.py").read_text())
    out = tmp_path / "out"
    assert main(["grade", "--assignment", "a1", str(subs), "--out", str(out), "--jobs", "2",
                 "--seed", "class-secret"]) == 0
    rows = {r["submission"]: r for r in csv.DictReader(open(out / "grades.csv"))}
    assert {k: float(r["score"]) for k, r in rows.items()} == {
        "alice": 24, "bob": 24, "carol": 0, "dave": 12}
    assert rows["carol"]["status"] == "refused"
    results = json.loads((out / "dave" / "results.json").read_text())
    assert results["score"] == 12 and len(results["tests"]) == 18
    assert "graded 4 submissions" in capsys.readouterr().err


def test_check_command_prints_the_report(capsys):
    assert main(["check", "a1", "--submission", str(FIXTURES / "reference.py")]) == 0
    assert "Score: 12 / 12 (visible tests)" in capsys.readouterr().out


def test_a_mistake_is_recognised_one_way_only():
    from autograder.spec import Misconception

    with pytest.raises(ValueError, match="exactly one of wrong, symptom, caused_by"):
        Misconception("k", "f", "t", "e", symptom=lambda *a: True, caused_by="g")
    with pytest.raises(ValueError, match="exactly one"):
        Misconception("k", "f", "t", "e")



def test_a_mistake_undefined_on_a_case_is_named_by_the_others_only():
    """Where a mistake has no definite answer (``undefined``) a failing case neither shows nor
    refutes it; it is named when the other failing cases show it, never on those alone."""
    from dataclasses import replace

    from autograder.judging import diagnose
    from autograder.results import CaseResult
    from autograder.spec import Case, Misconception

    chaos, plain = Case("chaos", (0.0,)), Case("plain", (1.0,))
    flip = Misconception("flip", "f", "t", "e", symptom=lambda got, a: got == -a - 1,
                         undefined=lambda a: a == 0.0)
    fn = A1.functions[0]
    one = replace(A1, misconceptions=(flip,), shared=(),
                  functions=(replace(fn, name="f"),))

    def failing(case: Case, got: float) -> CaseResult:
        return CaseResult(case, "wrong", "differs", got, 0.0)

    assert diagnose(one, one.functions[0], [failing(chaos, 7.0), failing(plain, -2.0)]) is flip
    assert diagnose(one, one.functions[0], [failing(chaos, 7.0)]) is None
    assert diagnose(one, one.functions[0], [failing(chaos, 7.0), failing(plain, 5.0)]) is None

FORK_WHILE_INVERTING = """
import os, subprocess, sys, time, types
import numpy as np
import autograder.grading as grading

def grade_one(assignment, s, seed, limits, level):
    end = time.monotonic() + 2.0
    while time.monotonic() < end:
        if s.name == "starts sandboxes":  # Popen's user switch rules out vfork: fork()
            subprocess.run(["true"], user=os.getuid(), check=True)
        else:  # a diagnosis: a5's Newton iterates invert the Hessian
            np.linalg.inv(np.eye(150) * 3.0 + np.ones((150, 150)))
    return s.name

grading._grade_one = grade_one
grading.record = lambda name, result, digest: result
todo = [(types.SimpleNamespace(name=n), None) for n in ("starts sandboxes", "diagnoses")]
print(sorted(name for name, _ in grading._on_pool(None, todo, 2, None, None, "plain")))
"""


@pytest.mark.skipif(os.name != "posix", reason="fork() is POSIX")
def test_grading_threads_may_fork_while_another_computes():
    """Two grading threads: one starts processes with fork() (as the sandbox does as root, to
    switch user), the other inverts matrices (as a5's diagnosis does). Before, OpenBLAS's
    fork handler stopped its thread pool under the running ``inv``, which never returned:
    ``grade --jobs 2`` of the a5 fixtures hung (an hour at 100 % CPU); the grading pool now
    runs BLAS on one thread. Run in a process of its own, so a hang fails within a minute."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", FORK_WHILE_INVERTING], capture_output=True,
                          text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split("\n")[0] == "['diagnoses', 'starts sandboxes']"
