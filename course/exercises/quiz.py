"""Predict, then run: a question with a few choices, answered before the experiment.

The answer and its explanation stay hidden until the student commits: they live in the widget's
Python callbacks, never in a displayed output. A right first choice reveals the explanation; a
wrong first choice only says "not quite — try again" with a hint; the answer and the explanation
show after the second choice, or when the student presses "show me".
"""

from __future__ import annotations

import html
from collections.abc import Sequence
from typing import Any

from .hints import in_kernel

TRY_AGAIN = "Not quite — try again."
DEFAULT_HINT = "Picture what the next cell will measure, and which choice it would contradict."


def quiz(key: str, question: str, choices: Sequence[str], answer: int | str,
         why: str, hint: str = DEFAULT_HINT) -> Any:
    """Ask ``question``; the answer and ``why`` show only once the student has committed.

    Parameters
    ----------
    key : str
        The quiz's name, ``"<notebook>.<name>"`` (``"05.first_sweep"``).
    question : str
        One question, about what the next cell will measure.
    choices : sequence of str
        Two to five possible answers.
    answer : int or str
        The right choice: its index, or its text.
    why : str
        One or two sentences on why (HTML and ``$...$`` math allowed). Shown after a right
        choice, after a second choice, or on "show me"; never before.
    hint : str
        Shown after a wrong first choice, with "not quite — try again"; it must not give the
        answer away.

    Returns
    -------
    ipywidgets.VBox or None
        In a kernel, the widget: the question, the choices, a "show me" button and the verdict
        (empty until the student commits). Elsewhere the question and choices are printed (never
        waiting for input, never the answer) and nothing is returned.
    """
    choices = list(choices)
    right = choices.index(answer) if isinstance(answer, str) else int(answer)
    if not 2 <= len(choices) <= 5 or not 0 <= right < len(choices):
        raise ValueError(f"quiz {key!r}: give 2 to 5 choices and the index or text of one")
    letters = "abcde"
    if not in_kernel():
        print(f"🤔 {question}")
        for letter, choice in zip(letters, choices, strict=False):
            print(f"   ({letter}) {choice}")
        print("   (choose in Jupyter to see the answer)")
        return None
    import ipywidgets as widgets

    buttons = widgets.RadioButtons(options=[(f"({a}) {c}", i) for i, (a, c)
                                            in enumerate(zip(letters, choices, strict=False))],
                                   value=None, layout=widgets.Layout(width="auto"))
    show = widgets.Button(description="show me", tooltip="reveal the answer and why")
    verdict = widgets.HTMLMath()
    tries = []  # the choices made so far

    def answered(picked: int | None) -> str:
        solution = f"the answer is ({letters[right]}) {html.escape(choices[right])}."
        if picked == right:
            return f"<b>✓ Right.</b> {why}"
        if picked is None:
            return f"<b>{solution[0].upper() + solution[1:]}</b> {why}"
        return f"<b>✗ Not this one either: {solution}</b> {why}"

    def reveal(text: str) -> None:
        verdict.value = text
        buttons.disabled = show.disabled = True

    def chose(change: dict[str, Any]) -> None:
        if change["new"] is None or buttons.disabled:
            return
        tries.append(change["new"])
        if change["new"] == right or len(tries) >= 2:
            reveal(answered(change["new"]))
        else:
            verdict.value = f"<b>✗ {TRY_AGAIN}</b> Hint: {hint}"

    buttons.observe(chose, names="value")
    show.on_click(lambda _: reveal(answered(None)))
    return widgets.VBox([widgets.HTMLMath(f"<b>🤔 Predict first:</b> {question}"), buttons,
                         show, verdict])
