"""The exercises by name: ``"02.fk_step"`` is exercise ``fk_step`` of ``nb02.py``, loaded on
first use."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any

from .spec import Exercise

#: The notebooks with exercises, by number (``nb02.py`` for ``"02"``).
NOTEBOOKS = ("01", "02", "03", "04", "05", "06", "07", "08", "09", "10", "11", "12", "13", "14",
             "15", "16")


def exercises(notebook: str) -> tuple[Exercise, ...]:
    """The exercises of notebook ``notebook`` (``"02"``), in the order they appear."""
    if notebook not in NOTEBOOKS:
        raise KeyError(f"notebook {notebook!r} has no exercises; these do: {', '.join(NOTEBOOKS)}")
    module = importlib.import_module(f"course.exercises.nb{notebook}")
    found: tuple[Exercise, ...] = module.EXERCISES
    return found


class UnknownExercise(KeyError):
    """No exercise has that name (its message is shown as written, not quoted as a key)."""

    def __str__(self) -> str:
        return str(self.args[0])


def exercise(key: str) -> Exercise:
    """The exercise ``key``, ``"<notebook>.<name>"`` (``"02.fk_step"``)."""
    if not isinstance(key, str):
        raise TypeError(f"an exercise is named by a string such as '02.fk_step', "
                        f"got {type(key).__name__}")
    notebook, _, name = key.partition(".")
    found = {e.key: e for e in exercises(notebook)} if notebook in NOTEBOOKS else {}
    if name not in found:
        known = (f"notebook {notebook} has {', '.join(f'{notebook}.{k}' for k in found)}"
                 if found else "the exercises are " + ", ".join(
                     f"{nb}.{e.key}" for nb in NOTEBOOKS for e in exercises(nb)))
        raise UnknownExercise(f"no exercise {key!r}; {known}")
    return found[name]


def reference(key: str) -> Callable[..., Any]:
    """The reference solution of exercise ``key`` (a function of ``course``)."""
    return exercise(key).function.reference
