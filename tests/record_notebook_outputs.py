"""Record the expected printout of every ``# NBVAL_CHECK_OUTPUT`` cell into its metadata.

Run after changing a notebook (from the repository root)::

    .venv/bin/python tests/record_notebook_outputs.py notebooks/01_rotations.ipynb ...

Each notebook is executed twice (headless, as the Makefile's tests): on this machine's default
numeric path and on its alternate one (another OpenBLAS kernel, numpy's baseline SIMD, another
BLAS thread count: ``tests/numeric_paths.py``). A checked cell must print the same on both,
or the notebook is not recorded: the tool says which cell (index and first line) and which
lines and digits differ. A checked cell prints only what every machine agrees on; rounding-
decided digits belong in an unchecked cell. When both agree, the stdout of each checked cell
is stored as ``cell.metadata["nbval_expected"]`` and the notebook saved without outputs.

``--check`` records nothing: it runs both paths and also compares them with the recorded
outputs (an audit of notebooks already recorded). The exit status is 1 when any notebook
was refused (or, with ``--check``, differs).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import nbformat
from numeric_paths import ADVICE, DEFAULT, KEY, Run, alternate_path, compare, run_notebook


def run_both(path: Path) -> tuple[nbformat.NotebookNode, list[Run]]:
    """The notebook and its runs on the default and the alternate numeric path."""
    nb = nbformat.read(path, as_version=4)
    return nb, [run_notebook(path, DEFAULT), run_notebook(path, alternate_path())]


def record(path: Path) -> tuple[int, list[str]]:
    """Record ``path``'s checked outputs; (how many, no problems), or (0, the problems) and
    the file left as it was."""
    nb, runs = run_both(path)
    problems = compare(str(path), nb, runs)
    if problems:
        return 0, problems
    checked = 0
    for i, cell in enumerate(nb.cells):
        if cell.cell_type != "code":
            continue
        cell.outputs, cell.execution_count = [], None
        cell.metadata.pop(KEY, None)
        if i in runs[0].outputs:
            cell.metadata[KEY] = runs[0].outputs[i]
            checked += 1
    nbformat.write(nb, path)
    return checked, []


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("notebooks", nargs="+", type=Path)
    parser.add_argument("--check", action="store_true",
                        help="record nothing; compare both paths with the recorded outputs")
    args = parser.parse_args(argv)
    alternate = alternate_path()
    print(f"numeric paths: {DEFAULT.describe()}; {alternate.describe()}")
    for note in alternate.notes:
        print(f"  {note}")
    failed = 0
    for path in args.notebooks:
        if args.check:
            nb, runs = run_both(path)
            problems = compare(str(path), nb, runs, recorded=True)
            verdict = "differs" if problems else "every checked cell as recorded, on both paths"
        else:
            checked, problems = record(path)
            verdict = ("NOT recorded" if problems
                       else f"{checked} checked cells recorded (the same on both paths)")
        print(f"{path}: {verdict}")
        for problem in problems:
            print(problem, file=sys.stderr)
        failed += bool(problems)
    if failed:
        print(ADVICE, file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
