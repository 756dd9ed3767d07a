"""Notebook submissions: what the grader keeps of a notebook, what it says it dropped, and
where (cell and line) a refusal or an error points."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from autograder import Limits, check
from autograder.submission import import_problems, source_from_notebook

REPO = Path(__file__).resolve().parents[1]
FIXTURES = REPO / "tests" / "fixtures" / "a1"
LIMITS = Limits(cpu_seconds=5, memory_mb=600, load_timeout=5.0, case_timeout=0.5)
REFERENCE = (FIXTURES / "reference.py").read_text()
NUMPY = frozenset({"numpy"})


def notebook(path: Path, *cells: str) -> Path:
    """A notebook of code cells (a cell starting with ``# md`` is a markdown cell)."""
    path.write_text(json.dumps({"nbformat": 4, "nbformat_minor": 5, "metadata": {}, "cells": [
        {"cell_type": "markdown" if c.startswith("# md") else "code", "metadata": {},
         "source": c, **({} if c.startswith("# md") else {"outputs": [],
                                                            "execution_count": None})}
        for c in cells]}))
    return path


def one_line(result) -> str:
    return " ".join(str(result).split())


def test_the_assignment_notebook_is_graded_on_its_module(tmp_path):
    shutil.copy(REPO / "assignments" / "a1_rotations.ipynb", tmp_path)
    (tmp_path / "a1_rotations.py").write_text(REFERENCE)
    result = check("a1", tmp_path / "a1_rotations.ipynb", limits=LIMITS)
    assert not result.problems and result.score == 12
    text = one_line(result)
    assert ("Note: a1_rotations.ipynb imports a1_rotations: graded a1_rotations.py beside it, "
            "then the notebook's own definitions") in text
    assert ("Note: cell 2, line 9: `from course import rotations as ref` is ignored: only "
            "display code uses it") in text


@pytest.mark.parametrize("stem", ["a1_rotations", "a2_forward_kinematics",
                                  "a3_inverse_kinematics"])
def test_every_assignment_notebook_loads_with_its_template(stem, tmp_path):
    """What the grader keeps of the notebooks' display cells loads: the template's stubs are
    all it sees of the functions."""
    for suffix in (".ipynb", ".py"):
        shutil.copy(REPO / "assignments" / f"{stem}{suffix}", tmp_path)
    result = check(stem[:2], tmp_path / f"{stem}.ipynb", limits=LIMITS)
    assert not result.problems, result.problems
    assert {t.status for t in result.tests} == {"not_implemented"}


def test_the_assignment_notebook_alone_says_what_to_submit(tmp_path):
    shutil.copy(REPO / "assignments" / "a2_forward_kinematics.ipynb", tmp_path)
    result = check("a2", tmp_path / "a2_forward_kinematics.ipynb", limits=LIMITS)
    assert result.score == 0
    assert result.problems == ["a2_forward_kinematics.ipynb imports a2_forward_kinematics, but "
                               "a2_forward_kinematics.py is not beside it: submit that file "
                               "(with the notebook or alone)"]


def test_course_in_a_display_cell_only_is_ignored_in_a_function_refused(tmp_path):
    display = notebook(tmp_path / "display.ipynb", "# md My a1", REFERENCE,
                       "from course import rotations as ref\nprint(ref.quat_mul([1.0, 0, 0, 0], "
                       "[1.0, 0, 0, 0]))")
    result = check("a1", display, limits=LIMITS)
    assert not result.problems and result.score == 12
    assert "Note: cell 3, line 1: `from course import rotations as ref` is ignored" in one_line(
        result)
    used = notebook(tmp_path / "used.ipynb", "# md My a1", REFERENCE,
                    "from course import rotations as ref\n\n\ndef quat_mul(a, b):\n"
                    "    return ref.quat_mul(a, b)")
    result = check("a1", used, limits=LIMITS)
    assert result.score == 0
    assert result.problems == ["cell 3, line 1: `from course import ...` is not allowed: the "
                               "course library is the reference you are compared with"]


def test_a_table_filled_by_a_loop_is_kept(tmp_path):
    """The audit's notebook: a dictionary filled by a top-level loop, used by a function."""
    euler = ("def matrix_from_euler(angles, order):\n"
             "    R = np.eye(3)\n"
             "    for axis, a in zip(order, angles):\n"
             "        c, s = np.cos(a), np.sin(a)\n"
             "        k = _AX[axis]\n"
             "        i, j = [n for n in range(3) if n != k]\n"
             "        E = np.eye(3)\n"
             "        E[i, i] = E[j, j] = c\n"
             "        E[i, j], E[j, i] = (-s, s) if k != 1 else (s, -s)\n"
             "        R = R @ E\n"
             "    return R\n")
    path = notebook(tmp_path / "table.ipynb",
                    "import numpy as np\n_AX = {}\nfor i, a in enumerate('XYZ'):\n    _AX[a] = i",
                    REFERENCE.replace("def matrix_from_euler(", "def _unused_euler("), euler)
    result = check("a1", path, limits=LIMITS)
    assert not result.notes and result.score == 12


def test_dropped_code_the_functions_need_is_named(tmp_path):
    path = notebook(tmp_path / "build.ipynb", REFERENCE,
                    "def _build():\n    return {'XYZ': 1}\n\n\n_TABLE = _build()",
                    "def quat_mul(a, b):\n    _TABLE['XYZ']\n    return a")
    result = check("a1", path, limits=LIMITS)
    text = one_line(result)
    assert ("Note: cell 2, line 5: `_TABLE = _build()` was not run by the grader (display code: "
            "only definitions and data built with numpy, math, imports and builtins are kept), "
            "but your code uses _TABLE") in text
    assert "quat_mul raised NameError: name '_TABLE' is not defined (cell 3, line 2: _TABLE" in text


def test_errors_point_to_the_cell_and_line(tmp_path):
    path = notebook(tmp_path / "raises.ipynb", "# md title", REFERENCE,
                    "# md why", "import numpy as np\n\n\ndef slerp(q0, q1, t):\n"
                    "    raise ValueError('not yet')")
    result = check("a1", path, limits=LIMITS)
    assert "slerp raised ValueError: not yet (cell 4, line 5: raise ValueError('not yet'))" in (
        one_line(result))
    broken = notebook(tmp_path / "broken.ipynb", REFERENCE, "def slerp(:\n    pass")
    result = check("a1", broken, limits=LIMITS)
    assert "Note: cell 2 was skipped: it does not parse (line 1: invalid syntax)" in one_line(
        result)


def test_cell_magics_keep_python_bodies_only():
    cells = [
        "%%time\ndef quat_mul(a, b):\n    return a",
        "%%timeit\ndef slerp(q0, q1, t):\n    return q0",
        "%%writefile helper.py\ndef matrix_from_quat(q):\n    return q",
        "%%capture\nEPS = 1e-9",
        "%matplotlib inline\n!pip install numpy\nimport numpy as np\nnp.dot?\nfiles = !ls",
        "def quat_from_matrix(R):\n    w = 1.0  # is this the largest component?\n    return R",
    ]
    src = source_from_notebook(json.dumps({"cells": [
        {"cell_type": "code", "source": c} for c in cells]}), functions=frozenset({
            "quat_mul", "slerp", "matrix_from_quat", "quat_from_matrix"}))
    assert "def quat_mul" in src.text and "EPS = 1e-9" in src.text
    assert "def slerp" not in src.text and "def matrix_from_quat" not in src.text
    assert "import numpy as np" in src.text and "pip" not in src.text and "ls" not in src.text
    assert "# is this the largest component?" in src.text  # a '?' in a comment is Python
    assert src.locate(src.text.splitlines().index("def quat_mul(a, b):") + 1) == "cell 1, line 2"
    compile(src.text, "nb", "exec")


def test_static_refusals_in_a_notebook_name_the_cell():
    nb = json.dumps({"cells": [{"cell_type": "markdown", "source": "# a1"},
                               {"cell_type": "code", "source": "import numpy as np\n\n"
                                "def f():\n    import scipy.linalg\n    return scipy.linalg"}]})
    src = source_from_notebook(nb, functions=frozenset({"f"}))
    assert import_problems(src, NUMPY, "nb.ipynb") == [
        "cell 2, line 4: `import scipy.linalg` is not allowed: the assignment asks you to "
        "implement the math yourself with numpy"]
