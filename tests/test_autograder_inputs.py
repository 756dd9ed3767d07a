"""What a class's export can hold besides submissions: links, pipes and devices where files
should be, names that are paths, control characters, bytes or formulas, folders nested too
deep, broken notebook JSON, oversized files and forged messages. Each gets a row with score 0
and the reason; nothing is read that should not be, nothing is written outside ``--out``, and
the batch finishes."""

from __future__ import annotations

import csv
import json
import os
import shutil
import stat
from pathlib import Path

import pytest
from test_autograder_fixtures import FIXTURES, REPO

from autograder.assignments import load
from autograder.cli import main
from autograder.grading import Submission, collect, grade, safe_name, unique
from autograder.intake import MAX_DEPTH
from autograder.output import csv_cell
from autograder.safe_text import MAX_LINE
from autograder.sandbox import Outcome, Sandbox
from autograder.submission import SubmissionError, import_problems, source_from_notebook

pytestmark = pytest.mark.skipif(os.name != "posix", reason="links, FIFOs and byte names")

A1 = load("a1")
SEED = "inputs-seed"
REFERENCE = (FIXTURES / "reference.py").read_text()
SCIPY = "import scipy\n"  # refused before anything runs: a quick row with a known reason
SCIPY_REASON = "line 1: `import scipy` is not allowed"
DEEP = 1200  # folder levels: deeper than Python's recursion limit and than PATH_MAX allows


def write(path: Path | bytes, text: str | bytes) -> None:
    """A file at ``path`` (bytes: a name that is not UTF-8), made with ``os.open``."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
    os.write(fd, text.encode() if isinstance(text, str) else text)
    os.close(fd)


def tree(root: Path, skip: frozenset[str] = frozenset()) -> set[str]:
    """Every path below ``root``, relative, without following links or entering ``skip``
    (a tree too deep for os.walk)."""
    found, stack = set(), [root]
    while stack:
        here = stack.pop()
        for e in os.scandir(here):
            rel = os.path.relpath(e.path, root)
            found.add(rel)
            if e.is_dir(follow_symlinks=False) and rel not in skip:
                stack.append(Path(e.path))
    return found


def make_deep(base: Path, levels: int, text: str) -> None:
    """``base/d/d/.../d/x.py``: each level made relative to the last one's descriptor (the
    whole path is longer than the system takes)."""
    base.mkdir()
    fd = os.open(base, os.O_RDONLY)
    for _ in range(levels):
        os.mkdir("d", dir_fd=fd)
        inner = os.open("d", os.O_RDONLY, dir_fd=fd)
        os.close(fd)
        fd = inner
    out = os.open("x.py", os.O_WRONLY | os.O_CREAT, 0o644, dir_fd=fd)
    os.write(out, text.encode())
    os.close(out)
    os.close(fd)


def remove_deep(base: Path, levels: int) -> None:
    """Undo :func:`make_deep` level by level (shutil.rmtree recurses: too deep for it)."""
    fd = os.open(base, os.O_RDONLY)
    for _ in range(levels):
        inner = os.open("d", os.O_RDONLY, dir_fd=fd)
        os.close(fd)
        fd = inner
    os.unlink("x.py", dir_fd=fd)
    for _ in range(levels):
        parent = os.open("..", os.O_RDONLY, dir_fd=fd)
        os.close(fd)
        os.rmdir("d", dir_fd=parent)
        fd = parent
    os.close(fd)
    base.rmdir()


def read_rows(out: Path) -> dict[str, dict[str, str]]:
    with open(out / "grades.csv", newline="", encoding="utf-8") as f:
        return {r["submission"]: r for r in csv.DictReader(f)}


# name in grades.csv -> what its reason says (every one scores 0)
HOSTILE = {
    "alice": "subs/alice/a1_rotations.py is a symbolic link: only regular files are graded",
    "passwd": "subs/passwd.py is a symbolic link: only regular files are graded",
    "linked": "subs/linked is a symbolic link: only regular files are graded",
    "fifo": "subs/fifo.py is a named pipe (FIFO): only regular files are graded",
    "socket": "subs/socket.py is a socket: only regular files are graded",
    "direct": "direct.py is a symbolic link: only regular files are graded",
    "pipe": "pipe.py is a named pipe (FIFO): only regular files are graded",
    "null": "/dev/null is a character device: only regular files are graded",
    "deep": f"subs/deep has no a1_rotations.py and could not be searched for one: its folders "
            f"nest deeper than {MAX_DEPTH} levels",
    "big": "subs/big.py is larger than 1 MiB, the limit for a .py file",
    "nb_list": "nb_list.ipynb is not a Jupyter notebook: its JSON is a list, not an object",
    "nb_nested": "nb_nested.ipynb is not a Jupyter notebook: its JSON is nested too deeply",
    "nb_bytes": "nb_bytes.ipynb is not a UTF-8 text file (byte 12 is 0xff)",
    "nb_source": "nb_source.ipynb: the source of cell 2 is a number, not text",
    # names: the files are ordinary (and refused for their import), the names made safe
    "submission": SCIPY_REASON,  # ..py
    "_": SCIPY_REASON,  # ...py
    "hidden": SCIPY_REASON,  # .hidden.py
    "newline": SCIPY_REASON,
    "tabhere": SCIPY_REASON,
    "esc[2Jape": SCIPY_REASON,
    "rtlyp.exe": SCIPY_REASON,  # with U+202E, it showed as "rtlexe.py"
    "caf_xe9": SCIPY_REASON,  # b"caf\xe9.py"
    "grades.csv-2": SCIPY_REASON,  # a student's folder named grades.csv
    "=2+3": SCIPY_REASON,
    "+x": SCIPY_REASON,
    "-x": SCIPY_REASON,
    "@x": SCIPY_REASON,
    # dup/ and dup-2/ (folders) keep their names; dup.py takes the first free one
    "dup": "`import socket` is not allowed",
    "dup-2": "`import ctypes` is not allowed",
    "dup-3": SCIPY_REASON,
}


@pytest.fixture
def hostile_class(tmp_path):
    """A class's folder with every hostile entry, a good submission, and three paths for the
    command line; the 1200-level folder is removed afterwards (it is too deep for rmtree)."""
    subs, elsewhere = tmp_path / "subs", tmp_path / "elsewhere"
    subs.mkdir()
    elsewhere.mkdir()
    write(elsewhere / "a1_rotations.py", REFERENCE)
    write(subs / "good.py", REFERENCE)
    (subs / "alice").mkdir()
    os.symlink(FIXTURES / "reference.py", subs / "alice" / "a1_rotations.py")
    os.symlink("/etc/passwd", subs / "passwd.py")
    os.symlink(elsewhere, subs / "linked")
    os.mkfifo(subs / "fifo.py")
    os.mknod(subs / "socket.py", stat.S_IFSOCK | 0o600)
    write(subs / "big.py", "#" * (1 << 20) + "\n")
    write(subs / "nb_list.ipynb", "[]")
    write(subs / "nb_nested.ipynb", "[" * 100_000)
    write(subs / "nb_bytes.ipynb", b'{"cells": ["\xff"]}')
    write(subs / "nb_source.ipynb", json.dumps({"cells": [
        {"cell_type": "markdown", "source": "# a1"}, {"cell_type": "code", "source": 3}]}))
    for name in ["..py", "...py", ".hidden.py", "new\nline.py", "tab\there.py",
                 "esc\x1b[2Jape.py", "rtl\u202eyp.exe.py", "=2+3.py", "+x.py", "-x.py", "@x.py",
                 "dup.py"]:
        write(subs / name, SCIPY)
    write(os.fsencode(subs) + b"/caf\xe9.py", SCIPY)
    for folder, text in [("dup", "import socket\n"), ("dup-2", "import ctypes\n"),
                         ("grades.csv", SCIPY)]:
        (subs / folder).mkdir()
        write(subs / folder / "a1_rotations.py", text)
    make_deep(subs / "deep", DEEP, REFERENCE)
    os.symlink(FIXTURES / "reference.py", tmp_path / "direct.py")
    os.mkfifo(tmp_path / "pipe.py")
    yield subs, [tmp_path / "direct.py", tmp_path / "pipe.py", Path("/dev/null")]
    remove_deep(subs / "deep", DEEP)


def test_a_hostile_class_is_graded_to_the_end(hostile_class, tmp_path, capsys):
    subs, direct = hostile_class
    before = tree(tmp_path, skip=frozenset({"subs/deep"}))
    out = tmp_path / "out"
    assert main(["grade", "--assignment", "a1", str(subs), *map(str, direct), "--out",
                 str(out), "--jobs", "2", "--seed", SEED]) == 0
    err = capsys.readouterr().err
    assert f"graded {len(HOSTILE) + 1} submissions" in err and "Traceback" not in err

    rows = read_rows(out)
    raw = (out / "grades.csv").read_text(encoding="utf-8")
    names = {n: n if not n.startswith(("=", "+", "-", "@")) else "'" + n for n in HOSTILE}
    assert set(rows) == {"good", *names.values()}
    assert float(rows["good"]["score"]) == 24 and rows["good"]["status"] == "graded"
    for name, reason in HOSTILE.items():
        row = rows[names[name]]
        assert float(row["score"]) == 0 and row["status"] == "refused", name
        assert reason in row["reason"], (name, row["reason"])
        results = json.loads((out / name / "results.json").read_text())
        assert results["score"] == 0 and reason in results["output"]
    assert not any(line.startswith(("=", "+", "-", "@")) for line in raw.splitlines())

    # Nothing was read that should not be: neither the reference nor /etc/passwd is shown.
    written = "".join((out / n / "results.json").read_text() for n in HOSTILE)
    for secret in ["q = np.array(rows[k])", Path("/etc/passwd").read_text().splitlines()[0]]:
        assert secret not in written and secret not in raw
    # Nothing was written outside --out, and inside it only the expected files.
    assert tree(tmp_path, skip=frozenset({"subs/deep"})) - before == {"out"} | {
        f"out/{p}" for p in tree(out)}
    kept = {f"{n}/grading.json" for n in [*HOSTILE, "good"]}  # what --resume reads, if any
    assert tree(out) - kept == {"grades.csv", "summary.html"} | {
        p for n in [*HOSTILE, "good"] for p in (n, f"{n}/results.json")}


@pytest.mark.parametrize(("raw", "safe"), [
    ("..", "_"), (".", "submission"), ("", "submission"), ("../../etc/x", "____etc_x"),
    ("a\\b", "a_b"), (" .hidden. ", "hidden"), ("a..b", "a_b"), ("new\nline\r\t", "newline"),
    ("rtl\u202egnp", "rtlgnp"), ("caf\udce9", "caf_xe9"), ("CON", "_CON"), ("nul.txt", "_nul.txt"),
    ("a:b*c?", "a_b_c_"), ("é" * 150, "é" * 100), ("=2+3", "=2+3"),
])
def test_names_become_one_plain_folder(raw, safe):
    assert safe_name(raw) == safe and safe_name(safe) == safe


def test_names_are_unique_without_taking_another_students():
    subs = [Submission(n, Path(f"{n}.py")) for n in
            ["dup", "dup-2", "dup", "Alice", "alice", "grades.csv", "dup"]]
    names = [s.name for s in unique(subs)]
    assert names == ["dup", "dup-2", "dup-3", "Alice", "alice-2", "grades.csv-2", "dup-4"]
    assert [s.name for s in unique(unique(subs))] == names


def test_collect_follows_no_link_and_passes_over_nothing(tmp_path):
    """A link where a student's file or folder is, is a submission (refused when read), not
    skipped for another file; a folder with several files or cut short says so."""
    subs = tmp_path / "subs"
    (subs / "ann" / "helpers").mkdir(parents=True)
    os.symlink(FIXTURES / "reference.py", subs / "ann" / "a1_rotations.py")
    write(subs / "ann" / "helpers" / "mine.py", REFERENCE)
    (subs / "bob" / ".ipynb_checkpoints").mkdir(parents=True)
    write(subs / "bob" / "work.ipynb", "{}")
    write(subs / "bob" / ".ipynb_checkpoints" / "work-checkpoint.ipynb", "{}")
    (subs / "cy").mkdir()
    write(subs / "cy" / "one.py", "")
    write(subs / "cy" / "two.py", "")
    (subs / "empty").mkdir()
    found = {s.name: s for s in collect([subs], A1)}
    assert set(found) == {"ann", "bob", "cy"}
    assert found["ann"].path == subs / "ann" / "a1_rotations.py" and not found["ann"].refused
    assert found["bob"].path == subs / "bob" / "work.ipynb"
    assert found["cy"].refused == (f"{subs / 'cy'} has no a1_rotations.py but 2 .py/.ipynb "
                                   "files (one.py, two.py; none defines any of its functions): "
                                   "cannot tell which one to grade")
    with pytest.raises(ValueError, match="does not exist"):
        collect([tmp_path / "nothing"], A1)


def test_results_are_never_written_through_a_link_in_out(tmp_path, capsys):
    elsewhere, out = tmp_path / "elsewhere", tmp_path / "out"
    elsewhere.mkdir()
    (out / "carol").mkdir(parents=True)
    os.symlink(elsewhere, out / "alice")
    os.symlink(elsewhere / "results.json", out / "carol" / "results.json")
    write(tmp_path / "s.py", SCIPY)
    rows = grade(A1, [("alice", tmp_path / "s.py"), ("carol", tmp_path / "s.py"),
                      ("../bob", tmp_path / "s.py"), ("/tmp/x", tmp_path / "s.py")], out,
                 progress=None)
    assert [r["submission"] for r in rows] == ["alice", "carol", "__bob", "_tmp_x"]
    assert os.listdir(elsewhere) == [] and not (tmp_path / "bob").exists()
    assert (out / "__bob" / "results.json").exists() and (out / "_tmp_x" / "results.json").exists()
    err = capsys.readouterr().err
    assert "warning: results of alice not written" in err
    assert "warning: results of carol not written" in err

    (out / "grades.csv").unlink()
    os.symlink(elsewhere / "grades.csv", out / "grades.csv")
    assert main(["grade", "--assignment", "a1", str(tmp_path / "s.py"), "--out", str(out)]) == 1
    assert "error: grades.csv not written" in capsys.readouterr().err
    assert os.listdir(elsewhere) == []


# notebook JSON -> what the student is told
NOTEBOOKS = {
    "{": "broken.ipynb is not a Jupyter notebook: its JSON is broken at line 1, column 2 "
         "(Expecting property name enclosed in double quotes)",
    "[]": "broken.ipynb is not a Jupyter notebook: its JSON is a list, not an object with "
          '"cells"',
    '"cells"': "its JSON is a string, not an object",
    "{}": 'broken.ipynb is not a Jupyter notebook: it has no "cells"',
    '{"cells": {"a": 1}}': 'broken.ipynb is not a Jupyter notebook: its "cells" are an '
                           "object, not a list",
    '{"cells": [{"cell_type": "code", "source": "x = 1"}, 7]}':
        "broken.ipynb: cell 2 is a number, not an object",
    '{"cells": [{"cell_type": "code", "source": null}]}':
        "broken.ipynb: the source of cell 1 is null, not text (a string or a list of strings)",
    '{"cells": [{"cell_type": "code", "source": ["x = 1", {"y": 2}]}]}':
        "broken.ipynb: the source of cell 1 is a list holding an object, not text",
    '{"cells": [{"cell_type": "code", "source": "s = \\"\\ud800\\""}]}':
        "broken.ipynb: cell 1 holds a character that is not Unicode text ('\\ud800')",
    '{"cells": [' * 50_000: "broken.ipynb is not a Jupyter notebook: its JSON is nested too "
                            "deeply",
    '{"cells": [], "n": ' + "9" * 5000 + "}": "its JSON holds a number too long to read",
}


@pytest.mark.parametrize("text", NOTEBOOKS, ids=range(len(NOTEBOOKS)))
def test_a_malformed_notebook_says_what_is_wrong(text):
    with pytest.raises(SubmissionError) as info:
        source_from_notebook(text, "broken.ipynb")
    assert NOTEBOOKS[text] in str(info.value)


def test_code_the_parser_cannot_take_is_a_refusal_not_a_crash():
    cells = [{"cell_type": "code", "source": s} for s in
             ["x = 1\x00", "y = " + "-" * 100_000 + "1", "def f():\n    return 1"]]
    src = source_from_notebook(json.dumps({"cells": cells}))
    assert "def f()" in src.text
    assert src.notes == ("cell 1 was skipped: it does not parse (line 1: source code string "
                         "cannot contain null bytes)",
                         "cell 2 was skipped: it does not parse (line 1: nested too deeply for "
                         "Python's parser)")
    assert import_problems("y = " + "-" * 100_000 + "1", frozenset(), "s.py") == [
        "line 1: nested too deeply for Python's parser (Python cannot read the file)"]


def test_check_shows_no_traceback_for_a_bad_submission(tmp_path, capsys):
    write(tmp_path / "broken.ipynb", '{"cells": [3]}')
    write(tmp_path / "bad.py", b"x = '\xe9'\n")
    write(os.fsencode(tmp_path) + b"/caf\xe9.py", REFERENCE)
    os.symlink(FIXTURES / "reference.py", tmp_path / "link.py")
    os.mkfifo(tmp_path / "fifo.py")
    nb = tmp_path / "nb"  # the assignment's notebook, its module beside it a link
    nb.mkdir()
    shutil.copy(REPO / "assignments" / "a1_rotations.ipynb", nb)
    os.symlink(FIXTURES / "reference.py", nb / "a1_rotations.py")
    cases = {
        "broken.ipynb": "Refused: broken.ipynb: cell 1 is a number, not an object",
        "bad.py": "Refused: bad.py is not a UTF-8 text file (byte 5 is 0xe9)",
        "link.py": "link.py is a symbolic link: only regular files are graded",
        "fifo.py": "fifo.py is a named pipe (FIFO): only regular files are graded",
        "nb/a1_rotations.ipynb": "nb/a1_rotations.py is a symbolic link: only regular files "
                                 "are graded",
    }
    for name, phrase in cases.items():
        assert main(["check", "a1", "--submission", str(tmp_path / name)]) == 1
        printed = capsys.readouterr()
        assert phrase in " ".join(printed.out.split()) and "Traceback" not in printed.err
    assert main(["check", "a1", "--submission", os.fsdecode(os.fsencode(tmp_path)
                                                             + b"/caf\xe9.py")]) == 0
    assert "caf\\xe9.py" in capsys.readouterr().out  # the name's byte shown, not printed raw
    for path, phrase in [(tmp_path / "none.py", "does not exist"), (tmp_path, "is a folder")]:
        with pytest.raises(SystemExit) as info:
            main(["check", "a1", "--submission", str(path)])
        assert info.value.code == 2 and phrase in capsys.readouterr().err


def test_a_forged_message_cannot_fill_the_results(tmp_path, monkeypatch):
    """Megabytes in a load error (as a forged frame could send) are cut in results.json and
    grades.csv, saying how much was cut."""
    def forged(self):
        return Outcome("error", error={"type": "ValueError", "message": "=" + "x" * 5_000_000,
                                       "where": None})

    monkeypatch.setattr(Sandbox, "start", forged)
    write(tmp_path / "s.py", REFERENCE)
    out = tmp_path / "out"
    grade(A1, [("s", tmp_path / "s.py")], out, progress=None)
    results = (out / "s" / "results.json").read_text()
    assert len(results) < 50_000 and "characters cut]" in results
    row = read_rows(out)["s"]
    assert len(row["reason"]) < MAX_LINE + 100 and row["reason"].endswith("characters cut]")
    assert csv_cell("=1+1") == "'=1+1" and csv_cell(-1.5) == -1.5 and csv_cell("a=b") == "a=b"
