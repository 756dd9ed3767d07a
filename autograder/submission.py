"""Read a submission (``.py`` or ``.ipynb``) and check its imports before anything runs.

From a notebook only the code that defines things is kept: function and class definitions,
imports, and assignments of constants. Magics (``%``), shell escapes (``!``), help (``?``)
and display code (plots, ``check(...)`` calls, other expressions) are dropped, as are imports
of display-only libraries. The static check then refuses imports of anything but numpy and
the harmless standard library, with the line and a reason; the sandbox enforces the same
rule at run time for code that hides its imports.
"""

from __future__ import annotations

import ast
import json
import sys
from pathlib import Path

from .child import BLOCKED_STDLIB

# Imported by notebooks to show things, never needed by the functions themselves.
DISPLAY_MODULES = frozenset({"matplotlib", "IPython", "ipywidgets", "pyvista", "autograder",
                             "course.viz", "mpl_toolkits"})
WHY_NOT = {
    "course": "the course library is the reference you are compared with",
    "autograder": "the autograder is not part of a solution",
    "scipy": "the assignment asks you to implement the math yourself with numpy",
}


class SubmissionError(ValueError):
    """The submission cannot be read (not UTF-8, not a notebook, ...)."""


def read_source(path: Path) -> str:
    """The Python source of a ``.py`` file, or the definitions extracted from a notebook."""
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise SubmissionError(f"{path.name} is not a UTF-8 text file") from None
    except OSError as exc:
        raise SubmissionError(f"cannot read {path}: {exc.strerror}") from None
    if path.suffix == ".ipynb":
        return source_from_notebook(text, path.name)
    return text


def source_from_notebook(text: str, name: str = "notebook") -> str:
    try:
        cells = json.loads(text)["cells"]
    except (json.JSONDecodeError, KeyError, TypeError):
        raise SubmissionError(f"{name} is not a Jupyter notebook") from None
    kept: list[str] = []
    for cell in cells:
        if not isinstance(cell, dict) or cell.get("cell_type") != "code":
            continue
        src = cell.get("source", "")
        src = "".join(src) if isinstance(src, list) else str(src)
        kept.extend(_definitions(src))
    return "\n\n".join(kept) + "\n"


def _definitions(src: str) -> list[str]:
    lines = [
        "" if ln.lstrip().startswith(("%", "!")) or ln.rstrip().endswith("?") else ln
        for ln in src.splitlines()
    ]
    try:
        tree = ast.parse("\n".join(lines))
    except SyntaxError:
        return []  # a cell that does not parse (a cell magic, say) defines nothing
    code = "\n".join(lines)
    out = []
    for node in tree.body:
        keep = isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) or (
            isinstance(node, (ast.Import, ast.ImportFrom)) and not _display_import(node)) or (
            isinstance(node, (ast.Assign, ast.AnnAssign)) and _constant(node))
        if keep:
            out.append(ast.get_source_segment(code, node, padded=True) or "")
    return out


def _display_import(node: ast.Import | ast.ImportFrom) -> bool:
    names = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
    return all(any(n == d or n.startswith(d + ".") for d in DISPLAY_MODULES) for n in names)


def _constant(node: ast.Assign | ast.AnnAssign) -> bool:
    """An assignment calling nothing but numpy/math (``EPS = 1e-9``, ``I = np.eye(3)``)."""
    for sub in ast.walk(node):
        if isinstance(sub, ast.Call):
            f = sub.func
            while isinstance(f, ast.Attribute):
                f = f.value
            if not (isinstance(f, ast.Name) and f.id in {"np", "numpy", "math"}):
                return False
    return True


def import_problems(source: str, allowed: frozenset[str], filename: str) -> list[str]:
    """Reasons to refuse ``source`` before running it: syntax errors and forbidden imports."""
    try:
        tree = ast.parse(source, filename=filename)
    except SyntaxError as exc:
        return [f"line {exc.lineno}: {exc.msg} (Python cannot read the file)"]
    ok = (sys.stdlib_module_names - BLOCKED_STDLIB) | allowed
    problems = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            stmts = [(a.name, f"import {a.name}") for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            stmts = [(node.module, f"from {node.module} import ...")]
        else:
            continue
        for name, stmt in stmts:
            top = name.partition(".")[0]
            if top not in ok:
                why = WHY_NOT.get(top, "use numpy and the Python standard library only")
                problems.append(f"line {node.lineno}: `{stmt}` is not allowed: {why}")
    return problems
