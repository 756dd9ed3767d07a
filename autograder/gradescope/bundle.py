"""Build the zip that Gradescope's "zip file upload" takes, for one assignment.

At the zip's root: ``setup.sh`` and ``run_autograder`` (Gradescope's two entry points),
``bundle.env`` (the assignment and the Python and numpy versions to install: this machine's),
``seed`` (the secret seed of the hidden tests, readable by root only once set up), the grader
(``autograder/``, with only this assignment's spec) and the course library it compares
with (``course/``'s Python and its packaged sample data). Nothing else of the repository:
no template, notebook, test or solution.
"""

from __future__ import annotations

import os
import secrets
import sys
import zipfile
from importlib.metadata import version
from pathlib import Path

from ..assignments import KEYS, load
from ..safe_text import printable
from ..submission import read_regular

HERE = Path(__file__).resolve().parent
PACKAGE = HERE.parent  # autograder/
REPO = PACKAGE.parent
SCRIPTS = ("setup.sh", "run_autograder")
COURSE_DATA = ("data/samples",)  # package data a spec reads (a2: the packaged wave clip)
STAMP = (2020, 1, 1, 0, 0, 0)  # the same bytes for the same files, whenever built
MAX_SEED = 4096  # bytes of a seed file


def build(key: str, out: Path, seed_file: Path | None = None) -> str | None:
    """Write the bundle of assignment ``key`` to ``out``; the seed is read from ``seed_file``
    (its first line), or made here with :mod:`secrets` and returned, so that the instructor
    sees it once (None when it was given). ``ValueError`` names the argument at fault."""
    spec = load(key)
    if seed_file is not None:
        try:
            seed = read_regular(Path(seed_file), limit=MAX_SEED).strip()
        except ValueError as exc:  # missing, a link, too large, not UTF-8...
            raise ValueError(f"--seed-file: {exc}") from None
        if not seed or "\n" in seed or not seed.isprintable():
            raise ValueError(f"--seed-file: {printable(seed_file)} must hold one line of "
                             "printable text")
        made = None
    else:
        seed = made = secrets.token_urlsafe(32)
    env = (f"ASSIGNMENT={spec.key}\n"
           f"PYTHON_VERSION={sys.version_info.major}.{sys.version_info.minor}\n"
           f"NUMPY_VERSION={version('numpy')}\n")
    files = [(f"{name}", (HERE / name).read_bytes(), 0o755) for name in SCRIPTS]
    files += [("bundle.env", env.encode(), 0o644), ("seed", f"{seed}\n".encode(), 0o400)]
    files += [(p.relative_to(REPO).as_posix(), p.read_bytes(), 0o644) for p in sources(key)]
    # The zip holds the seed: only its owner may read it, and no link is written through.
    try:
        fd = os.open(out, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | getattr(os, "O_NOFOLLOW", 0),
                     0o600)
    except OSError as exc:
        raise ValueError(f"--out: cannot write {printable(out)} ({exc.strerror})") from None
    if hasattr(os, "fchmod"):  # a file already there keeps its mode otherwise
        os.fchmod(fd, 0o600)
    with os.fdopen(fd, "wb") as f, zipfile.ZipFile(f, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data, mode in files:
            info = zipfile.ZipInfo(name, STAMP)
            info.external_attr = (0o100000 | mode) << 16  # a regular file with these bits
            info.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(info, data)
    return made


def sources(key: str) -> list[Path]:
    """The grader's and the course library's files that grading ``key`` needs."""
    others = {f"{k}.py" for k in KEYS if k != key}
    grader = [p for p in PACKAGE.rglob("*.py")
              if not (p.parent.name == "assignments" and p.name in others)]
    course = list((REPO / "course").rglob("*.py"))
    course += [p for d in COURSE_DATA for p in (REPO / "course" / d).iterdir() if p.is_file()]
    return sorted(p for p in grader + course if "__pycache__" not in p.parts)


def built_message(out: Path, made: str | None) -> str:
    """What the instructor is told once the bundle is written."""
    text = (f"wrote {printable(out)}: upload it as the autograder of the assignment on "
            "Gradescope (\"Zip file upload\"); keep it private, it holds the secret seed")
    if made:
        text += (f"\nthe secret seed (new; shown this once: keep it to grade the same hidden "
                 f"tests locally with --seed): {made}")
    return text
