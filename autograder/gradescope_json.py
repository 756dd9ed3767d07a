"""A graded submission as Gradescope's results.json, in Markdown.

What the grader writes is ours; what comes from the submission (its file names, the messages
of its errors, the notes on its notebook) is shown only inside fenced code blocks, so that it
cannot turn into a link, an image or HTML on the page Gradescope renders.
"""

from __future__ import annotations

import re
from typing import Any

from .findings import MAX_FIELD, bounded, header, points, scored, test_lines
from .results import Result, TestResult
from .spec import Misconception

# Parentheses stay: they act only after a "]" (escaped here), and "\(" is an inline-math
# delimiter where MathJax renders the page.
MARKDOWN_SPECIALS = re.compile(r"([\\`*_{}\[\]<>#+!|~-])")


def markdown_text(text: str) -> str:
    """``text`` with every character Markdown would act on escaped."""
    return MARKDOWN_SPECIALS.sub(r"\\\1", text)


def code_block(lines: list[str]) -> str:
    """``lines`` as a fenced block whose fence no run of backticks inside can close."""
    text = bounded("\n".join(lines), MAX_FIELD)
    longest = max((len(r) for r in re.findall(r"`+", text)), default=0)
    fence = "`" * max(3, longest + 1)
    return f"{fence}text\n{text}\n{fence}"


def test_output(t: TestResult) -> str:
    """A test's feedback: the likely mistake as a sentence, the details as a block."""
    if t.status == "passed":
        return markdown_text(test_lines(t)[0].capitalize() + ".")
    parts = []
    if t.misconception:
        m = t.misconception
        parts.append(f"**Likely mistake: {markdown_text(m.title)}.** "
                     f"{markdown_text(m.explanation)}")
    parts.append(code_block(test_lines(t)))
    return "\n\n".join(parts)


def summary(result: Result, graded: str) -> str:
    """The top-level output: what was graded, what stopped it, the mistakes the visible
    tests show (a hidden test's findings stay with that test until grades are published)
    and the visible score."""
    a = result.assignment
    parts = [f"**{markdown_text(a.key)} · {markdown_text(a.title)}**", markdown_text(graded)]
    said = [line for line in header(result)[1:] if line]
    if said:
        parts.append(code_block(said))
    if result.not_graded:
        return bounded("\n\n".join(parts), MAX_FIELD)
    shown = [t for t in scored(result) if not t.test.hidden]
    found: dict[tuple[str, str], tuple[Misconception, list[str]]] = {}
    for t in shown:
        if t.misconception and t.status != "passed":
            key = (t.test.function, t.misconception.key)
            found.setdefault(key, (t.misconception, []))[1].append(t.test.name)
    if found:
        items = [f"- `{fn}()`: **{markdown_text(m.title)}** ({markdown_text(', '.join(names))})"
                 f" — {markdown_text(m.explanation)}"
                 for (fn, _), (m, names) in found.items()]
        parts.append("**Likely mistakes**\n\n" + "\n".join(items))
    elif any(t.status not in ("passed", "not_run") for t in shown):
        parts.append("No known mistake matches the failing tests: see each test below.")
    visible = sum(t.score for t in shown)
    most = sum(t.test.points for t in shown if not t.test.bonus)
    hidden = [t for t in scored(result) if t.test.hidden]
    line = f"Visible tests: {points(visible)} / {points(most)} points."
    if hidden:
        line += (f" {len(hidden)} hidden tests ({points(sum(t.test.points for t in hidden))}"
                 " points) are shown when your instructor publishes the grades.")
    parts.append(line)
    return bounded("\n\n".join(parts), MAX_FIELD)


def results_json(result: Result, graded: str, extra: dict[str, Any] | None = None
                 ) -> dict[str, Any]:
    """``result`` in Gradescope's format: one entry per scored test (hidden ones
    ``after_published``), the summary on top, our log (stdout) for instructors only.
    ``graded`` says which file was graded and why that one."""
    tests = [{
        "name": t.test.name,
        "score": round(t.score, 4),
        "max_score": t.test.points,
        "status": "passed" if t.status == "passed" else "failed",
        "output": test_output(t),
        "output_format": "md",
        "visibility": "after_published" if t.test.hidden else "visible",
        # Gradescope documents no per-test time: it is kept with the test's own data
        "extra_data": {"execution_time": round(t.elapsed, 3), "function": t.test.function,
                       "misconception": t.misconception.key if t.misconception else None},
    } for t in scored(result)]
    if result.not_graded:  # no score at all: Gradescope's runner writes no results.json
        return {"execution_time": round(result.elapsed, 3), "output": summary(result, graded),
                "output_format": "md", "visibility": "visible", "stdout_visibility": "hidden",
                "extra_data": {"assignment": result.assignment.key,
                               "isolation": str(result.isolation),
                               "not_graded": bounded(result.not_graded), **(extra or {})},
                "tests": []}
    return {
        "score": round(result.score, 4),
        "execution_time": round(result.elapsed, 3),
        "output": summary(result, graded),
        "output_format": "md",
        "visibility": "visible",
        "stdout_visibility": "hidden",
        "extra_data": {"assignment": result.assignment.key, "isolation": str(result.isolation),
                       **(extra or {})},
        "tests": tests,
    }
