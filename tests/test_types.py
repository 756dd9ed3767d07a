"""The type checker is clean on the paths `[tool.mypy]` in pyproject.toml lists (strict)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def test_mypy_clean():
    mypy = REPO / ".venv" / "bin" / "mypy"
    if not mypy.exists():
        pytest.skip("mypy is installed by `make test` (the dev extra)")
    out = subprocess.run([str(mypy)], cwd=REPO, capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr
