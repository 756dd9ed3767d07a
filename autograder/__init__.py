"""Autograder: checks a student's implementation against the course's reference.

Students::

    python -m autograder check a1                 # a text report in the terminal
    from autograder import check; check("a1")     # an HTML report in a notebook

Instructors::

    python -m autograder grade --assignment a1 SUBMISSIONS... --out DIR --jobs 2 --seed SECRET

Student code runs only in a separate, limited interpreter (:mod:`autograder.sandbox`); all
comparisons and scores are computed here. An assignment is a spec module plus data
(:mod:`autograder.spec`, :mod:`autograder.assignments`).

Layers, lowest first: the judging core (:mod:`~autograder.judging`, whose one loop over a
test's cases runs on any executor, with the specs, checks, mistake catalogue, wire values,
limits, :mod:`~autograder.results` and :mod:`~autograder.findings`, the one record of what a
result says), which starts no process and which :mod:`course.exercises` uses in the
student's own kernel; the grading run (sandbox, runner); the views of a result (the report,
figures, Gradescope's feedback, the class summary, the LMS exports), which render its
findings and are never imported back; the batch (:mod:`~autograder.batch`, grading, cluster,
Gradescope's runner) and the command line on top. This package loads only the core until
:func:`check` runs.
"""

from __future__ import annotations

import os
from pathlib import Path

from .limits import DEFAULT_LIMITS, Limits
from .results import Result

__all__ = ["Limits", "Result", "check"]


def check(assignment: str, submission: str | Path | None = None, *, seed: str | None = None,
          limits: Limits = DEFAULT_LIMITS, isolation: str | None = None) -> Result:
    """Check a submission of ``assignment`` (``"a1"``, ...) and return its :class:`Result`.

    In a notebook the result shows as an HTML report (with a picture of the first failing
    case); ``print(result)`` gives the text report.

    Parameters
    ----------
    assignment : str
        The assignment's key.
    submission : str or Path, optional
        A ``.py`` or ``.ipynb`` file; default: the assignment's template file in the current
        directory, else in ``assignments/``.
    seed : str, optional
        The instructor's secret seed, which adds the hidden tests (default
        ``$AUTOGRADER_SEED``; students have none and run the visible tests only).
    limits : Limits, optional
        Time and memory limits of the sandbox.
    isolation : str, optional
        The sandbox's isolation level (see :mod:`autograder.sandbox`); default: the strongest
        this machine allows. ``"portable"`` is what Windows gets, and runs anywhere.
    """
    from .assignments import load
    from .report import Report
    from .runner import default_submission, run, seed_from_env
    from .safe_text import printable

    spec = load(assignment)
    path = Path(submission) if submission is not None else default_submission(spec)
    if not os.path.lexists(path):  # a link (even to nothing) is refused in the report
        raise ValueError(f"submission: {printable(path)} does not exist")
    return Report.of(run(spec, path, seed_from_env(seed), limits, isolation))
