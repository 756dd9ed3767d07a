"""What every assignment autograder a2–a8 promises, checked the same way for each: the
reference scores full marks, the untouched template scores nothing and says "not implemented",
the catalogue of mistakes and the mutant fixtures match one to one, and each mutant is
diagnosed by name on the functions it breaks and nowhere else."""

from __future__ import annotations

import re

import pytest
from grading_fixtures import (
    ASSIGNMENTS,
    FIXTURES,
    LIMITS,
    assert_catalogue_matches_fixtures,
    assert_diagnosed,
    expectation,
    fixture_submission,
    mutants,
    one_line,
    seed,
)

from autograder import check
from autograder.assignments import load

TEMPLATES = {
    "a2": "a2_forward_kinematics.py",
    "a3": "a3_inverse_kinematics.py",
    "a4": "a4_character.py",
    "a5": "a5_animation.py",
    "a6": "a6_physics.py",
    "a7": "a7_walking.py",
    "a8": "a8_optimal_control.py",
}
#: (score, max score, bonus) of the reference, hidden tests included
REFERENCE_SCORES = {"a2": (13, 11, 2), "a3": (20, 18, 2), "a4": (13, 13, 0), "a5": (14, 14, 0),
                    "a6": (16, 16, 0), "a7": (14, 14, 0), "a8": (15, 15, 0)}
#: the fewest own mistakes each catalogue names
OWN_MISTAKES = {"a2": 8, "a3": 12, "a4": 6, "a5": 7, "a6": 14, "a7": 12, "a8": 12}
KEYS = sorted(TEMPLATES)


@pytest.mark.parametrize("key", KEYS)
def test_reference_gets_full_marks(key):
    result = check(key, FIXTURES / key / "reference.py", seed=seed(key), limits=LIMITS)
    assert result.hidden_run, "a seed runs the hidden tests"
    assert (result.score, result.max_score, result.bonus_score) == REFERENCE_SCORES[key]
    assert {t.status for t in result.tests} == {"passed"}, one_line(result)
    score, most, bonus = REFERENCE_SCORES[key]
    extra = f", including {bonus:g} bonus points" if bonus else ""
    assert f"Score: {score:g} / {most:g} (all tests{extra})" in str(result)


@pytest.mark.parametrize("key", KEYS)
def test_template_is_not_implemented_yet(key, monkeypatch):
    monkeypatch.delenv("AUTOGRADER_SEED", raising=False)
    result = check(key, ASSIGNMENTS / TEMPLATES[key], limits=LIMITS)
    assert result.score == 0 and {t.status for t in result.tests} == {"not_implemented"}
    assert "not implemented yet" in str(result)


@pytest.mark.parametrize("key", KEYS)
def test_catalogue_covers_every_mutant(key):
    assignment = load(key)
    assert_catalogue_matches_fixtures(assignment, key)
    assert len(assignment.misconceptions) >= OWN_MISTAKES[key]


@pytest.mark.parametrize(("key", "name"), [(k, m) for k in KEYS for m in mutants(k)])
def test_mutant_is_diagnosed_by_name(key, name, tmp_path):
    fn, mistake = expectation(key, name)
    result = check(key, fixture_submission(key, name, tmp_path), seed=seed(key), limits=LIMITS)
    assert_diagnosed(result, key, fn, mistake)
    for words in re.findall(r"^# says: (.+)$", (FIXTURES / key / name).read_text(), re.M):
        assert words in one_line(result), (words, one_line(result))
