"""A graded submission as Gradescope's results.json, in Markdown.

What the grader writes is ours; what comes from the submission (its file names, the messages
of its errors, the notes on its notebook) is shown only inside fenced code blocks, so that it
cannot turn into a link, an image or HTML on the page Gradescope renders.
"""

from __future__ import annotations

import re
from typing import Any

from .findings import Findings, TestFindings, points
from .safe_text import MAX_FIELD, bounded
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


def test_output(t: TestFindings) -> str:
    """A test's feedback: the likely mistake as a sentence, the details as a block."""
    if t.status == "passed":
        return markdown_text(t.lines[0].capitalize() + ".")
    parts = []
    if t.mistake:
        m = t.mistake
        parts.append(f"**Likely mistake: {markdown_text(m.title)}.** "
                     f"{markdown_text(m.explanation)}")
    parts.append(code_block(list(t.lines)))
    return "\n\n".join(parts)


def summary(f: Findings, graded: str) -> str:
    """The top-level output: what was graded, what stopped it, the mistakes the visible
    tests show (a hidden test's findings stay with that test until grades are published)
    and the visible score."""
    parts = [f"**{markdown_text(f.assignment)} · {markdown_text(f.title)}**",
             markdown_text(graded)]
    said = [line for line in f.header[1:] if line]
    if said:
        parts.append(code_block(said))
    if f.not_graded:
        return bounded("\n\n".join(parts), MAX_FIELD)
    shown = [t for t in f.scored if not t.hidden]
    found: dict[tuple[str, str], tuple[Misconception, list[str]]] = {}
    for t in shown:
        if t.mistake and t.status != "passed":
            key = (t.function, t.mistake.key)
            found.setdefault(key, (t.mistake, []))[1].append(t.name)
    if found:
        items = [f"- `{fn}()`: **{markdown_text(m.title)}** ({markdown_text(', '.join(names))})"
                 f" — {markdown_text(m.explanation)}"
                 for (fn, _), (m, names) in found.items()]
        parts.append("**Likely mistakes**\n\n" + "\n".join(items))
    elif any(t.status not in ("passed", "not_run") for t in shown):
        parts.append("No known mistake matches the failing tests: see each test below.")
    visible = sum(t.score for t in shown)
    most = sum(t.points for t in shown if not t.bonus)
    hidden = [t for t in f.scored if t.hidden]
    line = f"Visible tests: {points(visible)} / {points(most)} points."
    if hidden:
        line += (f" {len(hidden)} hidden tests ({points(sum(t.points for t in hidden))}"
                 " points) are shown when your instructor publishes the grades.")
    parts.append(line)
    return bounded("\n\n".join(parts), MAX_FIELD)


def results_json(f: Findings, graded: str, extra: dict[str, Any] | None = None
                 ) -> dict[str, Any]:
    """A submission's findings in Gradescope's format: one entry per scored test (hidden
    ones ``after_published``), the summary on top, our log (stdout) for instructors only.
    ``graded`` says which file was graded and why that one."""
    tests = [{
        "name": t.name,
        "score": round(t.score, 4),
        "max_score": t.points,
        "status": "passed" if t.status == "passed" else "failed",
        "output": test_output(t),
        "output_format": "md",
        "visibility": "after_published" if t.hidden else "visible",
        # Gradescope documents no per-test time: it is kept with the test's own data
        "extra_data": {"execution_time": round(t.elapsed, 3), "function": t.function,
                       "misconception": t.mistake.key if t.mistake else None},
    } for t in f.scored]
    if f.not_graded:  # no score at all: Gradescope's runner writes no results.json
        return {"execution_time": round(f.elapsed, 3), "output": summary(f, graded),
                "output_format": "md", "visibility": "visible", "stdout_visibility": "hidden",
                "extra_data": {"assignment": f.assignment, "isolation": f.isolation,
                               "not_graded": bounded(f.not_graded), **(extra or {})},
                "tests": []}
    return {
        "score": round(f.score, 4),
        "execution_time": round(f.elapsed, 3),
        "output": summary(f, graded),
        "output_format": "md",
        "visibility": "visible",
        "stdout_visibility": "hidden",
        "extra_data": {"assignment": f.assignment, "isolation": f.isolation,
                       **(extra or {})},
        "tests": tests,
    }
