"""The assignments the autograder knows: one spec module per assignment (``a1.py``, ...).

Each module defines ``ASSIGNMENT``, an :class:`autograder.spec.Assignment`. Adding an
assignment is adding a module here and its key to :data:`KEYS`.
"""

from __future__ import annotations

from dataclasses import replace
from functools import cache
from importlib import import_module

from ..catalogue import shared_misconceptions
from ..spec import Assignment

KEYS = ("a1", "a2", "a3", "a4", "a5", "a6", "a7", "a8")


@cache
def load(key: str) -> Assignment:
    """The spec of assignment ``key`` (``"a1"``, ...) with the shared catalogue of mistakes;
    ``ValueError`` if there is none."""
    if key not in KEYS:
        raise ValueError(f"assignment: unknown {key!r}; known: {', '.join(KEYS)}")
    own: Assignment = import_module(f"{__name__}.{key}").ASSIGNMENT
    shared = tuple(m for f in own.functions for m in shared_misconceptions(f))
    return replace(own, shared=shared)
