"""Repository-wide rules: clean notebooks, a light `import course`, lint."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

NOTEBOOKS = sorted([*REPO.glob("notebooks/*.ipynb"), *REPO.glob("assignments/*.ipynb")])


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_committed_without_outputs(path):
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    dirty = [
        i for i, c in enumerate(cells)
        if c["cell_type"] == "code" and (c.get("outputs") or c.get("execution_count"))
    ]
    assert not dirty, f"{path.name}: cells {dirty} have outputs; clear them before committing"


def test_import_course_is_light():
    """`import course` loads no heavy library; how long it takes is benchmarks/import_time.py."""
    code = (
        "import sys; import course, course.rotations;"
        "print(','.join(sorted(m for m in ('scipy', 'pyvista', 'matplotlib', 'vtk', 'ipywidgets',"
        " 'dask') if m in sys.modules)))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    heavy = out.stdout.strip()
    assert not heavy, f"import course pulled in {heavy}"


def test_ruff_clean():
    ruff = REPO / ".venv" / "bin" / "ruff"
    if not ruff.exists():
        pytest.skip("ruff is installed by `make test`")
    out = subprocess.run([str(ruff), "check", "--quiet", str(REPO)], capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_checked_cells_have_recorded_output(path):
    """A `# NBVAL_CHECK_OUTPUT` cell is only compared if its expected printout is recorded
    (see tests/record_notebook_outputs.py and the root conftest.py)."""
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    missing = [
        i for i, c in enumerate(cells)
        if c["cell_type"] == "code"
        and "".join(c["source"]).lstrip().startswith("# NBVAL_CHECK_OUTPUT")
        and "nbval_expected" not in c.get("metadata", {})
    ]
    assert not missing, (
        f"{path.name}: checked cells {missing} have no recorded output; run "
        f"`.venv/bin/python tests/record_notebook_outputs.py {path.relative_to(REPO)}`"
    )
