"""``python -m autograder.gradescope.run``: grade the one submission of a Gradescope container.

Gradescope runs ``run_autograder`` once per submission, as root, in a fresh container built by
``setup.sh``. Under ``$AUTOGRADER_ROOT`` (default ``/autograder``) it finds ``source/`` (the
bundle: this grader, the course's reference, ``bundle.env`` and the secret ``seed``),
``submission/`` (whatever the student uploaded) and ``submission_metadata.json``, and it reads
back ``results/results.json``. What is printed here goes to Gradescope's stdout log, which the
results mark as shown to instructors only.

The sandbox runs at the strongest level the container allows (``$AUTOGRADER_ISOLATION`` may
ask for a weaker one, as the tests do), and never below ``$AUTOGRADER_MIN_ISOLATION``
(default :data:`~autograder.sandbox.FLOOR`, which a stock container run as root reaches): a
container that cannot give it grades nothing, and its log says why. A submission the
student's files decide (graded, or refused because nothing can be graded) gets a results.json
that says why. One the machine or the grader failed on (the sandbox could not start after
every retry, a bug of ours) is *not graded*: no results.json is written and the exit status is
:data:`NOT_GRADED_EXIT`, so Gradescope shows that the autograder failed instead of a score,
and the instructor's "Regrade" grades it again; the log says why, with the traceback.
"""

from __future__ import annotations

import json
import os
import sys
import traceback
from importlib.metadata import version
from pathlib import Path
from typing import Any

from .. import intake
from ..assignments import load
from ..findings import Findings
from ..gradescope_json import results_json
from ..gradescope_schema import problems
from ..judging import prepare
from ..output import create
from ..records import not_run
from ..runner import run
from ..safe_text import printable
from ..sandbox import FLOOR, Isolation, level_for, weaker_warning
from ..spec import Assignment
from ..submission import read_regular

SOURCE = Path(__file__).resolve().parents[2]  # the bundle's root: $AUTOGRADER_ROOT/source
CONFIG = "bundle.env"  # ASSIGNMENT=a1, PYTHON_VERSION=3.11, NUMPY_VERSION=2.4.6
SEED = "seed"
MAX_METADATA = 1 << 20  # bytes of submission_metadata.json read


NOT_GRADED_EXIT = 3  # the exit status for a submission not graded (no results.json)
NOT_GRADED = ("not graded, no results.json written: Gradescope shows that the autograder "
              "failed (no score), and Regrade grades it again")


def main() -> int:
    root = Path(os.environ.get("AUTOGRADER_ROOT") or "/autograder")
    try:
        results = grade(root)
    except Exception:  # our fault, not the student's: no score, the traceback logged
        print(f"grader fault: {NOT_GRADED}:", flush=True)
        traceback.print_exc(file=sys.stdout)
        return NOT_GRADED_EXIT
    if "score" not in results:  # the machine's fault (results_json says why)
        print(f"{NOT_GRADED}: {results['extra_data']['not_graded']}", flush=True)
        return NOT_GRADED_EXIT
    (root / "results").mkdir(parents=True, exist_ok=True)
    with create(root / "results" / "results.json") as f:
        f.write(json.dumps(results, indent=1, allow_nan=False))
    print(f"results.json written: score {results.get('score')}", flush=True)
    return 0


def config() -> dict[str, str]:
    """``bundle.env``'s ``KEY=VALUE`` lines (setup.sh sources the same file)."""
    pairs = (line.split("=", 1) for line in (SOURCE / CONFIG).read_text().splitlines()
             if "=" in line and not line.lstrip().startswith("#"))
    return {k.strip(): v.strip().strip("'\"") for k, v in pairs}


def grade(root: Path) -> dict[str, Any]:
    """Grade ``root/submission``; the results in Gradescope's format, checked."""
    settings = config()
    seed = protected_seed(root)
    spec = load(settings["ASSIGNMENT"])
    metadata = read_metadata(root / "submission_metadata.json")
    level = container_level()
    print(f"assignment {spec.key}; isolation {level}; submission "
          f"{metadata.get('id', '(no metadata)')} by {_users(metadata)}", flush=True)
    warning = weaker_warning(level)
    if warning:
        print(warning, flush=True)
    path, graded = choose(root / "submission", spec)
    print(graded, flush=True)
    if path is None:
        result = not_run(spec, root / "submission", seed, level, graded,
                         "not run: nothing to grade (see above)")
        graded = "Nothing was graded."
    else:
        result = run(spec, path, seed, level=level)
    results = results_json(Findings.of(result), graded, {"submission_id": metadata.get("id")})
    wrong = problems(results)
    if wrong:
        raise RuntimeError("results.json does not follow Gradescope's format: "
                           + "; ".join(wrong))
    return results


def container_level() -> Isolation:
    """The level to grade at here (``$AUTOGRADER_ISOLATION``, else the strongest); a
    ValueError below ``$AUTOGRADER_MIN_ISOLATION`` (else :data:`FLOOR`)."""
    return level_for(os.environ.get("AUTOGRADER_ISOLATION") or None,
                     os.environ.get("AUTOGRADER_MIN_ISOLATION") or FLOOR.value)


def protected_seed(root: Path) -> str:
    """The bundle's secret seed, after making sure only root (the grader) can read it or
    anything under ``root``: the submission runs as another user."""
    seed_file = SOURCE / SEED
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        os.chown(seed_file, 0, 0, follow_symlinks=False)
    os.chmod(seed_file, 0o400, follow_symlinks=False)
    os.chmod(root, 0o700)
    seed = read_regular(seed_file, limit=4096).strip()
    if not seed:
        raise RuntimeError(f"the bundle's {SEED} file is empty")
    return seed


def read_metadata(path: Path) -> dict[str, Any]:
    """Gradescope's ``submission_metadata.json`` (``{}`` if absent or unreadable: it only
    names the submission in the log)."""
    if not os.path.lexists(path):
        return {}
    try:
        data = json.loads(read_regular(path, limit=MAX_METADATA))
    except ValueError as exc:  # a SubmissionError (not a regular file...) or not JSON
        print(f"warning: {printable(path)} not read: {exc}", flush=True)
        return {}
    return data if isinstance(data, dict) else {}


def _users(metadata: dict[str, Any]) -> str:
    users = metadata.get("users")
    if not isinstance(users, list):
        return "(unknown)"
    names = [printable(str(u.get("email") or u.get("name") or u.get("id")))
             for u in users if isinstance(u, dict)]
    return ", ".join(names) or "(unknown)"


def choose(folder: Path, spec: Assignment) -> tuple[Path | None, str]:
    """The file of ``folder`` to grade (:func:`autograder.intake.choose`: the policy of the
    local pool and the cluster too), and a sentence for the student saying which and why (or
    why none)."""
    choice = intake.choose(folder, spec.template, [f.name for f in spec.functions],
                           shown="your submission")
    if choice.path is not None:
        return choice.path, choice.said
    return None, (f"{choice.refused[0].upper()}{choice.refused[1:]}: upload one file, or name "
                  f"the one to grade {spec.template}." if choice.refused else
                  f"No .py or .ipynb file was found in your submission: upload "
                  f"{spec.template} (or your notebook).")


def check_install() -> None:
    """setup.sh's last step: this Python and numpy are the pinned ones, the assignment's
    cases and reference answers compute, and the sandbox starts (its level is printed)."""
    settings = config()
    here = f"{sys.version_info.major}.{sys.version_info.minor}"
    if here != settings["PYTHON_VERSION"]:
        raise SystemExit(f"setup: Python {here}, but the bundle pins "
                         f"{settings['PYTHON_VERSION']}")
    if version("numpy") != settings["NUMPY_VERSION"]:
        raise SystemExit(f"setup: numpy {version('numpy')}, but the bundle pins "
                         f"{settings['NUMPY_VERSION']}")
    spec = load(settings["ASSIGNMENT"])
    tests = prepare(spec, "setup check")
    try:
        level = container_level()
    except ValueError as exc:
        raise SystemExit(f"setup: {exc}") from None
    print(f"setup: Python {here}, numpy {version('numpy')}, {spec.key} ({len(tests)} tests "
          f"with the hidden ones), sandbox isolation here: {level}")
    warning = weaker_warning(level)
    if warning:
        print(f"setup: {warning}")


if __name__ == "__main__":
    sys.exit(main())
