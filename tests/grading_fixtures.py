"""Fixture submissions for the assignment autograders a2–a5 and the assertions every one of
them shares: a mutant's ``# expect: function:mistake`` line, and what "diagnosed" means."""

from __future__ import annotations

import re
from pathlib import Path

from autograder import Limits
from autograder.results import Result
from autograder.spec import case_rng

FIXTURES = Path(__file__).parent / "fixtures"
ASSIGNMENTS = Path(__file__).parents[1] / "assignments"
LIMITS = Limits(cpu_seconds=8, memory_mb=600, load_timeout=5.0, case_timeout=1.0)
#: the functions whose score a mistake may also cost, because the reference calls the
#: student's function from them (a3's curve tracer runs their solver, a4's IK their path)
CALLERS: dict[str, dict[str, tuple[str, ...]]] = {
    "a3": {fn: ("trace_curve",) for fn in ("ccd", "fabrik", "jacobian", "dls_step", "two_link_ik")},
    "a4": {"path_to": ("ik_local",)},
}


def seed(key: str) -> str:
    return f"fixture-seed-{key}"


def fixture_submission(key: str, name: str, tmp_path: Path) -> Path:
    """A fixture as a file; ``# extends: reference.py`` fixtures are appended to it."""
    folder = FIXTURES / key
    src = (folder / name).read_text()
    if src.startswith("# extends: reference.py"):
        src = (folder / "reference.py").read_text() + "\n\n" + src
    path = tmp_path / f"{key}_submission.py"
    path.write_text(src)
    return path


def mutants(key: str) -> list[str]:
    return sorted(p.name for p in (FIXTURES / key).glob("mutant_*.py"))


def expectations(key: str, name: str) -> list[tuple[str, str]]:
    """``(function, misconception key)`` of each of a mutant's ``# expect:`` lines: the
    mistake itself first, then what its callers are told (``ik_local:path_to_wrong``)."""
    found = re.findall(r"# expect: (\S+)", (FIXTURES / key / name).read_text())
    assert found, name
    return [(fn, mistake) for fn, mistake in (f.split(":") for f in found)]


def expectation(key: str, name: str) -> tuple[str, str]:
    """``(function, misconception key)`` of a mutant's first ``# expect:`` line."""
    return expectations(key, name)[0]


def one_line(result: Result) -> str:
    return " ".join(str(result).split())


def assert_diagnosed(result: Result, key: str, fn: str, mistake: str) -> None:
    """Every failing test of ``fn`` names the mistake, the report says it, and only ``fn``
    (and the functions that call it) lost points."""
    failing = [t for t in result.tests if t.status != "passed"]
    own = [t for t in failing if t.test.function == fn]
    assert own and all(t.misconception and t.misconception.key == mistake for t in own), [
        (t.test.name, t.misconception) for t in own]
    assert f"Likely mistake, {own[0].misconception.title}" in one_line(result)
    allowed = (fn, *CALLERS.get(key, {}).get(fn, ()))
    assert all(t.test.function in allowed for t in failing), [t.test.name for t in failing]
    for caller, told in told_callers(key, fn, mistake):
        assert all(t.misconception and t.misconception.key == told
                   for t in failing if t.test.function == caller), [
            (t.test.name, t.misconception) for t in failing if t.test.function == caller]


def told_callers(key: str, fn: str, mistake: str) -> list[tuple[str, str]]:
    """What the callers of a mutant's function are told: its other ``# expect:`` lines."""
    for m in mutants(key):
        found = expectations(key, m)
        if found[0] == (fn, mistake):
            return found[1:]
    return []


def assert_catalogue_matches_fixtures(assignment, key: str) -> None:
    """Every mistake of the assignment's own catalogue has a mutant, every mutant names a
    catalogued mistake, and each shared mistake that can show here has at least one mutant."""
    expected = {":".join(e) for m in mutants(key) for e in expectations(key, m)}
    own = {f"{m.function}:{m.key}" for m in assignment.misconceptions}
    assert own <= expected <= {f"{m.function}:{m.key}" for m in assignment.catalogue}
    shared = {m.key for m in assignment.shared}
    assert shared <= {e.split(":")[1] for e in expected}


def visible_cases(assignment, fn: str):
    tests = [t for t in assignment.tests if t.function == fn and not t.hidden]
    return [c for t in tests for c in t.cases(case_rng(t, None))]
