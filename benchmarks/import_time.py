"""How long ``import course`` takes in a fresh interpreter, against ``import numpy`` (which it
needs anyway) measured the same way beside it.

Run:  .venv/bin/python benchmarks/import_time.py [--repeats 15]

Each figure is the median of ``--repeats`` fresh interpreters, timed inside the child with
``time.perf_counter`` around the import alone (interpreter start-up excluded). The goal is
that ``import course, course.rotations`` costs at most ~2x numpy's import: the heavy libraries
(scipy, matplotlib, pyvista, vtk) load on first use, which tests/test_repository.py checks.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys

CHILD = "import time; t = time.perf_counter(); {stmt}; print(time.perf_counter() - t)"


def import_seconds(stmt: str, repeats: int, prelude: str = "") -> float:
    code = prelude + CHILD.format(stmt=stmt)
    runs = [float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                 check=True).stdout) for _ in range(repeats)]
    return statistics.median(runs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    numpy = import_seconds("import numpy", args.repeats)
    course = import_seconds("import course, course.rotations", args.repeats)
    own = import_seconds("import course, course.rotations", args.repeats, prelude="import numpy; ")
    for label, seconds in (("import numpy", numpy), ("import course, course.rotations", course),
                           ("  of which course itself", own)):
        print(f"{label:34s}{seconds * 1e3:7.1f} ms   ({seconds / numpy:.2f}x numpy)")


if __name__ == "__main__":
    main()
