"""Record the expected printout of every ``# NBVAL_CHECK_OUTPUT`` cell into its metadata.

Run after changing a notebook (from the repository root, with the headless settings the
Makefile uses)::

    .venv/bin/python tests/record_notebook_outputs.py notebooks/01_rotations.ipynb ...

The notebook is executed, the stdout of each checked cell stored as
``cell.metadata["nbval_expected"]``, and the notebook saved again without outputs.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import nbformat
from nbclient import NotebookClient

MARK = "# NBVAL_CHECK_OUTPUT"
KEY = "nbval_expected"


def record(path: Path) -> int:
    nb = nbformat.read(path, as_version=4)
    run = nbformat.from_dict(nb)
    NotebookClient(run, timeout=120, kernel_name="python3",
                   resources={"metadata": {"path": str(path.parent)}}).execute()
    checked = 0
    for cell, ran in zip(nb.cells, run.cells, strict=True):
        if cell.cell_type != "code":
            continue
        cell.outputs, cell.execution_count = [], None
        cell.metadata.pop(KEY, None)
        if cell.source.lstrip().startswith(MARK):
            cell.metadata[KEY] = "".join(
                o.get("text", "") for o in ran.outputs
                if o.output_type == "stream" and o.name == "stdout"
            )
            checked += 1
    nbformat.write(nb, path)
    return checked


def main(paths: list[str]) -> None:
    os.environ.setdefault("PYVISTA_JUPYTER_BACKEND", "static")
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    for p in paths:
        print(f"{p}: {record(Path(p))} checked cells recorded")


if __name__ == "__main__":
    main(sys.argv[1:])
