"""``docs/architecture.md`` names only modules, files and functions that exist: every dotted
``course.…`` name in backticks resolves (a module, or an attribute of one), every file of its
``course/ik/`` tree is there, and every ``module.name`` it gives for ``course.ik`` (``api.…``,
``_pipeline.…``, ``tree.…``, ``components.…``) is an attribute of that module."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
IK_SECTION = DOC[DOC.index("## `course.ik`"):DOC.index("## `course.viz`")]
IK_MODULES = {"api": "course.ik.api", "_pipeline": "course.ik._pipeline",
              "tree": "course.ik._engine.tree", "components": "course.ik._engine.components",
              "chain": "course.ik._engine.chain", "methods": "course.ik.methods"}


def _resolve(dotted: str) -> object:
    """The module or attribute ``dotted`` names; raises if there is none."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj: object = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError:
            continue
        for attr in parts[cut:]:
            obj = getattr(obj, attr)
        return obj
    raise ModuleNotFoundError(dotted)


DOTTED = sorted(set(re.findall(r"`(course(?:\.\w+)+)", DOC)))
TREE_FILES = re.findall(r"[├└]── (\S+\.py|\S+/)", IK_SECTION)
_NAMES = "|".join(map(re.escape, IK_MODULES))
SHORT = sorted(set(re.findall(rf"`((?:{_NAMES})\.(?!py`)\w+)", IK_SECTION)))


def test_the_doc_names_something():
    assert len(DOTTED) >= 5 and len(TREE_FILES) >= 15 and len(SHORT) >= 4


@pytest.mark.parametrize("dotted", DOTTED)
def test_every_dotted_name_exists(dotted):
    _resolve(dotted)


def test_every_file_of_the_ik_tree_exists():
    folder, missing = ROOT / "course" / "ik", []
    for name in TREE_FILES:
        if name == "_engine/":
            folder = ROOT / "course" / "ik" / "_engine"
            continue
        if not (folder / name).exists() and not (ROOT / "course" / "ik" / name).exists():
            missing.append(name)
    assert not missing


def test_every_file_of_course_ik_is_in_the_tree():
    files = {p.name for p in (ROOT / "course" / "ik").rglob("*.py")}
    assert files <= set(TREE_FILES) | {"__init__.py"}, files - set(TREE_FILES)


@pytest.mark.parametrize("name", SHORT)
def test_every_module_function_named_in_the_ik_section_exists(name):
    module, attr = name.split(".", 1)
    _resolve(f"{IK_MODULES[module]}.{attr}")
