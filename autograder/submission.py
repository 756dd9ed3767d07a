"""Read a submission (``.py`` or ``.ipynb``) and check its imports before anything runs.

A ``.py`` file is taken as it is. From a notebook the grader keeps what a module would
define and nothing that shows, prints or calls the student's functions:

* function and class definitions, and imports of numpy and the standard library;
* top-level code that only builds data: assignments, ``for`` loops, ``if`` blocks and method
  calls on data already kept (``TABLE.append(...)``), calling nothing but numpy, ``math``,
  imported functions and builtins such as ``range``, ``zip`` or ``dict``, and reading only
  names kept before them (a table filled by a loop is kept; a plot, a ``print``, a call of
  your own functions or anything built from dropped code is not);
* cell magics: the body of ``%%time`` and ``%%capture`` cells (Python that IPython runs in the
  notebook's namespace) is read as a cell of its own; every other cell magic (``%%timeit``,
  ``%%writefile``, ``%%bash``, ...) drops its whole cell, whose body is not plain Python in
  the notebook's namespace; line magics (``%``), shell escapes (``!``) and help (``?``) are
  blanked, but only in a cell that would not parse otherwise;
* imports of display libraries (matplotlib, ipywidgets, pyvista, ``course.viz``, ...) are
  dropped; an import the assignment forbids (``course``, ``scipy``) is dropped too when only
  display code uses it, and refused when kept code does;
* a notebook importing its own template module (``import a1_rotations as mine``, as the
  assignment notebooks do) is graded on that file beside it, followed by the notebook's own
  definitions.

What was dropped that kept code needs, and what was graded instead, is reported as notes;
refusals and errors name the cell and the line (``cell 3, line 4``). The static check then
refuses imports of anything but numpy and the harmless standard library, with the place and
a reason; the sandbox enforces the same rule at run time for code that hides its imports.

Only regular files are read, up to a size (:data:`MAX_BYTES`): a link could point at the
reference or a system file, a named pipe or device could hang the grader. Whatever a file or
notebook holds, what goes wrong is a :class:`SubmissionError` that says what and where.
"""

from __future__ import annotations

import ast
import builtins
import errno
import json
import os
import stat
import threading
from dataclasses import dataclass, field
from pathlib import Path

from .child import ALLOWED_STDLIB
from .safe_text import printable

# Imported by notebooks to show things, never needed by the functions themselves.
DISPLAY_MODULES = frozenset({"matplotlib", "IPython", "ipywidgets", "pyvista", "autograder",
                             "course.viz", "mpl_toolkits"})
WHY_NOT = {
    "course": "the course library is the reference you are compared with",
    "autograder": "the autograder is not part of a solution",
    "scipy": "the assignment asks you to implement the math yourself with numpy",
    **dict.fromkeys(("ctypes", "cffi", "tkinter", "_tkinter", "subprocess", "multiprocessing",
                     "socket", "code", "pdb"),
                    "the grader runs no native code, other programs or other interpreters: "
                    "use numpy and the Python standard library only"),
}
# Cell magics whose body IPython runs as Python in the notebook's namespace.
PYTHON_CELL_MAGICS = frozenset({"time", "capture"})
# Builtins top-level data code may call: they build values and show nothing.
DATA_BUILTINS = frozenset({
    "abs", "all", "any", "bool", "bytes", "chr", "complex", "dict", "divmod", "enumerate",
    "filter", "float", "frozenset", "int", "isinstance", "iter", "len", "list", "map", "max",
    "min", "next", "ord", "pow", "range", "repr", "reversed", "round", "set", "slice",
    "sorted", "str", "sum", "tuple", "zip",
})
BUILTIN_NAMES = frozenset(dir(builtins))
# Far beyond any honest solution; bounds what the grader reads, parses and reports.
MAX_BYTES = {".py": 1 << 20, ".ipynb": 5 << 20}
# Not regular files, as a message names them.
KINDS = ((stat.S_ISLNK, "a symbolic link"), (stat.S_ISDIR, "a folder"),
         (stat.S_ISFIFO, "a named pipe (FIFO)"), (stat.S_ISSOCK, "a socket"),
         (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"))
# O_NOFOLLOW: a link is refused by the open itself; O_NONBLOCK: a FIFO opens at once, unread.
# Windows has neither (nor FIFOs); its rare links are caught by the lstat before the open.
READ_FLAGS = (os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
              | getattr(os, "O_BINARY", 0))
JSON_TYPES = {dict: "an object", list: "a list", str: "a string", int: "a number",
              float: "a number", bool: "true or false", type(None): "null"}


class SubmissionError(ValueError):
    """The submission cannot be read (not UTF-8, not a notebook, ...)."""


def _kind(mode: int) -> str:
    return next((name for test, name in KINDS if test(mode)), "not a regular file")


def read_regular(path: Path, limit: int | None = None) -> str:
    """The UTF-8 text of ``path`` if it is a regular file of at most ``limit`` bytes (default:
    :data:`MAX_BYTES` for its suffix); else a :class:`SubmissionError` saying what it is.

    The type is checked on the opened descriptor (``fstat``), so nothing can be swapped in
    between the check and the read; the ``lstat`` before only names what is refused.
    """
    shown = printable(path)
    limit = limit or MAX_BYTES.get(path.suffix, MAX_BYTES[".py"])
    try:
        mode = os.lstat(path).st_mode
        if not stat.S_ISREG(mode):
            raise SubmissionError(f"{shown} is {_kind(mode)}: only regular files are graded")
        fd = os.open(path, READ_FLAGS)
    except OSError as exc:
        if exc.errno == errno.ELOOP:  # became a link after the lstat
            raise SubmissionError(f"{shown} is a symbolic link: only regular files are "
                                  "graded") from None
        raise SubmissionError(f"cannot read {shown}: {exc.strerror}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise SubmissionError(f"{shown} is {_kind(st.st_mode)}: only regular files are "
                                  "graded")
        chunks, size = [], 0
        while size <= limit and st.st_size <= limit:  # read one byte past the limit at most
            chunk = os.read(fd, min(1 << 20, limit + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except OSError as exc:
        raise SubmissionError(f"cannot read {shown}: {exc.strerror}") from None
    finally:
        os.close(fd)
    if st.st_size > limit or size > limit:
        raise SubmissionError(f"{shown} is larger than {_size(limit)}, the limit for a "
                              f"{path.suffix or 'submitted'} file")
    try:
        return b"".join(chunks).decode("utf-8-sig")  # a BOM is not part of the text
    except UnicodeDecodeError as exc:
        raise SubmissionError(f"{printable(path.name)} is not a UTF-8 text file (byte "
                              f"{exc.start} is 0x{exc.object[exc.start]:02x})") from None


def _size(n: int) -> str:
    return f"{n >> 20} MiB" if n >= 1 << 20 and not n % (1 << 20) else f"{n} bytes"


@dataclass(frozen=True)
class Source:
    """A submission's Python source, where its lines came from, and notes on what the grader
    made of it (for a notebook: what it dropped that kept code needs).

    ``origins`` are ``(first line in text, place, first line there)``, in order; a line
    outside every origin is the file's own.
    """

    text: str
    origins: tuple[tuple[int, str, int], ...] = ()
    notes: tuple[str, ...] = ()

    def locate(self, line: int) -> str:
        """``"line 12"``, or ``"cell 3, line 4"`` for a line taken from a notebook."""
        for start, place, first in reversed(self.origins):
            if line >= start:
                return f"{place}, line {line - start + first}"
        return f"line {line}"


def read_source(path: Path, allowed: frozenset[str] = frozenset({"numpy"}),
                template: str | None = None, functions: frozenset[str] | None = None) -> Source:
    """The Python source of a ``.py`` file, or what is kept of a notebook (see the module's
    docstring); ``template`` is the assignment's file name (``a1_rotations.py``), which a
    notebook may import, and ``functions`` the names the grader calls."""
    text = read_regular(path)
    if path.suffix == ".ipynb":
        return source_from_notebook(text, printable(path.name), allowed,
                                    path.parent / template if template else None, functions)
    return Source(text)


@dataclass
class _Statement:
    node: ast.stmt
    code: str
    cell: int
    line: int  # of the statement's first line within its cell
    keep: bool = False
    why: str = ""  # why it was dropped, for the notes


@dataclass
class _Extraction:
    allowed: frozenset[str]
    template_module: str | None
    functions: frozenset[str] | None
    statements: list[_Statement] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    imports_template: bool = False


def source_from_notebook(text: str, name: str = "notebook",
                         allowed: frozenset[str] = frozenset({"numpy"}),
                         paired: Path | None = None,
                         functions: frozenset[str] | None = None) -> Source:
    """The definitions of a notebook (see the module's docstring) as one source. ``paired``
    is the template file beside the notebook, graded first if the notebook imports it;
    ``functions`` are the names the grader calls (None: every function may be)."""
    ex = _Extraction(allowed | ALLOWED_STDLIB,
                     paired.stem if paired else None, functions)
    for number, src in _code_cells(text, name):
        _read_cell(ex, src, number)
    _choose(ex)
    parts: list[str] = []
    origins: list[tuple[int, str, int]] = []
    line = 1
    if ex.imports_template:
        assert paired is not None
        if not os.path.lexists(paired):  # a link or pipe there is refused by read_regular
            raise SubmissionError(f"{name} imports {paired.stem}, but {paired.name} is not "
                                  "beside it: submit that file (with the notebook or alone)")
        module = read_regular(paired).rstrip("\n") + "\n"
        parts.append(module)
        origins.append((1, paired.name, 1))
        line += module.count("\n") + 1
        ex.notes.insert(0, f"{name} imports {paired.stem}: graded {paired.name} beside it, "
                           "then the notebook's own definitions")
    for s in ex.statements:
        if s.keep:
            parts.append(s.code + "\n")
            origins.append((line, f"cell {s.cell}", s.line))
            line += s.code.count("\n") + 2
    return Source("\n".join(parts), tuple(origins), tuple(ex.notes))


def _code_cells(text: str, name: str) -> list[tuple[int, str]]:
    """``(number, source)`` of each code cell of a notebook's JSON, numbered among all its
    cells; anything malformed is a :class:`SubmissionError` naming the cell."""
    not_nb = f"{name} is not a Jupyter notebook"
    try:
        nb = json.loads(text)
    except json.JSONDecodeError as exc:
        raise SubmissionError(f"{not_nb}: its JSON is broken at line {exc.lineno}, column "
                              f"{exc.colno} ({exc.msg})") from None
    except RecursionError:
        raise SubmissionError(f"{not_nb}: its JSON is nested too deeply") from None
    except ValueError:  # an integer of more digits than Python converts
        raise SubmissionError(f"{not_nb}: its JSON holds a number too long to read") from None
    if not isinstance(nb, dict):
        raise SubmissionError(f"{not_nb}: its JSON is {_json_type(nb)}, not an object with "
                              "\"cells\"")
    cells = nb.get("cells")
    if not isinstance(cells, list):
        raise SubmissionError(f"{not_nb}: its \"cells\" are {_json_type(cells)}, not a list"
                              if "cells" in nb else f"{not_nb}: it has no \"cells\"")
    code = []
    for number, cell in enumerate(cells, start=1):
        if not isinstance(cell, dict):
            raise SubmissionError(f"{name}: cell {number} is {_json_type(cell)}, not an object "
                                  "(is the notebook damaged?)")
        if cell.get("cell_type") != "code":
            continue
        src = cell.get("source", "")
        if isinstance(src, list) and all(isinstance(line, str) for line in src):
            src = "".join(src)
        elif isinstance(src, list):
            odd = next(x for x in src if not isinstance(x, str))
            raise SubmissionError(f"{name}: the source of cell {number} is a list holding "
                                  f"{_json_type(odd)}, not text (a list of strings)")
        elif not isinstance(src, str):
            raise SubmissionError(f"{name}: the source of cell {number} is {_json_type(src)}, "
                                  "not text (a string or a list of strings)")
        try:
            src.encode("utf-8")
        except UnicodeEncodeError as exc:  # a lone surrogate, which JSON's \ud800 spells
            raise SubmissionError(f"{name}: cell {number} holds a character that is not "
                                  f"Unicode text ({exc.object[exc.start]!a})") from None
        code.append((number, src))
    return code


def _json_type(value: object) -> str:
    return JSON_TYPES.get(type(value), type(value).__name__)


#: ast.parse, one thread at a time: CPython keeps the AST builder's recursion depth in the
#: interpreter, not the thread, and two threads grading at once (``--jobs``) can make it raise
#: "SystemError: AST constructor recursion depth mismatch" on a good file (CPython gh-106905)
_PARSING = threading.Lock()


def _parse(code: str, filename: str = "<unknown>") -> ast.Module:
    """``ast.parse``, with every way hostile text breaks the parser as a SyntaxError: null
    bytes (a ValueError before Python 3.12) and nesting deeper than its stack."""
    try:
        with _PARSING:
            return ast.parse(code, filename=filename)
    except SyntaxError:
        raise
    except ValueError as exc:
        raise SyntaxError(str(exc)) from None
    except (RecursionError, MemoryError):
        raise SyntaxError("nested too deeply for Python's parser") from None


def _read_cell(ex: _Extraction, src: str, number: int) -> None:
    """Parse one code cell into statements (IPython syntax set aside), or note why not."""
    lines = src.splitlines()
    first = lines[0].strip() if lines else ""
    offset, why = 0, ""
    if first.startswith("%%"):
        magic = (first[2:].split() or [""])[0]
        if magic not in PYTHON_CELL_MAGICS:
            # Its body is shell, HTML, a file's text, or timed in a namespace of its own.
            why = f"in a %%{magic} cell"
        lines, offset = lines[1:], 1
    code = "\n".join(lines)
    try:
        tree = _parse(code)
    except SyntaxError:
        code = "\n".join("" if _ipython_line(ln) else ln for ln in lines)
        try:
            tree = _parse(code)
        except SyntaxError as exc:
            if not why:
                ex.notes.append(f"cell {number} was skipped: it does not parse (line "
                                f"{(exc.lineno or 1) + offset}: {exc.msg})")
            return
    code_lines = code.splitlines()
    for node in tree.body:
        decorated = getattr(node, "decorator_list", [])
        start = min([node.lineno] + [d.lineno for d in decorated])
        segment = ("\n".join(code_lines[start - 1:node.end_lineno]) if decorated
                   else ast.get_source_segment(code, node, padded=True) or "")
        ex.statements.append(_Statement(node, segment, number, start + offset, why=why))


def _ipython_line(line: str) -> bool:
    """A line magic, shell escape or help request (``%time``, ``!pip``, ``x = !ls``,
    ``np.dot?``), which only IPython understands."""
    s = line.strip()
    if s.startswith(("%", "!", "?")) or (s.endswith("?") and s[:-1].replace(".", "").replace(
            "?", "").isidentifier()):
        return True
    target, eq, value = s.partition("=")
    return bool(eq) and target.strip().isidentifier() and value.strip().startswith(("!", "%"))


def _choose(ex: _Extraction) -> None:
    """Decide which statements to keep, in order: each may use only what came before."""
    bound: set[str] = set()  # names kept code defines
    callable_: set[str] = set()  # names kept imports and data define: safe to call
    forbidden: list[tuple[_Statement, set[str], str]] = []
    for s in ex.statements:
        node = s.node
        if s.why:  # in a cell magic that is not Python
            continue
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            modules = _imported_modules(node)
            names = _bound_by_import(node)
            if ex.template_module and ex.template_module in modules:
                ex.imports_template = True
            elif all(_display(m) for m in modules):
                pass
            elif any(m.partition(".")[0] not in ex.allowed for m in modules):
                forbidden.append((s, names, next(
                    m for m in modules if m.partition(".")[0] not in ex.allowed)))
            else:
                s.keep = True
                bound |= names
                callable_ |= names
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            s.keep = True
            bound.add(node.name)
        elif _builds_data(node, bound, callable_):
            s.keep = True
            stored = _stored(node)
            bound |= stored
            callable_ |= stored
        else:
            s.why = "display code"
    used = _needed(ex)
    for s, names, module in forbidden:
        if names & used:  # kept code needs it: keep it, so the static check refuses it
            s.keep = True
        else:
            why = WHY_NOT.get(module.partition(".")[0], "it is not allowed in a solution")
            ex.notes.append(f"cell {s.cell}, line {s.line}: `{_first_line(s.code)}` is "
                            f"ignored: only display code uses it ({why})")
    kept_names = bound | set().union(*(_bound_by_import(s.node) for s, _, _ in forbidden
                                       if s.keep))
    for s in ex.statements:
        if s.keep or not s.why:
            continue
        lost = sorted((_stored(s.node) | _bound_by_import(s.node)) & (used - kept_names))
        if lost:
            ex.notes.append(
                f"cell {s.cell}, line {s.line}: `{_first_line(s.code)}` was not run by the "
                f"grader ({s.why}: only definitions and data built with numpy, math, imports "
                f"and builtins are kept), but your code uses {', '.join(lost)}")


def _needed(ex: _Extraction) -> set[str]:
    """The names the grader's calls may read: those the graded functions (every kept
    function, if they are not known) and the kept data code read, with the kept functions
    and classes they reach."""
    defs = {s.node.name: s.node for s in ex.statements if s.keep and isinstance(
        s.node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))}
    todo = [s.node for s in ex.statements if s.keep and not isinstance(
        s.node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))]
    todo += [d for n, d in defs.items() if ex.functions is None or n in ex.functions]
    seen: set[int] = set()
    used: set[str] = set()
    while todo:
        node = todo.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        free = _free_names(node)
        used |= free
        todo += [defs[n] for n in free if n in defs]
    return used


def _first_line(code: str, limit: int = 60) -> str:
    line = code.strip().splitlines()[0] if code.strip() else ""
    return line if len(line) <= limit else line[:limit - 3] + "..."


def _display(module: str) -> bool:
    return any(module == d or module.startswith(d + ".") for d in DISPLAY_MODULES)


def _imported_modules(node: ast.Import | ast.ImportFrom) -> list[str]:
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    return [node.module or ""] if node.level == 0 else [""]


def _bound_by_import(node: ast.AST) -> set[str]:
    if not isinstance(node, (ast.Import, ast.ImportFrom)):
        return set()
    return {(a.asname or a.name).partition(".")[0] for a in node.names if a.name != "*"}


def _stored(node: ast.AST) -> set[str]:
    """Names a statement binds (assignment and loop targets, walrus), at any depth."""
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)
            and isinstance(n.ctx, (ast.Store, ast.Del))}


def _free_names(node: ast.AST) -> set[str]:
    """Names a statement reads that it does not bind itself (roughly: a function's locals and
    parameters and a comprehension's variables are its own)."""
    loaded = {n.id for n in ast.walk(node) if isinstance(n, ast.Name)
              and isinstance(n.ctx, ast.Load)}
    own = _stored(node) if not isinstance(node, (ast.Import, ast.ImportFrom)) else set()
    own |= {a.arg for n in ast.walk(node) if isinstance(n, ast.arguments)
            for a in (*n.posonlyargs, *n.args, *n.kwonlyargs, n.vararg, n.kwarg) if a}
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        own.discard(node.name)
    return loaded - own


def _builds_data(node: ast.stmt, bound: set[str], callable_: set[str]) -> bool:
    """Whether a top-level statement only builds data from what is kept (see the module's
    docstring): an assignment, ``for``, ``if`` or a method call on kept data, reading only
    names bound before it."""
    if isinstance(node, (ast.For, ast.If)):
        head = node.iter if isinstance(node, ast.For) else node.test
        if not _only_data(head, bound, callable_):
            return False
        targets = _stored(node.target) if isinstance(node, ast.For) else set()
        for body in (node.body, node.orelse):
            names, calls = bound | targets, set(callable_)
            for stmt in body:
                if not _builds_data(stmt, names, calls):
                    return False
                names |= _stored(stmt)
                calls |= _stored(stmt)
        return True
    if isinstance(node, ast.Expr):
        call = node.value
        return (isinstance(call, ast.Call) and isinstance(call.func, ast.Attribute)
                and _root(call.func) in bound and _only_data(call, bound, callable_))
    if isinstance(node, ast.AugAssign) and not _only_data(node.target, bound, callable_, True):
        return False  # x += 1 reads x
    return isinstance(node, (ast.Assign, ast.AugAssign, ast.AnnAssign)) and _only_data(
        node, bound, callable_)


def _only_data(node: ast.AST, bound: set[str], callable_: set[str],
               stores_read: bool = False) -> bool:
    """Whether an expression (or statement) calls only safe things and reads only bound
    names; a comprehension's own variables count as bound inside it. ``stores_read``: the
    names it stores are read too (an augmented assignment's target)."""
    local = {n.id for c in ast.walk(node) if isinstance(c, ast.comprehension)
             for n in ast.walk(c.target) if isinstance(n, ast.Name)}
    local |= {n.target.id for n in ast.walk(node) if isinstance(n, ast.NamedExpr)}
    for sub in ast.walk(node):
        if isinstance(sub, (ast.Lambda, ast.Await, ast.Yield, ast.YieldFrom)):
            return False
        if isinstance(sub, ast.Call):
            root = _root(sub.func)
            if not (root in callable_ or root in local or root in DATA_BUILTINS
                    or isinstance(root, ast.Constant)):
                return False
        if isinstance(sub, ast.Name) and (stores_read or isinstance(sub.ctx, ast.Load)) and not (
                sub.id in bound or sub.id in local or sub.id in BUILTIN_NAMES):
            return False
    return True


def _root(f: ast.expr) -> str | ast.Constant | None:
    """The name an attribute chain or subscript starts from (``np`` in ``np.linalg.norm``),
    the constant (``"XYZ".index``), or None."""
    while isinstance(f, (ast.Attribute, ast.Subscript, ast.Call)):
        f = f.value if not isinstance(f, ast.Call) else f.func
    if isinstance(f, ast.Name):
        return f.id
    return f if isinstance(f, ast.Constant) else None


def import_problems(source: Source | str, allowed: frozenset[str], filename: str) -> list[str]:
    """Reasons to refuse ``source`` before running it: syntax errors and forbidden imports,
    each with its place (``line 3``, or ``cell 2, line 3`` in a notebook)."""
    if isinstance(source, str):
        source = Source(source)
    try:
        tree = _parse(source.text, filename)
    except SyntaxError as exc:
        return [f"{source.locate(exc.lineno or 1)}: {exc.msg} (Python cannot read the file)"]
    ok = ALLOWED_STDLIB | allowed
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
                problems.append(f"{source.locate(node.lineno)}: `{stmt}` is not allowed: {why}")
    return problems
