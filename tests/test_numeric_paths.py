"""The alternate numeric path and the recording tool's refusal (tests/numeric_paths.py,
tests/record_notebook_outputs.py): a tiny notebook run on two BLAS kernels, with the same
comparison code the tool uses."""

from __future__ import annotations

from pathlib import Path

import nbformat
import numeric_paths
import pytest
from numeric_paths import KEY, MARK, alternate_core, alternate_path, line_diff
from record_notebook_outputs import record

TESTS = Path(__file__).resolve().parent

SURE = f"""{MARK}
import numpy as np
A = np.random.default_rng(0).normal(size=(300, 300))
x = np.linalg.solve(A, A @ np.ones(300))   # LAPACK and BLAS, rounded differently per kernel
print("solve gives back the ones (within 1e-8):", np.allclose(x, 1, atol=1e-8))"""

# What differs by construction between the two paths: the BLAS kernel and thread count really
# in use inside the kernel, and numpy's disabled SIMD features.
PATH_DEPENDENT = f"""{MARK}
print("blas:", blas_core(), os.environ.get("NPY_DISABLE_CPU_FEATURES"))"""


def notebook(tmp_path: Path, *cells: str) -> Path:
    setup = (f"import os, sys\nsys.path.insert(0, {str(TESTS)!r})\n"
             "from numeric_paths import blas_core")
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(setup)]
                                  + [nbformat.v4.new_code_cell(c) for c in cells])
    path = tmp_path / "tiny.ipynb"
    nbformat.write(nb, path)
    return path


@pytest.mark.parametrize(("machine", "core", "expected"), [
    ("x86_64", "SkylakeX", "Haswell"), ("x86_64", "Cooperlake", "Haswell"),
    ("x86_64", "Haswell", "Sandybridge"), ("AMD64", "Zen", "Sandybridge"),
    ("x86_64", "Sandybridge", "Nehalem"), ("x86_64", "Nehalem", "Prescott"),
    ("x86_64", "Prescott", None), ("x86_64", None, None),
    ("aarch64", "NEOVERSEN1", "ARMV8"), ("arm64", "VORTEX", "ARMV8"), ("aarch64", "ARMV8", None),
    ("ppc64le", "POWER9", None),
])
def test_alternate_kernel_is_an_older_one_the_cpu_runs(machine, core, expected):
    alt, why = alternate_core(machine, core)
    assert alt == expected
    assert (alt or "not varied") in why or "not OpenBLAS" in why


def test_line_diff_marks_the_digits():
    diff = line_diff("a\nratio = 1e-07\nb\n", "a\nratio = 4e-07\nb\n")
    assert diff == ["- ratio = 1e-07", "?         ^", "+ ratio = 4e-07", "?         ^"]


def varies() -> None:
    path = alternate_path()
    if not path.overrides:
        pytest.skip("no alternate numeric path on this machine: " + "; ".join(path.notes))


def test_alternate_path_changes_something_and_says_what():
    varies()
    path = alternate_path()
    assert path.notes, path
    assert set(path.overrides) <= {"OPENBLAS_CORETYPE", "OPENBLAS_NUM_THREADS",
                                   "NPY_DISABLE_CPU_FEATURES"}


def test_record_refuses_an_output_that_differs_between_paths(tmp_path):
    varies()
    path = notebook(tmp_path, SURE, PATH_DEPENDENT)
    before = path.read_text(encoding="utf-8")
    checked, problems = record(path)
    assert checked == 0 and len(problems) == 1, problems
    assert "tiny.ipynb, cell 2 (`print(\"blas:\"" in problems[0], problems[0]
    assert "\n    - blas:" in problems[0] and "\n    + blas:" in problems[0], problems[0]
    assert path.read_text(encoding="utf-8") == before, "a refused notebook is left as it was"
    core, _ = numeric_paths.blas_core()
    if "OPENBLAS_CORETYPE" in alternate_path().overrides:  # the kernel was really switched
        lines = problems[0].splitlines()
        default = next(ln for ln in lines if ln.startswith("    - blas:"))
        alternate = next(ln for ln in lines if ln.startswith("    + blas:"))
        assert f"('{core}'" in default and f"('{core}'" not in alternate, problems[0]


def test_record_stores_what_both_paths_agree_on(tmp_path):
    path = notebook(tmp_path, SURE)
    assert record(path) == (1, [])
    cells = nbformat.read(path, as_version=4).cells
    assert cells[1].metadata[KEY] == "solve gives back the ones (within 1e-8): True\n"
    assert all(not c.outputs and c.execution_count is None for c in cells)
