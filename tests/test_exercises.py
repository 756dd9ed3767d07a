"""The notebooks' exercises (:mod:`course.exercises`): every one solvable by its reference,
every known mistake caught and named, unattempted ones "not yet", and the notebooks' own
exercise cells checked both ways (left as ``...``, and filled in with the reference)."""

from __future__ import annotations

import ast
import importlib
import json
import linecache
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from course.exercises import check, exercise, exercises, hint, quiz, reference
from course.exercises.registry import NOTEBOOKS

REPO = Path(__file__).resolve().parents[1]
ALL = [f"{nb}.{e.key}" for nb in NOTEBOOKS for e in exercises(nb)]
CHECK_CALL = re.compile(r'check\("([\w.]+)",\s*(\w+)\)')


@pytest.mark.parametrize("key", ALL)
def test_every_exercise_is_solved_by_its_reference(key):
    feedback = check(key, reference(key))
    assert feedback.passed, feedback.text


@pytest.mark.parametrize("key", ALL)
def test_every_known_mistake_is_caught_and_named(key):
    mistakes = [m for m in exercise(key).mistakes if m.wrong is not None]
    for m in mistakes:
        feedback = check(key, lambda *args, wrong=m.wrong: wrong(*args))
        assert feedback.status == "fail", f"{m.key} passed {key}"
        assert m.title in feedback.text, f"{key}: {m.key} not named:\n{feedback.text}"


def test_shared_convention_mistakes_are_named():
    """The autograder's catalogue names a scalar-last quaternion and a transposed matrix."""
    xyzw = check("02.fk_orientation",
                 lambda Q, R: np.roll(reference("02.fk_orientation")(Q, R), -1))
    assert "(x, y, z, w)" in xyzw.text
    transposed = check("01.compose", lambda a, b: (b @ a).T)
    assert "transposed" in transposed.text
    pivot = check("05.ccd_rotation", lambda r, e, t: reference("05.ccd_rotation")(0 * r, e, t))
    assert "world origin" in pivot.text


def test_a_failure_shows_the_case_its_inputs_and_expected_vs_got():
    feedback = check("07.jacobian_column", lambda r, a, e: np.zeros(3))
    lines = feedback.text.splitlines()
    assert lines[0].startswith("✗ 07.jacobian_column: ")
    assert any(line.strip().startswith("r_i = [") for line in lines)
    assert "returned [0, 0, 0], expected" in feedback.text


def _defined(source: str, name: str):
    """Define ``name`` from ``source`` as a notebook cell would (its source findable)."""
    filename = f"<cell {abs(hash(source))}>"
    linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
    namespace: dict = {"np": np}
    exec(compile(source, filename, "exec"), namespace)
    return namespace[name]


@pytest.mark.parametrize("body", ["...  # your code here", "pass",
                                  '"""Docstring only."""', "raise NotImplementedError"])
def test_an_unwritten_body_is_not_yet(body):
    fn = _defined(f"def child_position(p_parent, Q_parent, l_i):\n    {body}\n", "child_position")
    feedback = check("02.fk_step", fn)
    assert feedback.status == "not_yet" and not feedback.passed


def test_a_missing_return_and_an_error_are_failures():
    no_return = _defined("def f(p, Q, l):\n    p + l\n", "f")
    assert "forget a `return`" in check("02.fk_step", no_return).text
    raising = _defined("def f(p, Q, l):\n    return p[7]\n", "f")
    feedback = check("02.fk_step", raising)
    assert feedback.status == "fail" and "raised IndexError" in feedback.text
    assert "(line 2: return p[7])" in feedback.text, "the error names the student's line"


def test_the_student_cannot_corrupt_the_cases():
    def edits_in_place(p, Q, l_i):
        p += 100.0
        return p

    check("02.fk_step", edits_in_place)
    assert check("02.fk_step", reference("02.fk_step")).passed


def test_unknown_keys_list_the_known_ones():
    with pytest.raises(KeyError, match="02.fk_step"):
        check("02.no_such", reference("02.fk_step"))
    with pytest.raises(KeyError, match="no exercises"):
        exercises("99")


def test_a_key_that_is_not_a_name_or_names_nothing_is_a_clear_error():
    with pytest.raises(TypeError, match="a string such as '02.fk_step', got NoneType"):
        check(None, reference("02.fk_step"))
    with pytest.raises(KeyError) as unknown:
        check("fk_step", reference("02.fk_step"))
    assert str(unknown.value).startswith("no exercise 'fk_step'; the exercises are 01.compose")
    assert all(key in str(unknown.value) for key in ALL)


def test_an_exception_that_cannot_say_what_it_is_is_reported_by_its_type():
    class Broken(Exception):
        def __str__(self):
            raise RuntimeError("no message")

    def raises(p, Q, l_i):
        raise Broken

    feedback = check("02.fk_step", raises)
    assert feedback.status == "fail" and "raises raised Broken (line" in feedback.text


@pytest.mark.parametrize("kind", ["python loop", "long C call"])
def test_a_call_over_the_time_limit_is_stopped_and_the_rest_skipped(kind):
    """The grader's 2 s per case: a Python loop is stopped at 2 s, a sleep when it returns;
    either way the check says so, and the cases after it are not run (each 2.5 s call would
    have made this check take 12 s, silently)."""
    def busy(p, Q, l_i):
        end = time.monotonic() + 2.5
        while time.monotonic() < end:
            pass
        return reference("02.fk_step")(p, Q, l_i)

    def sleeps(p, Q, l_i):
        time.sleep(2.5)
        return reference("02.fk_step")(p, Q, l_i)

    start = time.monotonic()
    feedback = check("02.fk_step", busy if kind == "python loop" else sleeps)
    elapsed = time.monotonic() - start
    assert feedback.status == "fail", feedback.text
    assert "took longer than 2 s on this case and was stopped" in feedback.text
    assert elapsed < (2.4 if kind == "python loop" else 4.0), elapsed
    assert check("02.fk_step", reference("02.fk_step")).passed  # nothing left behind


def test_a_time_limit_never_fires_after_its_block():
    """However close to the limit the block ends, the exception is raised inside the
    ``with`` or not at all (the watchdog's post is cleared on the way out)."""
    from course.exercises.check import _OutOfTime, _TimeLimit

    fired = 0
    for i in range(300):
        limit = 1e-4 * (i % 10)
        timer = _TimeLimit(limit)
        try:
            with timer:
                end = time.perf_counter() + limit
                while time.perf_counter() < end:
                    pass
        except _OutOfTime:
            assert timer.fired
        fired += timer.fired
        sum(range(2000))  # bytecodes where a late exception would surface
    assert 0 < fired < 300


def test_what_a_function_prints_is_shown_cut_short(capsys):
    def chatty(p, Q, l_i):
        print("x" * 200_000)
        return reference("02.fk_step")(p, Q, l_i)

    assert check("02.fk_step", chatty).passed
    out = capsys.readouterr().out
    assert out.startswith("x" * 4000) and len(out) < 4200
    assert out.rstrip().endswith("… and 996,005 more characters printed by your function, "
                                 "not shown")


def test_hint_and_quiz_headless(capsys):
    text = hint("04.inner_angle")
    assert text.startswith("hint: ") and "formula: " in text and "<code>" not in text
    assert quiz("05.first_sweep", "Which joint turns most?", ["the root", "the tip"],
                answer="the tip", why="It goes first.") is None
    out = capsys.readouterr().out
    assert "Which joint turns most?" in out and "(b) the tip" in out and "goes first" not in out
    with pytest.raises(ValueError):
        quiz("05.bad", "?", ["one", "two"], answer=2, why="")


def test_the_hint_button_reveals_a_hint_then_the_formula(monkeypatch):
    import course.exercises.hints as hints

    monkeypatch.setattr(hints, "in_kernel", lambda: True)
    ex = exercise("07.dls_step")
    button, shown = hints.hint("07.dls_step").children
    assert shown.value == ""
    button.click()
    assert ex.hint in shown.value and ex.formula not in shown.value
    button.click()
    assert ex.formula in shown.value and button.disabled


def _quiz_widget(monkeypatch, **kw):
    quizzes = importlib.import_module("course.exercises.quiz")  # the module, not the function
    monkeypatch.setattr(quizzes, "in_kernel", lambda: True)
    return quizzes.quiz("05.first_sweep", "Which joint turns most?", ["the root", "the tip"],
                        answer=1, why="It goes first.", **kw).children


def test_the_quiz_reveals_its_answer_only_after_a_choice(monkeypatch):
    question, choices, show, verdict = _quiz_widget(monkeypatch)
    assert verdict.value == "" and "It goes first." not in question.value
    choices.value = 1
    assert "Right" in verdict.value and "It goes first." in verdict.value
    assert choices.disabled and show.disabled


def test_a_wrong_first_choice_gets_a_hint_not_the_answer(monkeypatch):
    _, choices, show, verdict = _quiz_widget(monkeypatch, hint="Count the lever arms.")
    choices.value = 0
    assert "try again" in verdict.value and "Count the lever arms." in verdict.value
    assert "(b)" not in verdict.value and "It goes first." not in verdict.value
    assert not choices.disabled
    choices.value = 1  # the second try, right: the explanation
    assert "Right" in verdict.value and "It goes first." in verdict.value


def test_a_second_wrong_choice_reveals_the_answer(monkeypatch):
    _, choices, _, verdict = _quiz_widget(monkeypatch)
    choices.value = 0
    choices.value = None  # (a reset, as the widget may send, counts as nothing)
    assert "try again" in verdict.value
    choices.value = 0
    assert "(b) the tip" in verdict.value and "It goes first." in verdict.value


def test_show_me_reveals_the_answer_without_a_choice(monkeypatch):
    _, choices, show, verdict = _quiz_widget(monkeypatch)
    show.click()
    assert "(b) the tip" in verdict.value and "It goes first." in verdict.value
    assert choices.disabled


def test_importing_the_exercises_is_light():
    code = ("import sys, course.exercises; print(sorted(m for m in ('autograder', 'ipywidgets', "
            "'matplotlib', 'pyvista') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=REPO)
    assert out.stdout.strip() == "[]"


# --- the notebooks' own exercise cells ----------------------------------------------------


def _exercise_cells(path: Path) -> list[tuple[str, str, str]]:
    """``(exercise cell source, key, function name)`` for each ``# ✏️ Exercise`` cell and
    the check that follows it."""
    cells = [("".join(c["source"]), c["cell_type"])
             for c in json.loads(path.read_text(encoding="utf-8"))["cells"]]
    found = []
    for i, (src, kind) in enumerate(cells):
        if kind == "code" and src.startswith("# ✏️ Exercise"):
            follow = next(s for s, k in cells[i + 1:] if k == "code")
            key, name = CHECK_CALL.search(follow).groups()
            found.append((src, key, name))
    return found


def _solved(source: str, key: str, name: str) -> str:
    """The cell with the body of ``name`` replaced by a call to the exercise's reference."""
    fn = next(n for n in ast.parse(source).body if isinstance(n, ast.FunctionDef)
              and n.name == name)
    params = ", ".join(a.arg for a in fn.args.args)
    call = f"return __import__('course.exercises').exercises.reference({key!r})({params})"
    assert "...  # your code here" in source, f"{name}: no '...  # your code here' line"
    return source.replace("...  # your code here", call)


NOTEBOOK_PATHS = [p for nb in NOTEBOOKS for p in REPO.glob(f"notebooks/{nb}_*.ipynb")]


@pytest.mark.parametrize("path", NOTEBOOK_PATHS, ids=lambda p: p.name)
def test_notebook_exercises_unattempted_and_solved(path):
    cells = _exercise_cells(path)
    notebook = path.name[:2]
    assert {key for _, key, _ in cells} == {f"{notebook}.{e.key}" for e in exercises(notebook)}, \
        "every exercise of the notebook's module appears in it, once"
    for source, key, name in cells:
        assert check(key, _defined(source, name)).status == "not_yet", key
        solved = check(key, _defined(_solved(source, key, name), name))
        assert solved.passed, solved.text


@pytest.mark.parametrize("path", sorted(REPO.glob("notebooks/[0-9][0-9]_*.ipynb")),
                         ids=lambda p: p.name)
def test_notebook_quizzes_run_headless(path, capsys):
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    quizzes = ["".join(c["source"]) for c in cells
               if c["cell_type"] == "code" and 'quiz("' in "".join(c["source"])]
    assert quizzes, f"{path.name} has no predict-then-run quiz"
    for source in quizzes:
        exec(source, {"quiz": quiz})
        assert "🤔" in capsys.readouterr().out
    hidden = [c["metadata"].get("jupyter", {}).get("source_hidden", False) for c in cells
              if c["cell_type"] == "code" and 'quiz("' in "".join(c["source"])]
    assert all(hidden), f"{path.name}: a quiz cell shows its source (and its answer)"


def test_the_uniform_catmull_rom_tangent_is_named_as_in_a5():
    """Exercise 11.catmull_rom_tangent names (p₊ − p₋)/2 through the shared catalogue, in the
    words a5 uses."""
    from autograder.catalogue import UNIFORM_TANGENT

    feedback = check("11.catmull_rom_tangent", lambda a, b, t0, t1, t2: (b - a) / 2)
    assert feedback.status == "fail"
    assert UNIFORM_TANGENT[0] in feedback.text
    assert "divided by the time between the two neighbours" in feedback.text


def _one_dof_grows(inertia: float, h: float, kp: float, kd: float, steps: int = 4000) -> bool:
    """A 1-DOF joint under explicit PD, stepped by semi-implicit Euler (MuJoCo's Euler):
    whether its error grows a thousandfold within ``steps`` steps (a stable undamped joint
    near the bound swings on a long, thin ellipse: bounded, but far from 1)."""
    x, v = 1.0, 0.0
    for _ in range(steps):
        v += h * (-kp * x - kd * v) / inertia
        x += h * v
        if abs(x) > 1e3:
            return True
    return False


@pytest.mark.parametrize("inertia,h,kd", [(0.01, 1 / 600, 0.0), (0.5, 1 / 120, 10.0),
                                    (0.2, 1 / 240, 20.0), (1.3, 1 / 60, 0.0)])
def test_kp_max_is_where_a_simulated_joint_turns_unstable(inertia, h, kd):
    """14.kp_max's closed form against a simulated joint: 2 % under it the error decays,
    2 % over it the error grows."""
    kp = reference("14.kp_max")(inertia, h, kd)
    assert not _one_dof_grows(inertia, h, 0.98 * kp, kd)
    assert _one_dof_grows(inertia, h, 1.02 * kp, kd)


def test_leg_torque_does_the_virtual_work_of_its_force():
    """τ · δθ = f · δc for a small δθ (finite differences of the hip's position)."""
    rng = np.random.default_rng(14)
    ref = reference("14.leg_torque")
    for _ in range(5):
        theta, lengths = rng.uniform(0.2, 2.0, 2), rng.uniform(0.3, 0.6, 2)
        c_bar, kp = rng.normal(size=2), 300.0

        def hip(t, lengths=lengths):
            return np.array([lengths[0] * np.cos(t[0]) + lengths[1] * np.cos(t[0] + t[1]),
                             lengths[0] * np.sin(t[0]) + lengths[1] * np.sin(t[0] + t[1])])

        f = kp * (c_bar - hip(theta))
        d = rng.normal(size=2) * 1e-6
        dc = (hip(theta + d) - hip(theta - d)) / 2
        assert np.isclose(ref(theta, lengths, c_bar, kp) @ d, f @ dc, rtol=1e-6, atol=1e-12)


def test_pd_torque_of_q_and_minus_q_targets_agree():
    """q̄ and −q̄ are one rotation: the same torque, whose size is kp times the angle."""
    rng = np.random.default_rng(7)
    ref = reference("14.pd_torque")
    for _ in range(10):
        q, qb = (v / np.linalg.norm(v) for v in rng.normal(size=(2, 4)))
        a, b = ref(q, qb, np.zeros(3), 2.0, 0.0), ref(q, -qb, np.zeros(3), 2.0, 0.0)
        assert np.allclose(a, b)
        assert np.linalg.norm(a) <= 2.0 * np.pi + 1e-9
