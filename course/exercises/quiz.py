"""Predict, then run: a question with a few choices, answered before the experiment."""

from __future__ import annotations

import html
from collections.abc import Sequence
from typing import Any

from .hints import in_kernel


def quiz(key: str, question: str, choices: Sequence[str], answer: int | str,
         why: str) -> Any:
    """Ask ``question``; the answer and ``why`` show only once the student has chosen.

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
        One or two sentences on why (HTML and ``$...$`` math allowed).

    Returns
    -------
    ipywidgets.VBox or None
        In a kernel, the widget; elsewhere the question and choices are printed (never
        waiting for input) and nothing is returned.
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
    verdict = widgets.HTMLMath()

    def reveal(change: dict[str, Any]) -> None:
        if change["new"] is None:
            return
        mark = ("✓ Right." if change["new"] == right
                else f"✗ Not this one: the answer is ({letters[right]}) "
                     f"{html.escape(choices[right])}.")
        verdict.value = f"<b>{mark}</b> {why}"

    buttons.observe(reveal, names="value")
    return widgets.VBox([widgets.HTMLMath(f"<b>🤔 Predict first:</b> {question}"), buttons,
                         verdict])
