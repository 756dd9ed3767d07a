"""What an exercise is: the function the student writes (an autograder
:class:`~autograder.spec.Function`, with its reference and its check), its visible cases, its
known mistakes and two hints. Each ``nbNN.py`` lists its notebook's exercises with it."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from autograder.spec import Case, Function, Misconception


@dataclass(frozen=True)
class Exercise:
    """One exercise: ``key`` (``"fk_step"``; the notebook's number makes ``"02.fk_step"``),
    the ``function`` the student writes (its ``reference`` is the solution), its visible
    ``cases(rng)``, its known ``mistakes`` and two hints: a nudge, then the formula."""

    key: str
    function: Function
    cases: Callable[[np.random.Generator], Sequence[Case]]
    hint: str
    formula: str
    mistakes: tuple[Misconception, ...] = ()
