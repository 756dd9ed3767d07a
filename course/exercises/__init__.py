"""Exercises inside the lecture notebooks 练习: write a few lines, check them at once.

A notebook cell marked ``# ✏️ Exercise 2.1`` holds a function with ``...`` for a body; the
cell below checks it::

    from course.exercises import check, hint, quiz
    check("02.fk_step", child_position)

:func:`check` calls the student's function on the exercise's visible cases, in the student's
own kernel, and judges every answer with the autograder's engine (equivalence-aware
comparisons, the catalogue of known mistakes), so a scalar-last quaternion or a transposed
matrix is named just as in the assignments. While the body is still ``...`` (or raises
``NotImplementedError``) it says "not yet", so "Run All" never breaks. :func:`hint` gives a
button that reveals a hint, then the formula, never the answer; :func:`quiz` asks a question
with a few choices before an experiment and reveals the answer only once one is chosen.

Each notebook's exercises live in ``nbNN.py`` (``nb02`` for notebook 02), each with its
reference solution, a function of ``course``; :func:`reference` returns it (the tests run
every check against it). Nothing heavy is imported here: the autograder's judging core and
ipywidgets load on first use, and no part of its grading run (sandbox, processes) ever does.
"""

from __future__ import annotations

from .check import Feedback, check
from .hints import hint
from .quiz import quiz
from .registry import exercise, exercises, reference
from .spec import Exercise

__all__ = ["Exercise", "Feedback", "check", "exercise", "exercises", "hint", "quiz", "reference"]
