"""The class's totals in the CSV layout a learning-management system imports.

One row per student, keyed by the submission's student identifier: the e-mail address and
student id (SID) of each user named in a Gradescope-style ``submission_metadata.json`` in the
student's folder (a group submission gives each member a row), else the submission's name
(its folder or file name, made safe as in ``grades.csv``). The layouts (documented in
``assignments/README.md``, section "Gradebook exports"):

``canvas``
    Canvas's gradebook import: ``Student, ID, SIS User ID, SIS Login ID, Section`` and one
    column named after the assignment, with a ``Points Possible`` row first. The SID goes
    to ``SIS User ID``, the e-mail (or the submission's name) to ``SIS Login ID``; Canvas
    matches a row by either.
``moodle``
    Moodle's "Import grades from CSV": ``Username, ID number, Email address`` and the
    grade column; map the identifier column you use to the user field of the same name.
``gradescope-csv``
    Gradescope's roster and score layout: ``Name, SID, Email, Total Score, Max Points``.

Every cell is a student's or platform's string, so each goes through
:func:`autograder.output.csv_cell` (a spreadsheet formula is quoted), as in ``grades.csv``.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .output import write_csv
from .safe_text import bounded, printable
from .submission import SubmissionError, read_regular

if TYPE_CHECKING:
    from .records import Submission
    from .spec import Assignment

FILES = {"canvas": "grades-canvas.csv", "moodle": "grades-moodle.csv",
         "gradescope-csv": "grades-gradescope.csv"}
METADATA = "submission_metadata.json"
MAX_METADATA = 256 << 10  # bytes of a metadata file
MAX_ID = 200  # characters of a name, e-mail or SID


@dataclass(frozen=True)
class Student:
    """Who a submission is graded for: ``login`` is the submission's name when no metadata
    names the student."""

    name: str = ""
    email: str = ""
    sid: str = ""
    login: str = ""

    @property
    def key(self) -> str:
        """What tells this student from every other: the e-mail, else the SID, else the
        login."""
        return (self.email.casefold() or self.sid or self.login.casefold())


def students(s: Submission) -> list[Student]:
    """The students of submission ``s`` (see the module's docstring); a ``ValueError``
    naming the file if its metadata is there but unusable."""
    path = s.folder / METADATA if s.folder is not None else None
    if path is None or not os.path.lexists(path):  # a link there is refused when read
        return [Student(login=s.name)]
    try:
        data = json.loads(read_regular(path, MAX_METADATA))
    except (SubmissionError, json.JSONDecodeError) as exc:
        raise ValueError(f"{printable(path)}: not usable metadata ({exc})") from None
    users = data.get("users") if isinstance(data, dict) else None
    if not isinstance(users, list) or not users:
        raise ValueError(f"{printable(path)}: no \"users\" list")
    found = []
    for i, user in enumerate(users):
        fields = {k: _text(user.get(k)) for k in ("name", "email", "sid")} if isinstance(
            user, dict) else {}
        if not (fields.get("email") or fields.get("sid")):
            raise ValueError(f"{printable(path)}: users[{i}] has neither an email nor a sid")
        found.append(Student(**fields))
    return found


def _text(value: Any) -> str:
    """A metadata field as one bounded, printable line ("" if absent)."""
    if value is None:
        return ""
    return bounded(printable(" ".join(str(value).split())), MAX_ID)


def export(kind: str, path: Path, assignment: Assignment,
           graded: list[tuple[Submission, dict[str, Any]]]) -> None:
    """Write ``path`` in ``kind``'s layout (a key of :data:`FILES`) from the submissions and
    their rows of ``grades.csv``. A ``ValueError`` if two rows would be the same student."""
    if kind not in FILES:
        raise ValueError(f"lms: {kind!r} is not one of {', '.join(FILES)}")
    rows: list[tuple[Student, dict[str, Any]]] = []
    owner: dict[str, str] = {}
    for s, row in graded:
        for student in students(s):
            if student.key in owner:
                raise ValueError(f"lms: {printable(owner[student.key])} and {printable(s.name)} "
                                 f"are both graded for the student {student.key!r}: resolve "
                                 "this by hand (an LMS keeps only one of them)")
            owner[student.key] = s.name
            rows.append((student, row))
    column = f"{assignment.key} {assignment.title}"
    maximum = rows[0][1]["max_score"] if rows else 0
    if kind == "canvas":
        header = ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", column]
        lines = [dict.fromkeys(header, "") | {"Student": "    Points Possible", column: maximum}]
        lines += [{"Student": st.name or st.login, "SIS User ID": st.sid,
                   "SIS Login ID": st.email or st.login, column: row["score"]}
                  for st, row in rows]
    elif kind == "moodle":
        header = ["Username", "ID number", "Email address", column]
        lines = [{"Username": st.login, "ID number": st.sid, "Email address": st.email,
                  column: row["score"]} for st, row in rows]
    else:
        header = ["Name", "SID", "Email", "Total Score", "Max Points"]
        lines = [{"Name": st.name or st.login, "SID": st.sid, "Email": st.email,
                  "Total Score": row["score"], "Max Points": row["max_score"]}
                 for st, row in rows]
    write_csv(path, header, lines)
