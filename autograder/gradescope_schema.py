"""The results.json that Gradescope reads, checked key by key.

Every key Gradescope's autograder specification documents (gradescope-autograders.readthedocs.io,
"Autograder Specifications": output format, visibility, output string formatting, test case
status, leaderboards) is listed here with the type and values it takes; a key it does not
document is a problem too, so a typo cannot pass unnoticed.
"""

from __future__ import annotations

import math
from typing import Any

VISIBILITY = ("hidden", "after_due_date", "after_published", "visible")
FORMATS = ("text", "html", "simple_format", "md", "ansi")
STATUS = ("passed", "failed")
ORDER = ("asc", "desc")
NUMBER = (int, float)

# key -> (the types it may have, the values it may take or None for any)
TOP: dict[str, tuple[tuple[type, ...], tuple[str, ...] | None]] = {
    "score": (NUMBER, None),  # required unless every test has a score
    "execution_time": (NUMBER, None),  # seconds
    "output": ((str,), None),
    "output_format": ((str,), FORMATS),
    "test_output_format": ((str,), FORMATS),
    "test_name_format": ((str,), FORMATS),
    "visibility": ((str,), VISIBILITY),
    "stdout_visibility": ((str,), VISIBILITY),
    "extra_data": ((dict,), None),
    "tests": ((list,), None),  # required unless there is a top-level score
    "leaderboard": ((list,), None),
}
TEST: dict[str, tuple[tuple[type, ...], tuple[str, ...] | None]] = {
    "score": (NUMBER, None),  # required unless there is a top-level score
    "max_score": (NUMBER, None),
    "status": ((str,), STATUS),
    "name": ((str,), None),
    "name_format": ((str,), FORMATS),
    "number": ((str,), None),
    "output": ((str,), None),
    "output_format": ((str,), FORMATS),
    "tags": ((list,), None),
    "visibility": ((str,), VISIBILITY),
    "extra_data": ((dict,), None),
}
LEADERBOARD: dict[str, tuple[tuple[type, ...], tuple[str, ...] | None]] = {
    "name": ((str,), None),
    "value": ((int, float, str), None),
    "order": ((str,), ORDER),
}


def problems(results: Any) -> list[str]:
    """What in ``results`` (a parsed results.json) Gradescope's specification does not
    allow; empty when it is valid."""
    if not isinstance(results, dict):
        return [f"results.json holds {type(results).__name__}, not an object"]
    found = _fields(results, TOP, "results.json")
    tests = results.get("tests", [])
    if "score" not in results and not (
            isinstance(tests, list) and tests
            and all(isinstance(t, dict) and "score" in t for t in tests)):
        found.append("results.json has no top-level score and not every test has one")
    for i, test in enumerate(tests if isinstance(tests, list) else []):
        where = f"tests[{i}]"
        if not isinstance(test, dict):
            found.append(f"{where} is {type(test).__name__}, not an object")
            continue
        found += _fields(test, TEST, where)
        if isinstance(test.get("tags"), list) and not all(isinstance(t, str)
                                                          for t in test["tags"]):
            found.append(f"{where}.tags holds something other than strings")
    for i, entry in enumerate(results.get("leaderboard") or []):
        where = f"leaderboard[{i}]"
        if not isinstance(entry, dict):
            found.append(f"{where} is {type(entry).__name__}, not an object")
            continue
        found += _fields(entry, LEADERBOARD, where)
        found += [f"{where} has no {k}" for k in ("name", "value") if k not in entry]
    return found


def _fields(obj: dict[str, Any], spec: dict[str, Any], where: str) -> list[str]:
    found = []
    for key, value in obj.items():
        if key not in spec:
            found.append(f"{where}.{key} is not a key Gradescope documents")
            continue
        types, allowed = spec[key]
        if isinstance(value, bool) or not isinstance(value, types):
            found.append(f"{where}.{key} is {type(value).__name__}, expected "
                         + " or ".join(t.__name__ for t in types))
        elif allowed is not None and value not in allowed:
            found.append(f"{where}.{key} is {value!r}, not one of {', '.join(allowed)}")
        elif isinstance(value, float) and not math.isfinite(value):
            found.append(f"{where}.{key} is {value}, not a finite number")
    return found
