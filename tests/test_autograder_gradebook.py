"""The gradebook: LMS exports (Canvas, Moodle, Gradescope CSV) keyed by the student's
identifier, with spreadsheet formulas quoted, and the class summary ``summary.html``."""

from __future__ import annotations

import csv
import json
import os
import re
from pathlib import Path

import pytest

from autograder import Limits
from autograder.assignments import load
from autograder.grading import Submission, collect, grade
from autograder.lms import FILES, export, students
from autograder.summary import summary_html

FIXTURES = Path(__file__).parent / "fixtures" / "a1"
A1 = load("a1")
LIMITS = Limits(cpu_seconds=5, memory_mb=600, load_timeout=5.0, case_timeout=0.5)
HOSTILE = "<img src=x onerror=alert(1)>"


def student_file(folder: Path, fixture: str, extra: str = "") -> None:
    src = (FIXTURES / f"{fixture}.py").read_text()
    if src.startswith("# extends: reference.py"):
        src = (FIXTURES / "reference.py").read_text() + "\n\n" + src
    folder.mkdir(parents=True)
    (folder / "a1_rotations.py").write_text(src + extra)


def metadata(folder: Path, *users: dict) -> None:
    (folder / "submission_metadata.json").write_text(json.dumps({"id": 1, "users": list(users)}))


def read(path: Path) -> list[list[str]]:
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.reader(f))


def row(name: str, score: float) -> dict:
    return {"submission": name, "score": score, "max_score": 24.0}


@pytest.fixture
def graded(tmp_path) -> list[tuple[Submission, dict]]:
    """Three submissions: a plain folder, a Gradescope folder of two users (one with a
    formula for a name), and a file given alone."""
    (tmp_path / "ann").mkdir()
    (tmp_path / "gs_17").mkdir()
    metadata(tmp_path / "gs_17", {"name": "Bo Li", "email": "bo@uni.edu", "sid": "007"},
             {"name": "=HYPERLINK(\"http://x\")", "email": "cy@uni.edu", "sid": "+1"})
    return [(Submission("ann", tmp_path / "ann" / "a.py", folder=tmp_path / "ann"), row("ann", 20)),
            (Submission("gs_17", tmp_path / "gs_17" / "a.py", folder=tmp_path / "gs_17"),
             row("gs_17", 12.5)),
            (Submission("solo", tmp_path / "solo.py"), row("solo", 0.0))]


def test_canvas_export_has_its_columns_points_possible_and_one_row_per_student(graded,
                                                                               tmp_path):
    export("canvas", tmp_path / "c.csv", A1, graded)
    assert read(tmp_path / "c.csv") == [
        ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", "a1 Rotations"],
        ["    Points Possible", "", "", "", "", "24.0"],
        ["ann", "", "", "ann", "", "20"],
        ["Bo Li", "", "007", "bo@uni.edu", "", "12.5"],
        ["'=HYPERLINK(\"http://x\")", "", "'+1", "cy@uni.edu", "", "12.5"],
        ["solo", "", "", "solo", "", "0.0"],
    ]


def test_moodle_and_gradescope_exports_key_by_username_id_number_and_email(graded, tmp_path):
    export("moodle", tmp_path / "m.csv", A1, graded)
    assert read(tmp_path / "m.csv") == [
        ["Username", "ID number", "Email address", "a1 Rotations"],
        ["ann", "", "", "20"], ["", "007", "bo@uni.edu", "12.5"],
        ["", "'+1", "cy@uni.edu", "12.5"], ["solo", "", "", "0.0"]]
    export("gradescope-csv", tmp_path / "g.csv", A1, graded)
    assert read(tmp_path / "g.csv") == [
        ["Name", "SID", "Email", "Total Score", "Max Points"],
        ["ann", "", "", "20", "24.0"], ["Bo Li", "007", "bo@uni.edu", "12.5", "24.0"],
        ["'=HYPERLINK(\"http://x\")", "'+1", "cy@uni.edu", "12.5", "24.0"],
        ["solo", "", "", "0.0", "24.0"]]


def test_one_student_twice_or_unusable_metadata_is_an_error_naming_it(graded, tmp_path):
    metadata(tmp_path / "ann", {"email": "BO@uni.edu"})  # ann's folder claims bo's address
    with pytest.raises(ValueError, match="ann and gs_17 are both graded for the student "
                                         "'bo@uni.edu'"):
        export("canvas", tmp_path / "c.csv", A1, graded)
    metadata(tmp_path / "ann", {"name": "no id"})
    with pytest.raises(ValueError, match=r"users\[0\] has neither an email nor a sid"):
        students(graded[0][0])
    (tmp_path / "ann" / "submission_metadata.json").write_text("{")
    with pytest.raises(ValueError, match="not usable metadata"):
        students(graded[0][0])
    os.unlink(tmp_path / "ann" / "submission_metadata.json")
    os.symlink(tmp_path / "gs_17" / "submission_metadata.json",
               tmp_path / "ann" / "submission_metadata.json")
    with pytest.raises(ValueError, match="symbolic link"):
        students(graded[0][0])
    with pytest.raises(ValueError, match="'blackboard' is not one of"):
        export("blackboard", tmp_path / "b.csv", A1, graded)


@pytest.fixture(scope="module")
def graded_class(tmp_path_factory) -> Path:
    """A small class graded with every export: two students making the same mistake (one
    in a Gradescope folder), one right, one refused with a hostile message."""
    root = tmp_path_factory.mktemp("class")
    subs = root / "subs"
    student_file(subs / "ann", "reference")
    student_file(subs / "bob", "mutant_mul_reversed")
    student_file(subs / "gs_1", "mutant_mul_reversed")
    metadata(subs / "gs_1", {"name": "Cy", "email": "cy@uni.edu", "sid": "42"})
    (subs / "dee & co").mkdir()
    (subs / "dee & co" / "a1_rotations.py").write_text(f"raise ValueError({HOSTILE!r})\n")
    grade(A1, collect([subs], A1), root / "out", seed="gradebook-seed",
          limits=LIMITS, progress=None, lms=list(FILES))
    return root / "out"


def test_grading_a_class_writes_every_export_keyed_by_folder_or_metadata(graded_class):
    canvas = read(graded_class / "grades-canvas.csv")
    assert [r[3] for r in canvas[2:]] == ["ann", "bob", "dee & co", "cy@uni.edu"]
    assert [r[2] for r in canvas[2:]] == ["", "", "", "42"]
    assert [float(r[5]) for r in canvas[2:]][0] == 24
    assert len(read(graded_class / "grades-moodle.csv")) == 5
    assert len(read(graded_class / "grades-gradescope.csv")) == 5
    assert len(read(graded_class / "grades.csv")) == 5  # grades.csv stays as it was


def test_summary_counts_the_class_and_its_mistakes_with_an_example(graded_class):
    page = (graded_class / "summary.html").read_text()
    assert "4 submissions, 3 graded, 1 refused" in page
    assert page.count("data:image/png;base64,") == 3  # histogram, pass rates, mistakes
    mistake = re.search(r"<tr><td><b>([^<]*)</b><br><code>quat_mul:reversed</code></td>"
                        r"<td>[^<]*</td><td>(\d+)</td><td><code>([^<]*)</code>", page)
    assert mistake and mistake.group(2) == "2"  # bob and Cy's group
    example = mistake.group(3)
    assert example.startswith("quat_mul(a = ") and "returned" in example
    assert "bob" not in example and "gs_1" not in example  # anonymised
    rate = re.search(r"<tr><td>quat_mul: random cases</td><td>(\d+) / (\d+)</td>", page)
    assert rate and rate.groups() == ("1", "3")  # only ann's is right


def test_summary_escapes_every_student_string(graded_class):
    page = (graded_class / "summary.html").read_text()
    assert HOSTILE not in page and "&lt;img src=x onerror=alert(1)&gt;" in page
    assert "dee &amp; co" in page and "<script" not in page
    facts = [{"name": HOSTILE, "score": 0.0, "max_score": 24.0, "refused": HOSTILE,
              "tests": {"t": "failed"},
              "mistakes": [{"key": "f:k", "title": HOSTILE, "test": "t", "example": HOSTILE}]}]
    page = summary_html(A1, facts)
    assert HOSTILE not in page and page.count("&lt;img src=x onerror=alert(1)&gt;") == 4
    assert "src='http" not in page and "<link" not in page  # self-contained
