"""The autograder's modules import on their own: each alone, in a fresh interpreter.

That no module imports another in a circle (lazy and type-only imports included) is
``tests/test_layers.py``'s check, for ``course`` too.
"""

from __future__ import annotations

import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

import autograder

PACKAGE = Path(autograder.__file__).parent
# __main__ runs the command line when imported: `python -m autograder` is its test.
MODULES = sorted(m.name for m in pkgutil.walk_packages([str(PACKAGE)], "autograder.")
                 if not m.name.endswith("__main__"))


@pytest.mark.parametrize("module", MODULES)
def test_each_module_imports_on_its_own(module):
    out = subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True,
                         text=True, cwd=PACKAGE.parent)
    assert out.returncode == 0, out.stderr
