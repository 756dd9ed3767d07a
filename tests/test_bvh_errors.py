"""Malformed BVH: one file per kind of error, each refused with its line number and problem."""

from __future__ import annotations

import pickle

import pytest

from course.bvh import BVHError, load_bvh, parse_bvh

# A valid file; every case below breaks one thing in it. Line numbers are 1-based.
GOOD = """HIERARCHY
ROOT Hips
{
\tOFFSET 0 0 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
\tJOINT Chest
\t{
\t\tOFFSET 0 5 0
\t\tCHANNELS 3 Zrotation Yrotation Xrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 2 0
\t\t}
\t}
}
MOTION
Frames: 2
Frame Time: 0.5
1 2 3 10 20 30 40 50 60
4 5 6 11 21 31 41 51 61
"""


def broken(line: int, new: str | None) -> str:
    """GOOD with line ``line`` replaced by ``new`` (removed if None)."""
    lines = GOOD.splitlines()
    lines[line - 1 : line] = [] if new is None else [new]
    return "\n".join(lines) + "\n"


# name: (text, line of the error, phrase in the message)
CASES = {
    "missing closing brace": (broken(14, None), 15, "unbalanced braces"),
    "extra closing brace": (broken(14, "\t}\n}"), 16, "unbalanced braces: '}' without"),
    "file ends inside the hierarchy": (GOOD.split("\t}\n}")[0], 13, "unbalanced braces"),
    "no brace after joint": (broken(7, "\tOFFSET 0 5 0"), 7, "expected '{' to open joint 'Chest'"),
    "unknown keyword": (broken(8, "\t\tOFSET 0 5 0"), 8, "unknown keyword 'OFSET'"),
    "misspelt End Site": (broken(10, "\t\tEnd Sight"), 10, "expected 'End Site'"),
    "channel count does not match the names": (
        broken(9, "\t\tCHANNELS 3 Zrotation Yrotation"),
        9,
        "declares 3 channels but names 2",
    ),
    "channel count not a number": (
        broken(9, "\t\tCHANNELS three Zrotation Yrotation Xrotation"),
        9,
        "'three' is not a whole number",
    ),
    "bad channel name": (
        broken(9, "\t\tCHANNELS 3 Zrotation Yrot Xrotation"),
        9,
        "bad channel name 'Yrot'",
    ),
    "repeated channel": (
        broken(9, "\t\tCHANNELS 3 Zrotation Zrotation Xrotation"),
        9,
        "channel Zrotation repeated",
    ),
    "OFFSET with two numbers": (broken(8, "\t\tOFFSET 0 5"), 8, "needs 3 numbers, found 2"),
    "OFFSET not numbers": (broken(8, "\t\tOFFSET 0 five 0"), 8, "is not three numbers"),
    "joint without OFFSET": (broken(8, None), 13, "joint 'Chest' has no OFFSET"),
    "joint without a name": (broken(6, "\tJOINT"), 6, "JOINT without a name"),
    "duplicate joint name": (broken(6, "\tJOINT Hips"), 6, "duplicate joint name 'Hips'"),
    "second ROOT": (GOOD.replace("MOTION", "ROOT Again\n{\n}\nMOTION"), 16, "a second ROOT"),
    "no HIERARCHY": (broken(1, None), 1, "expected HIERARCHY"),
    "empty file": ("", 1, "empty file"),
    "missing MOTION": (GOOD.split("MOTION")[0], 15, "missing MOTION section"),
    "missing Frames": (broken(17, None), 17, "expected 'Frames: <count>'"),
    "Frames not a number": (broken(17, "Frames: many"), 17, "'many' is not a whole number"),
    "missing Frame Time": (broken(18, None), 18, "expected 'Frame Time: <seconds>'"),
    "file ends after MOTION": (GOOD.split("Frames")[0], 16, "missing 'Frames:' line"),
    "zero Frame Time": (broken(18, "Frame Time: 0"), 18, "not a positive number of seconds"),
    "frame with too few values": (
        broken(20, "4 5 6 11 21 31 41 51"), 20, "frame 1 has 8 values, expected 9"
    ),
    "frame with too many values": (
        broken(19, "1 2 3 10 20 30 40 50 60 70"), 19, "frame 0 has 10 values, expected 9"
    ),
    "non-numeric value": (broken(20, "4 5 6 11 21 x31 41 51 61"), 20, "'x31' is not a number"),
    "not a finite value": (broken(19, "1 2 3 10 nan 30 40 50 60"), 19, "'nan' is not a finite"),
    "fewer frame lines than declared": (
        broken(17, "Frames: 5"), 20, "fewer frame lines than declared: 'Frames:' says 5"
    ),
}


def test_the_good_file_is_good():
    assert parse_bvh(GOOD).n_frames == 2


@pytest.mark.parametrize("case", CASES)
def test_error_names_file_line_and_problem(case, tmp_path):
    text, line, phrase = CASES[case]
    file = tmp_path / "broken.bvh"
    file.write_text(text)
    with pytest.raises(BVHError) as caught:
        load_bvh(file)
    error = caught.value
    assert isinstance(error, ValueError)
    assert error.path == str(file)
    assert error.line == line
    assert phrase in error.problem
    assert str(error) == f"{file}, line {line}: {error.problem}"


@pytest.mark.parametrize("case", ["missing closing brace", "bad channel name", "non-numeric value"])
def test_parse_errors_name_the_source(case):
    text, line, _ = CASES[case]
    with pytest.raises(BVHError, match=rf"^<lesson>, line {line}: "):
        parse_bvh(text, source="<lesson>")


def test_crlf_does_not_change_line_numbers(tmp_path):
    text, line, phrase = CASES["non-numeric value"]
    file = tmp_path / "crlf.bvh"
    file.write_bytes(text.replace("\n", "\r\n").encode())
    with pytest.raises(BVHError, match=phrase) as caught:
        load_bvh(file)
    assert caught.value.line == line


def test_error_survives_pickling():
    text, line, _ = CASES["bad channel name"]
    with pytest.raises(BVHError) as caught:
        parse_bvh(text, source="clip.bvh")
    copy = pickle.loads(pickle.dumps(caught.value))
    assert (copy.path, copy.line, copy.problem, str(copy)) == (
        "clip.bvh", line, caught.value.problem, str(caught.value)
    )
