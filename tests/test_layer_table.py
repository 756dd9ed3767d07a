"""The layer tables of ``docs/architecture.md`` are the rules: written once there, asserted here.

``course``'s table (the diagram under "## Layers") lists its modules top down, a row of
``│`` between two layers; every import inside ``course`` goes up the table or stays in its
row. ``autograder``'s tree lists its files under four numbered layers, lowest first; every
import inside ``autograder`` goes to its own layer or a lower one. A module neither table
names fails, so the tables cannot fall behind the code.
"""

from __future__ import annotations

import re
from functools import cache

from test_layers import ROOT, Import, project_graph

DOC = ROOT / "docs" / "architecture.md"


def _block(heading: str) -> list[str]:
    """The lines of the first fenced block after ``heading``."""
    text = DOC.read_text(encoding="utf-8")
    start = text.index(heading)
    body = text[text.index("```", start) + 3:]
    return body[body.index("\n") + 1:body.index("```")].splitlines()


@cache
def course_layers() -> dict[str, int]:
    """``course.x`` -> its row in the table (0 the top)."""
    layer, out, on_row = 0, {}, False
    for line in _block("## Layers"):
        if line.startswith("course"):
            for name in re.findall(r"course(?:\.\w+)+", line):
                out.setdefault(name, layer)
            on_row = True
        elif line.lstrip().startswith("│") and on_row:
            layer, on_row = layer + 1, False
    return out


@cache
def autograder_layers() -> dict[str, int]:
    """``autograder.x`` (a module, or a folder's prefix ``autograder.x.``) -> its layer."""
    layer, out = 0, {}
    for line in _block("## `autograder/`"):
        heading = re.match(r"│\s+(\d)\.", line)
        if heading:
            layer = int(heading.group(1))
            continue
        if not layer:
            continue
        for folder in re.findall(r"(?:├──|└──)\s+(\w+)/", line):
            out[f"autograder.{folder}."] = layer
        for file in re.findall(r"\b(\w+)\.py\b", line):
            out.setdefault(f"autograder.{file}", layer)
    return out


def layer_of(module: str, table: dict[str, int]) -> int | None:
    """The layer of ``module``: its own entry, else its longest listed package or folder."""
    best = None
    for name, layer in table.items():
        inside = module == name.rstrip(".") or module.startswith(
            name if name.endswith(".") else name + ".")
        if inside and (best is None or len(name) > len(best[0])):
            best = (name, layer)
    return None if best is None else best[1]


def _unlisted(package: str, table: dict[str, int]) -> list[str]:
    return sorted(m for m in project_graph() if m.partition(".")[0] == package
                  and m != package and layer_of(m, table) is None)


def _upward(package: str, table: dict[str, int]) -> list[Import]:
    """Imports inside ``package`` to a higher layer than their own."""
    bad = []
    for imports_ in project_graph().values():
        for imp in imports_:
            if not (imp.source.startswith(package + ".") and imp.target.startswith(package)):
                continue
            src, dst = layer_of(imp.source, table), layer_of(imp.target, table)
            if src is not None and dst is not None and dst > src:
                bad.append(imp)
    return bad


def _show(bad: list[Import], table: dict[str, int]) -> str:
    return "\n".join(f"  {i.source} (layer {layer_of(i.source, table)}) -> {i.target} "
                     f"(layer {layer_of(i.target, table)})  {i.where()}" for i in bad)


def test_every_module_is_in_its_table() -> None:
    assert not _unlisted("course", course_layers()), (
        "not in docs/architecture.md's course table: " + ", ".join(
            _unlisted("course", course_layers())))
    assert not _unlisted("autograder", autograder_layers()), (
        "not in docs/architecture.md's autograder tree: " + ", ".join(
            _unlisted("autograder", autograder_layers())))


def test_course_imports_only_up_its_table() -> None:
    table = course_layers()
    assert len(set(table.values())) >= 6, table  # the table was read, row by row
    bad = _upward("course", table)
    assert not bad, "imports down course's table:\n" + _show(bad, table)


def test_autograder_imports_only_its_own_layer_or_lower() -> None:
    table = autograder_layers()
    assert set(table.values()) == {1, 2, 3, 4}, table
    bad = _upward("autograder", table)
    assert not bad, "imports up autograder's layers:\n" + _show(bad, table)


def test_the_tables_are_read_as_written() -> None:
    """Spot checks that the parser reads the rows it should."""
    c, a = course_layers(), autograder_layers()
    assert c["course._validate"] == c["course._typing"] < c["course.rotations"]
    assert c["course.skeleton"] == c["course.fk"] < c["course.motion"] == c["course.bvh"]
    assert c["course.ik"] < c["course.physics"] < c["course.exercises"] < c["course.viz"]
    assert a["autograder.judging"] == 1 and a["autograder.seccomp"] == 2
    assert a["autograder.gradescope_json"] == 3 and a["autograder.cli"] == 4
    assert layer_of("autograder.assignments.a5", a) == 1
    assert layer_of("autograder.gradescope.run", a) == 4
