"""What the batch keeps of a graded submission: plain data rendered from its record, the
:class:`~autograder.findings.Findings` built once from its
:class:`~autograder.results.Result` (Gradescope's results.json, its row of ``grades.csv``,
the facts of the class summary). The local pool and a cluster's worker (which sends it back)
build it here; ``--resume`` reads it again from ``grading.json``.
"""

from __future__ import annotations

from typing import Any

from .findings import Findings
from .gradescope_json import results_json
from .report import csv_header, csv_row
from .results import Result
from .summary import facts


def record(name: str, result: Result, digest: str = "") -> dict[str, Any]:
    """What the batch keeps of a graded submission, as plain data (a cluster's worker sends
    it back): its ``results.json``, its row and header of ``grades.csv``, the facts the
    class summary needs, and the digest of what was graded ("" for nothing to resume: a
    submission not graded is graded again by ``--resume``)."""
    found = Findings.of(result)
    return {"results": results_json(found, f"Graded {found.path.name}."),
            "row": csv_row(name, found), "header": csv_header(found),
            "facts": facts(name, found), "digest": "" if found.not_graded else digest}
