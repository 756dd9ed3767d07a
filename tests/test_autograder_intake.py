"""One policy picks the file of a student's folder to grade (:mod:`autograder.intake`): the
local pool, the cluster (both through :func:`autograder.grading.collect`) and Gradescope
(:func:`autograder.gradescope.run.choose`) grade the same upload the same way."""

from __future__ import annotations

from pathlib import Path

import pytest

from autograder.assignments import load
from autograder.gradescope.run import choose
from autograder.grading import collect

A1 = load("a1")
SOLUTION = "def quat_mul(a, b):\n    pass\n\ndef slerp(q0, q1, t):\n    pass\n"
ONE = "def quat_mul(a, b):\n    raise NotImplementedError\n"

#: an upload (relative path -> text) and the file graded, or None for a refusal
UPLOADS: dict[str, tuple[dict[str, str], str | None]] = {
    "the only file, any name": ({"HW1 final.py": ONE}, "HW1 final.py"),
    "the template beside helpers": ({"a1_rotations.py": ONE, "util.py": SOLUTION},
                                    "a1_rotations.py"),
    "the shallowest template": ({"old/a1_rotations.py": SOLUTION, "a1_rotations.ipynb": "{}"},
                                "a1_rotations.ipynb"),
    "the .py template before its notebook": ({"a1_rotations.ipynb": "{}",
                                              "a1_rotations.py": ONE}, "a1_rotations.py"),
    "the file that defines the most": ({"notes.py": "x = 1\n", "helpers/util.py": ONE,
                                        "work/final/mine.py": SOLUTION}, "work/final/mine.py"),
    "two templates equally deep, one defines more": (
        {"v1/a1_rotations.py": ONE, "v2/a1_rotations.py": SOLUTION}, "v2/a1_rotations.py"),
    "a tie: refused": ({"a.py": SOLUTION, "b.py": SOLUTION}, None),
    "none defines anything: refused": ({"a.py": "x = 1\n", "b.py": "y = 2\n"}, None),
    "hidden and junk folders are not the student's": (
        {".ipynb_checkpoints/a1_rotations-checkpoint.py": SOLUTION,
         "__MACOSX/a1_rotations.py": SOLUTION, "mine.py": ONE}, "mine.py"),
}


def upload(folder: Path, files: dict[str, str]) -> Path:
    for rel, text in files.items():
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        (folder / rel).write_text(text)
    return folder


@pytest.mark.parametrize("what", UPLOADS)
def test_the_pool_and_gradescope_grade_the_same_file(what, tmp_path):
    files, expected = UPLOADS[what]
    student = upload(tmp_path / "class" / "ada", files)
    [local] = collect([tmp_path / "class"], A1)
    path, said = choose(student, A1)
    if expected is None:
        assert path is None and local.refused and local.path == student
        assert "cannot tell which one to grade" in local.refused
        assert said.startswith("Your submission has") and "cannot tell which one" in said
    else:
        assert path == local.path == student / expected and not local.refused
        assert said.startswith(f"Graded {expected}")


def test_the_refusal_lists_the_files_and_why(tmp_path):
    student = upload(tmp_path / "ada", {f"f{i}.py": SOLUTION for i in range(5)})
    _, said = choose(student, A1)
    assert said == ("Your submission has no a1_rotations.py but 5 .py/.ipynb files (f0.py, "
                    "f1.py, f2.py and 2 more; 5 of them define 2 of its functions each): cannot "
                    "tell which one to grade: upload one file, or name the one to grade "
                    "a1_rotations.py.")
