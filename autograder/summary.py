"""The class summary, ``summary.html`` beside ``grades.csv``: what an instructor reads before
the next lecture.

The score histogram, each test's pass rate, and the mistakes of the catalogue found most
often, each with its count and one example (the first failing case of the first submission
that showed it: its inputs and what came back, without the student's name or file). Drawn
with matplotlib on the Agg canvas and embedded as PNG, so the page is one self-contained
file; every string that may come from a student (names, reasons, examples) is escaped and
bounded.

The summary is built from :func:`facts`, plain data rendered from each submission's
:class:`~autograder.findings.Findings` that the batch keeps per submission (and a cluster's
worker sends back), so a resumed batch summarises the whole class.
"""

from __future__ import annotations

import html
from collections import Counter
from typing import TYPE_CHECKING, Any

from .figures import figure, png
from .safe_text import bounded, one_line

if TYPE_CHECKING:
    from .findings import Findings, TestFindings
    from .spec import Assignment

MAX_EXAMPLE = 300  # characters of a mistake's example
MAX_REASON = 300  # characters of a refusal's reason
TOP = 10  # mistakes listed
HIDDEN = "<student>"  # what an example says in place of the student's name or file


def facts(name: str, f: Findings) -> dict[str, Any]:
    """What the summary needs of one graded submission, as plain data."""
    own = {name, f.path.name, f.path.stem, str(f.path)}
    mistakes: dict[str, dict[str, str]] = {}  # each once, as the first test showing it has it
    for t in f.scored:
        if t.mistake:
            key = f"{t.function}:{t.mistake.key}"
            mistakes.setdefault(key, {"key": key, "title": t.mistake.title,
                                      "test": t.name, "example": _example(t, own)})
    return {
        "name": name,
        "score": round(f.score, 4),
        "max_score": f.max_score,
        "refused": one_line(f.refused, MAX_REASON),
        "not_graded": one_line(f.not_graded, MAX_REASON),
        "tests": {t.name: t.status for t in f.scored},
        "mistakes": list(mistakes.values()),
    }


def _example(t: TestFindings, own: set[str]) -> str:
    """The test's first failing case, in one bounded line without the strings in ``own``."""
    first = t.first
    if first is None:
        return ""
    text = f"{t.call}: {first.reason}"
    for s in sorted(own, key=len, reverse=True):
        if len(s) >= 3:  # a shorter name would blot out numbers and words
            text = text.replace(s, HIDDEN)
    return bounded(text, MAX_EXAMPLE)


def summary_html(assignment: Assignment, class_facts: list[dict[str, Any]]) -> str:
    """The page, from each submission's :func:`facts` (in the order of ``grades.csv``)."""
    esc = html.escape
    maximum = class_facts[0]["max_score"] if class_facts else 0
    tests = list(class_facts[0]["tests"]) if class_facts else []
    # not graded (the machine's fault): listed, but in no score, rate or count
    missed = [f for f in class_facts if f.get("not_graded")]
    class_facts = [f for f in class_facts if not f.get("not_graded")]
    n = len(class_facts)
    refused = [f for f in class_facts if f["refused"]]
    graded = n - len(refused)
    scores = [f["score"] for f in class_facts]
    passed = {t: sum(f["tests"].get(t) == "passed" for f in class_facts) for t in tests}
    counts: Counter[str] = Counter()
    first: dict[str, dict[str, str]] = {}
    for f in class_facts:
        for m in f["mistakes"]:
            counts[m["key"]] += 1
            first.setdefault(m["key"], m)
    top = counts.most_common(TOP)
    mean = sum(scores) / n if n else 0.0
    parts = [
        f"<h1>{esc(assignment.key)} · {esc(assignment.title)}: class summary</h1>",
        f"<p>{n + len(missed)} submissions, {graded} graded, {len(refused)} refused"
        + (f", {len(missed)} not graded (the machine's fault: grade again with --resume)"
           if missed else "") + f"; mean score {mean:.2f} / {maximum:g}.</p>",
        "<h2>Scores</h2>", _img(_histogram_png(scores, maximum), "score histogram"),
        "<h2>Pass rate per test</h2>",
        f"<p>Of the {graded} graded submissions, how many pass each test in full.</p>",
        _img(_bars_png([(t, passed[t]) for t in tests], graded, "submissions passing"),
             "pass rate per test"),
        "<table><tr><th>test</th><th>passed</th><th>rate</th></tr>"
        + "".join(f"<tr><td>{esc(t)}</td><td>{passed[t]} / {graded}</td>"
                  f"<td>{_rate(passed[t], graded)}</td></tr>" for t in tests) + "</table>",
        "<h2>Most frequent mistakes</h2>",
    ]
    if top:
        parts.append(_img(_bars_png([(k, c) for k, c in top], n, "submissions showing it"),
                          "most frequent mistakes"))
        parts.append(
            "<table><tr><th>mistake</th><th>test</th><th>submissions</th><th>an example</th></tr>"
            + "".join(f"<tr><td><b>{esc(first[k]['title'])}</b><br><code>{esc(k)}</code></td>"
                      f"<td>{esc(first[k]['test'])}</td><td>{c}</td>"
                      f"<td><code>{esc(first[k]['example'])}</code></td></tr>" for k, c in top)
            + "</table>")
    else:
        parts.append("<p>No catalogued mistake was found.</p>")
    if refused:
        parts.append("<h2>Refused submissions</h2><table><tr><th>submission</th>"
                     "<th>reason</th></tr>"
                     + "".join(f"<tr><td>{esc(f['name'])}</td><td>{esc(f['refused'])}</td></tr>"
                               for f in refused) + "</table>")
    if missed:
        parts.append("<h2>Not graded</h2><table><tr><th>submission</th><th>why</th></tr>"
                     + "".join(f"<tr><td>{esc(f['name'])}</td><td>{esc(f['not_graded'])}</td>"
                               "</tr>" for f in missed) + "</table>")
    style = ("body{font-family:sans-serif;max-width:60em;margin:1em auto}"
             "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:2px 6px;"
             "text-align:left;vertical-align:top}")
    title = esc(f"{assignment.key}: class summary")
    return (f"<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>{title}</title>"
            f"<style>{style}</style></head><body>\n" + "\n".join(parts) + "\n</body></html>\n")


def _rate(k: int, n: int) -> str:
    return f"{100 * k / n:.0f} %" if n else "–"


def _img(png: str, alt: str) -> str:
    return f"<p><img alt='{alt}' src='data:image/png;base64,{png}'></p>"


def _histogram_png(scores: list[float], maximum: float) -> str:
    fig = figure((6, 2.6))
    ax = fig.add_subplot()
    top = max([maximum, *scores, 1.0])
    ax.hist(scores, bins=min(20, max(5, int(top) * 2)), range=(0, top), color="#1f6fd1",
            edgecolor="white")
    ax.set_xlabel(f"score (of {maximum:g})")
    ax.set_ylabel("submissions")
    # The default AutoLocator is a MaxNLocator, which takes integer=; Locator's stub does not.
    ax.yaxis.get_major_locator().set_params(integer=True)  # type: ignore[call-arg]  # counts
    return png(fig)


def _bars_png(bars: list[tuple[str, int]], total: int, label: str) -> str:
    """Horizontal bars, the first on top, of counts out of ``total``."""
    fig = figure((6, 0.8 + 0.3 * len(bars)))
    ax = fig.add_subplot()
    names = [bounded(name, 40) for name, _ in bars][::-1]
    ax.barh(range(len(bars)), [c for _, c in bars][::-1], color="#1a7f37")
    ax.set_yticks(range(len(bars)), names)
    ax.set_xlim(0, max(total, 1))
    ax.set_xlabel(f"{label} (of {total})")
    ax.xaxis.get_major_locator().set_params(integer=True)  # type: ignore[call-arg]  # as above
    return png(fig)
