"""Checked notebook outputs without committing outputs.

Notebooks are committed clean (no outputs, no execution counts), so nbval alone would skip
the comparison of ``# NBVAL_CHECK_OUTPUT`` cells. Their expected printout lives in the cell's
metadata (``nbval_expected``, written by ``tests/record_notebook_outputs.py``); here it is put
back as the reference output before nbval runs the cell.
"""

from __future__ import annotations

import nbformat

EXPECTED_KEY = "nbval_expected"


def pytest_collection_modifyitems(items):
    for item in items:
        cell = getattr(item, "cell", None)
        if cell is None or not getattr(item, "options", {}).get("check"):
            continue
        expected = cell.get("metadata", {}).get(EXPECTED_KEY)
        if expected is None:
            continue
        cell.outputs = [nbformat.v4.new_output("stream", name="stdout", text=expected)]
        cell.execution_count = 1
