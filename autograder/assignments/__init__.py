"""The assignments the autograder knows: one spec module per assignment (``a1.py``, ...).

Each module defines ``ASSIGNMENT``, an :class:`autograder.spec.Assignment`. Adding an
assignment is adding a module here and its key to :data:`KEYS`.
"""

from __future__ import annotations

from importlib import import_module

from ..spec import Assignment

KEYS = ("a1", "a2", "a3")


def load(key: str) -> Assignment:
    """The spec of assignment ``key`` (``"a1"``, ...); ``ValueError`` if there is none."""
    if key not in KEYS:
        raise ValueError(f"assignment: unknown {key!r}; known: {', '.join(KEYS)}")
    return import_module(f"{__name__}.{key}").ASSIGNMENT
