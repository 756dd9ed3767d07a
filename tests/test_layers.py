"""The packages ``course`` and ``autograder`` are layers without circles.

Every ``.py`` file is read with ``ast`` and every import statement counts: at module level,
inside functions (a lazy import still runs) and under ``if TYPE_CHECKING:`` (a type-only
import still says which module knows which), and ``importlib.import_module`` of a literal
name, or of an f-string, as every module its fixed start may name (a registry loading its
plugins by name depends on each of them).
Relative imports are resolved; ``from pkg import mod`` where ``mod`` is a submodule is an
edge to ``pkg.mod``, ``from pkg import name`` an edge to ``pkg`` (its ``__init__``).

A package's ``__init__`` re-exporting its submodules is fine: loading ``pkg.sub`` runs
``pkg/__init__`` first, but that implicit load is not an edge (the submodule uses none of its
names). A submodule that names something of its own package (``from . import name``) has an
edge to the ``__init__``, and that is a circle exactly when the ``__init__`` imports the
submodule back, directly or through others: the cycle search finds it like any other.

Private names (a leading underscore) stay in their module: no function, class or constant
named ``_x`` is imported elsewhere. A private module (``_kernels``, ``_typing``) is internal
to the top-level package holding it: modules of that package may import it, others may not.
"""

from __future__ import annotations

import ast
import importlib.util
import subprocess
import sys
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("course", "autograder")


@dataclass(frozen=True)
class Import:
    """One imported module (``target``) and the names taken from it, where it is written
    (``path`` relative to the packages' folder)."""

    source: str
    target: str
    names: tuple[str, ...]
    path: Path
    line: int

    def where(self) -> str:
        return f"{self.path}:{self.line}"


def module_name(path: Path, root: Path) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules(root: Path, packages: tuple[str, ...]) -> dict[str, Path]:
    return {module_name(p, root): p for pkg in packages for p in sorted((root / pkg).rglob("*.py"))}


def _import_module_targets(node: ast.Call, name: str, known: dict[str, Path]) -> list[str]:
    """The modules ``importlib.import_module(...)`` may load: the one named by a literal, or
    every module of ``known`` starting with an f-string's fixed start (``f"pkg.nb{n}"``, where
    ``{__name__}`` is the importing module's name)."""
    f = node.func
    named = (isinstance(f, ast.Attribute) and f.attr == "import_module") or (
        isinstance(f, ast.Name) and f.id == "import_module")
    if not (named and node.args):
        return []
    arg = node.args[0]
    if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
        return [arg.value]
    if not isinstance(arg, ast.JoinedStr):
        return []
    prefix = ""
    for part in arg.values:
        if isinstance(part, ast.Constant):
            prefix += str(part.value)
        elif (isinstance(part, ast.FormattedValue) and isinstance(part.value, ast.Name)
              and part.value.id == "__name__"):
            prefix += name
        else:
            break
    return [m for m in known if m.startswith(prefix) and len(m) > len(prefix)] if prefix else []


def imports(name: str, path: Path, known: dict[str, Path], root: Path) -> Iterator[Import]:
    """Every import of module ``name`` (file ``path``) into a module of ``known``."""
    anchor = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if not isinstance(node, (ast.Import, ast.ImportFrom, ast.Call)):
            continue
        found: list[tuple[str, tuple[str, ...]]] = []
        if isinstance(node, ast.Import):
            found = [(a.name, ()) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = (importlib.util.resolve_name("." * node.level + (node.module or ""), anchor)
                    if node.level else node.module or "")
            taken: list[str] = []
            for a in node.names:
                if f"{base}.{a.name}" in known:  # `from pkg import mod`: the submodule
                    found.append((f"{base}.{a.name}", ()))
                else:
                    taken.append(a.name)
            if taken:
                found.append((base, tuple(taken)))
        else:
            found = [(target, ()) for target in _import_module_targets(node, name, known)]
        for target, names in found:
            if target in known and target != name:
                yield Import(name, target, names, path.relative_to(root), node.lineno)


def import_graph(root: Path = ROOT, packages: tuple[str, ...] = PACKAGES
                 ) -> dict[str, list[Import]]:
    """Module -> its imports of the packages' modules."""
    known = modules(root, packages)
    return {name: list(imports(name, path, known, root)) for name, path in known.items()}


@cache
def project_graph() -> dict[str, list[Import]]:
    return import_graph()


def _groups(graph: dict[str, list[Import]]) -> list[set[str]]:
    """The strongly connected groups of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[set[str]] = []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted({i.target for i in graph[start]})))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            v, children = work[-1]
            for w in children:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted({i.target for i in graph[w]}))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    group = set()
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        group.add(w)
                        if w == v:
                            break
                    if len(group) > 1:
                        found.append(group)
    return found


def cycles(graph: dict[str, list[Import]]) -> list[list[Import]]:
    """A shortest circle through the first module of each strongly connected group, as the
    imports that make it."""
    out = []
    for group in _groups(graph):
        start = min(group)
        came: dict[str, Import] = {}
        queue = deque([start])
        while queue:
            v = queue.popleft()
            for imp in graph[v]:
                if imp.target in group and imp.target not in came:
                    came[imp.target] = imp
                    queue.append(imp.target)
        path = [came[start]]
        while path[-1].source != start:
            path.append(came[path[-1].source])
        out.append(path[::-1])
    return sorted(out, key=lambda c: c[0].source)


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def private_imports(graph: dict[str, list[Import]]) -> list[Import]:
    """Imports of another module's private name, or of a private module from outside the
    top-level package holding it."""
    bad = []
    for imports_ in graph.values():
        for imp in imports_:
            top = imp.source.partition(".")[0]
            private_module = any(_private(part) for part in imp.target.split("."))
            if any(_private(n) for n in imp.names) or (
                    private_module and imp.target.partition(".")[0] != top):
                bad.append(imp)
    return bad


def _show_cycle(cycle: list[Import]) -> str:
    return "\n".join(f"  {i.source} -> {i.target}  ({i.where()})" for i in cycle)


# --- the rules -----------------------------------------------------------------------------

def test_no_import_circle() -> None:
    found = cycles(project_graph())
    assert not found, "import circles:\n" + "\n\n".join(_show_cycle(c) for c in found)


def test_no_private_name_crosses_a_module() -> None:
    bad = private_imports(project_graph())
    assert not bad, "private names imported from another module:\n" + "\n".join(
        f"  {i.where()}: {i.source} imports "
        f"{', '.join(n for n in i.names if _private(n)) or 'private module'} from {i.target}"
        for i in bad)


# --- the checker itself --------------------------------------------------------------------

def _package(tmp_path: Path, files: dict[str, str]) -> dict[str, list[Import]]:
    for rel, text in files.items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text(text)
    return import_graph(tmp_path, tuple(sorted({rel.partition("/")[0] for rel in files})))


def _edges(graph: dict[str, list[Import]]) -> dict[str, set[str]]:
    return {k: {i.target for i in v} for k, v in graph.items()}


def test_the_graph_counts_lazy_typing_relative_and_submodule_imports(tmp_path: Path) -> None:
    graph = _package(tmp_path, {
        "pkg/__init__.py": "from .a import x\n",
        "pkg/a.py": ("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                     "    from .b import y\n\ndef f():\n    from . import b\n"),
        "pkg/b.py": ("from .sub import c\nimport importlib\nimportlib.import_module('pkg.d')\n"
                     "importlib.import_module(f'{__name__}x{1}')\n"),
        "pkg/bx1.py": "",
        "pkg/d.py": "",
        "pkg/sub/__init__.py": "",
        "pkg/sub/c.py": "from ..a import x\n",
    })
    assert _edges(graph) == {"pkg": {"pkg.a"}, "pkg.a": {"pkg.b"},
                             "pkg.b": {"pkg.sub.c", "pkg.d", "pkg.bx1"}, "pkg.bx1": set(),
                             "pkg.d": set(), "pkg.sub": set(), "pkg.sub.c": {"pkg.a"}}
    [cycle] = cycles(graph)
    assert [(i.source, i.target) for i in cycle] == [
        ("pkg.a", "pkg.b"), ("pkg.b", "pkg.sub.c"), ("pkg.sub.c", "pkg.a")]
    assert cycle[0].where().endswith("pkg/a.py:3")


def test_a_package_re_exporting_is_no_circle_unless_named_back(tmp_path: Path) -> None:
    files = {"pkg/__init__.py": "from .a import f\nLIMIT = 3\n", "pkg/a.py": "def f(): ...\n"}
    assert cycles(_package(tmp_path, files)) == []
    files["pkg/a.py"] = "from . import LIMIT\n"  # the submodule needs its __init__'s name
    [cycle] = cycles(_package(tmp_path, files))
    assert [(i.source, i.target) for i in cycle] == [("pkg", "pkg.a"), ("pkg.a", "pkg")]


def test_private_names_are_found(tmp_path: Path) -> None:
    graph = _package(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/_inner.py": "X = 1\n",
        "pkg/a.py": "def _f(): ...\nfrom ._inner import X\nfrom . import _inner\n",
        "pkg/b.py": "def g():\n    from .a import _f\n",
        "other/__init__.py": "from pkg._inner import X\n",
    })
    assert [(i.source, i.names, i.line) for i in private_imports(graph)] == [
        ("other", ("X",), 1), ("pkg.b", ("_f",), 2)]


# --- the autograder's layers ---------------------------------------------------------------

def reach(graph: dict[str, list[Import]], start: str) -> set[str]:
    """The modules ``start`` loads, directly or through others (itself left out)."""
    seen, todo = set(), [start]
    while todo:
        for imp in graph[todo.pop()]:
            if imp.target not in seen:
                seen.add(imp.target)
                todo.append(imp.target)
    return seen - {start}


def table_layer(n: int) -> set[str]:
    """The modules of layer ``n`` of autograder's table in docs/architecture.md (the one
    place the layers are written; read by ``test_layer_table``)."""
    from test_layer_table import autograder_layers  # it imports this module: not at the top

    return {m for m, layer in autograder_layers().items() if layer == n and not m.endswith(".")}


def views() -> set[str]:
    """The views of a result (layer 3) and the batch that renders them."""
    return table_layer(3) | {"autograder.batch"}


def test_results_and_records_are_data_below_every_view() -> None:
    graph = project_graph()
    for data in ("autograder.results", "autograder.records"):
        assert not reach(graph, data) & views(), data
    for view in views():  # a view says what was graded: it never grades
        assert "autograder.runner" not in reach(graph, view), view


def test_the_judging_core_loads_nothing_else() -> None:
    graph = project_graph()
    core = table_layer(1)
    assert {"autograder.judging", "autograder.findings", "autograder.spec"} <= core
    for module in core:
        assert reach(graph, module) <= core, module
    exercises = {m for m in graph if m.startswith("course.exercises")}
    loaded = set().union(*(reach(graph, m) for m in exercises))
    assert {m for m in loaded if m.startswith("autograder")} <= core


# --- what the notebooks' checks load --------------------------------------------------------

GRADING_RUN = ("autograder.sandbox", "autograder.grading", "autograder.runner",
               "autograder.cluster", "autograder.jail", "autograder.seccomp",
               "autograder.runtime", "autograder.child", "subprocess")


@pytest.mark.parametrize("module", ["course.exercises"] + [
    f"course.exercises.{p.stem}" for p in sorted((ROOT / "course/exercises").glob("nb*.py"))])
def test_exercises_load_no_grading_run(module: str) -> None:
    code = (f"import sys, {module}\n"
            f"from course.exercises import check, exercises\n"
            f"nb = {module!r}.rpartition('.nb')[2]\n"
            f"if nb != {module!r}:\n"
            f"    for e in exercises(nb):\n"
            f"        check(nb + '.' + e.key, e.function.reference)\n"
            f"print('loaded:', *(m for m in {GRADING_RUN!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, check=True)
    loaded = out.stdout.splitlines()[-1]
    assert loaded == "loaded:", f"{module} {loaded}"
