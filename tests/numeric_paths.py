"""The numeric paths a checked notebook output must not depend on.

A ``# NBVAL_CHECK_OUTPUT`` cell's recorded printout is compared wherever ``make test`` runs,
and each machine computes its floats its own way: OpenBLAS picks a kernel for the CPU
(SkylakeX, Haswell, Zen, NeoverseN1, ...) and a thread count for the cores, numpy a SIMD path
(AVX-512, AVX2, NEON, ...) for its loops, and each can change the last bits of a result (and,
in a chaotic computation, everything after them). A checked printout must hold on all of them.

This module defines this machine's **alternate numeric path**, in one place:

* another OpenBLAS kernel (``OPENBLAS_CORETYPE``): always an older one of the same CPU family,
  which the CPU runs (AVX-512 -> Haswell, AVX2 -> Sandybridge, AVX -> Nehalem, ...; on arm64
  the generic ARMV8 kernels);
* numpy's baseline SIMD (``NPY_DISABLE_CPU_FEATURES``: every dispatched feature this numpy
  would use on this CPU);
* one OpenBLAS thread (``OPENBLAS_NUM_THREADS=1``; two where the default is one).

Where a part is impossible (not OpenBLAS, an unknown kernel, no SIMD above the baseline) it
is left out and :attr:`NumericPath.notes` says so. Used by

* ``tests/record_notebook_outputs.py``: runs a notebook on the default and the alternate path
  and refuses to record a checked output that differs between them (:func:`compare`);
* ``make test-numeric`` (run by ``.ci/run``): the notebooks' checked cells and the library
  tests that compare floats, again, under the alternate path;
* ``tests/test_numeric_paths.py``.

Command line (from the repository root)::

    .venv/bin/python tests/numeric_paths.py              # what the alternate path changes
    .venv/bin/python tests/numeric_paths.py --env        # the same as KEY=VALUE lines
    .venv/bin/python tests/numeric_paths.py -- CMD ...   # run CMD under the alternate path
"""

from __future__ import annotations

import ctypes
import difflib
import glob
import os
import platform
import sys
from dataclasses import dataclass, field
from pathlib import Path

import nbformat

MARK = "# NBVAL_CHECK_OUTPUT"
KEY = "nbval_expected"  # where a checked cell's expected stdout is recorded (see conftest.py)

# Rendering without a display, as the Makefile's TEST_ENV.
HEADLESS = {
    "PYVISTA_JUPYTER_BACKEND": "static",
    "PYVISTA_OFF_SCREEN": "true",
    "VTK_DEFAULT_OPENGL_WINDOW": "vtkEGLRenderWindow",
}

# The alternate OpenBLAS kernel for the kernel in use (lower case, as OpenBLAS names vary in
# case): an older generation of the same family, so the CPU is sure to run it.
_X86_ALTERNATE = {
    **dict.fromkeys(("skylakex", "cooperlake", "sapphirerapids"), "Haswell"),
    **dict.fromkeys(("haswell", "zen", "excavator", "skylake"), "Sandybridge"),
    **dict.fromkeys(("sandybridge", "bulldozer", "piledriver", "steamroller"), "Nehalem"),
    **dict.fromkeys(("nehalem", "dunnington", "penryn", "core2", "barcelona", "opteron_sse3",
                     "opteron", "atom", "nano"), "Prescott"),
}
_ARM64_GENERIC = "ARMV8"


def alternate_core(machine: str, core: str | None) -> tuple[str | None, str]:
    """The OPENBLAS_CORETYPE to force instead of ``core`` on a ``machine`` (platform.machine()),
    or None; and a sentence saying which and why."""
    if core is None:
        return None, "numpy's BLAS is not OpenBLAS here: OPENBLAS_CORETYPE would change nothing"
    arch = machine.lower()
    if arch in ("x86_64", "amd64"):
        alt = _X86_ALTERNATE.get(core.lower())
        if alt is None:
            return None, (f"no alternate for the OpenBLAS kernel {core} (x86-64): the BLAS "
                          "kernel is not varied, only the thread count and numpy's SIMD")
        return alt, f"OpenBLAS kernel {alt} instead of {core}"
    if arch in ("aarch64", "arm64"):
        if core.lower() == _ARM64_GENERIC.lower():
            return None, (f"OpenBLAS already runs its generic {core} kernels (arm64): the BLAS "
                          "kernel is not varied, only the thread count and numpy's SIMD")
        return _ARM64_GENERIC, f"OpenBLAS kernel {_ARM64_GENERIC} (generic arm64) instead of {core}"
    return None, (f"no known alternate OpenBLAS kernel on {machine} (kernel {core}): the BLAS "
                  "kernel is not varied, only the thread count and numpy's SIMD")


def _openblas_functions() -> list[tuple[ctypes.CDLL, str]]:
    """The loaded OpenBLAS libraries of numpy (and scipy, if imported) and their symbol prefix."""
    import numpy  # noqa: F401  (loads numpy's BLAS)

    paths: list[str] = []
    try:
        with open("/proc/self/maps", encoding="utf-8") as maps:
            paths = [line.split()[-1] for line in maps if "openblas" in line.lower()]
    except OSError:  # not Linux: the libraries numpy's wheel bundles
        base = Path(numpy.__file__).parent
        paths = glob.glob(str(base / ".dylibs" / "*openblas*")) + glob.glob(
            str(base.parent / "numpy.libs" / "*openblas*"))
    found = []
    numpy_first = sorted(dict.fromkeys(paths), key=lambda p: "numpy" not in p.lower())
    for path in numpy_first:
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for prefix in ("scipy_", ""):
            for suffix in ("64_", ""):
                if hasattr(lib, f"{prefix}openblas_get_corename{suffix}"):
                    found.append((lib, f"{prefix}openblas_%s{suffix}"))
                    break
            else:
                continue
            break
    return found


def blas_core() -> tuple[str | None, int | None]:
    """(OpenBLAS kernel, thread count) numpy's BLAS uses in this process; (None, None) if
    numpy's BLAS is not OpenBLAS. threadpoolctl's view where it is installed, else asked of
    the loaded library itself (what threadpoolctl does)."""
    try:
        import numpy  # noqa: F401  (loads numpy's BLAS)
        from threadpoolctl import threadpool_info
    except ImportError:
        pass
    else:
        infos = sorted((i for i in threadpool_info() if i.get("internal_api") == "openblas"),
                       key=lambda i: "numpy" not in str(i.get("filepath", "")).lower())
        if infos and infos[0].get("architecture"):
            return str(infos[0]["architecture"]), int(infos[0]["num_threads"])
    found = _openblas_functions()
    if not found:
        return None, None
    lib, pattern = found[0]  # numpy's own, where scipy bundles another
    corename = getattr(lib, pattern % "get_corename")
    corename.restype = ctypes.c_char_p
    threads = getattr(lib, pattern % "get_num_threads")
    threads.restype = ctypes.c_int
    return corename().decode(), int(threads())


def numpy_dispatched_features() -> list[str]:
    """The SIMD features numpy dispatches to above its baseline, and this CPU has: the ones
    NPY_DISABLE_CPU_FEATURES may name (numpy refuses to disable a baseline feature)."""
    try:
        from numpy._core import _multiarray_umath as umath
    except ImportError:  # numpy 1.x
        from numpy.core import _multiarray_umath as umath  # type: ignore[no-redef]
    return [f for f in umath.__cpu_dispatch__ if umath.__cpu_features__.get(f)]


@dataclass(frozen=True)
class NumericPath:
    """Environment variables set on top of the current environment, and what they do."""

    name: str
    overrides: dict[str, str] = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    def env(self, base: dict[str, str] | None = None) -> dict[str, str]:
        return {**(os.environ if base is None else base), **self.overrides}

    def describe(self) -> str:
        if not self.overrides:
            return f"{self.name} (this environment, unchanged)"
        return f"{self.name} ({', '.join(f'{k}={v}' for k, v in self.overrides.items())})"


DEFAULT = NumericPath("default")


def alternate_path(environ: dict[str, str] | None = None) -> NumericPath:
    """This machine's alternate numeric path, relative to the numeric path of this process."""
    environ = dict(os.environ if environ is None else environ)
    overrides: dict[str, str] = {}
    notes: list[str] = []
    core, threads = blas_core()
    alt, why = alternate_core(platform.machine(), core)
    notes.append(why)
    if alt is not None:
        overrides["OPENBLAS_CORETYPE"] = alt
    if core is not None:
        overrides["OPENBLAS_NUM_THREADS"] = "1" if (threads or 1) > 1 else "2"
        notes.append(f"{overrides['OPENBLAS_NUM_THREADS']} OpenBLAS thread(s) instead of "
                     f"{threads}")
    already = environ.get("NPY_DISABLE_CPU_FEATURES", "").replace(",", " ").split()
    disable = list(dict.fromkeys(already + numpy_dispatched_features()))
    if disable:
        overrides["NPY_DISABLE_CPU_FEATURES"] = " ".join(disable)
        notes.append("numpy's baseline SIMD: " + " ".join(disable) + " disabled")
    else:
        notes.append("numpy dispatches no SIMD above its baseline on this CPU: not varied")
    return NumericPath("alternate", overrides, tuple(notes))


# --- running a notebook's checked cells, comparing two runs --------------------------------


def checked_cells(nb: nbformat.NotebookNode) -> dict[int, str]:
    """Index -> first line after the mark, of every ``# NBVAL_CHECK_OUTPUT`` cell."""
    cells = {}
    for i, cell in enumerate(nb.cells):
        if cell.cell_type == "code" and cell.source.lstrip().startswith(MARK):
            lines = [ln for ln in cell.source.lstrip()[len(MARK):].splitlines() if ln.strip()]
            cells[i] = lines[0].strip() if lines else ""
    return cells


@dataclass
class Run:
    """One execution of a notebook: the stdout of its checked cells, the errors of any cell."""

    path: NumericPath
    outputs: dict[int, str]
    errors: dict[int, str]


def run_notebook(nb_path: Path, path: NumericPath, timeout: int = 300) -> Run:
    """Execute the notebook at ``nb_path`` (in its folder, headless) on the numeric ``path``."""
    from nbclient import NotebookClient

    nb = nbformat.read(nb_path, as_version=4)
    client = NotebookClient(nb, timeout=timeout, kernel_name="python3", allow_errors=True,
                            resources={"metadata": {"path": str(nb_path.parent)}})
    client.execute(env=path.env({**os.environ, **HEADLESS}))
    outputs, errors = {}, {}
    checked = checked_cells(nb)
    for i, cell in enumerate(nb.cells):
        if cell.cell_type != "code":
            continue
        for out in cell.outputs:
            if out.output_type == "error":
                errors[i] = f"{out.ename}: {out.evalue}"
        if i in checked:
            outputs[i] = "".join(o.get("text", "") for o in cell.outputs
                                 if o.output_type == "stream" and o.name == "stdout")
    return Run(path, outputs, errors)


def line_diff(a: str, b: str) -> list[str]:
    """The lines of ``a`` and ``b`` that differ, with ``?`` lines marking the characters."""
    return [ln.rstrip("\n") for ln in difflib.ndiff(a.splitlines(), b.splitlines())
            if not ln.startswith("  ")]


def compare(name: str, nb: nbformat.NotebookNode, runs: list[Run],
            recorded: bool = False) -> list[str]:
    """What keeps the checked outputs of ``runs`` from being recorded: a cell that raised, a
    checked cell that printed differently on two paths (or, with ``recorded``, differently from
    its recorded ``nbval_expected``). One message per problem; none if all agree."""
    problems = []
    first = checked_cells(nb)

    def where(i: int) -> str:
        line = first.get(i) or nb.cells[i].source.strip().splitlines()[0]
        return f"{name}, cell {i} (`{line[:60]}`)"

    for run in runs:
        for i, error in run.errors.items():
            problems.append(f"{where(i)} raised on the {run.path.describe()} path: {error}")
    base = runs[0]
    for i in first:
        for other in runs[1:]:
            if base.outputs.get(i) != other.outputs.get(i):
                diff = line_diff(base.outputs.get(i, ""), other.outputs.get(i, ""))
                problems.append(
                    f"{where(i)}: the checked output differs between numeric paths\n"
                    f"  - {base.path.describe()}\n  + {other.path.describe()}\n"
                    + "\n".join("    " + ln for ln in diff))
        expected = nb.cells[i].metadata.get(KEY)
        if recorded and expected is not None:
            for run in runs:
                if run.outputs.get(i) != expected:
                    diff = line_diff(expected, run.outputs.get(i, ""))
                    problems.append(
                        f"{where(i)}: the {run.path.describe()} path differs from the recorded "
                        "output\n  - recorded\n  + this run\n"
                        + "\n".join("    " + ln for ln in diff))
    return problems


ADVICE = (
    "A checked cell must print only what every CPU agrees on: round to the digits that are "
    "sure, print a property (converged or not, the order of two methods) or a bound "
    "(`< 1e-12`), and leave exact digits to an unchecked cell (say in the prose why)."
)


def main(argv: list[str]) -> None:
    path = alternate_path()
    if argv[:1] == ["--env"]:
        print("\n".join(f"{k}={v}" for k, v in path.overrides.items()))
        return
    if argv[:1] == ["--"] and len(argv) > 1:
        print(f"numeric path: {path.describe()}", file=sys.stderr)
        for note in path.notes:
            print(f"  {note}", file=sys.stderr)
        sys.stderr.flush()
        os.execvpe(argv[1], argv[1:], path.env())
    if argv:
        sys.exit(__doc__)
    print(path.describe())
    for note in path.notes:
        print(f"  {note}")


if __name__ == "__main__":
    main(sys.argv[1:])
