"""The hint button of an exercise: a hint first, then the formula, never the answer."""

from __future__ import annotations

import re
from typing import Any

from .registry import exercise


def in_kernel() -> bool:
    """Whether this runs in a Jupyter kernel (where widgets show), not a plain interpreter."""
    try:
        from IPython import get_ipython
    except ImportError:
        return False
    shell = get_ipython()
    return shell is not None and hasattr(shell, "kernel")


def hint(key: str) -> Any:
    """A button that reveals exercise ``key``'s hint, then (pressed again) its formula.

    Outside a kernel (a script, a headless run) it returns both as text instead.
    """
    ex = exercise(key)
    if not in_kernel():
        return re.sub(r"<[^>]+>", "", f"hint: {ex.hint}\nformula: {ex.formula}")
    import ipywidgets as widgets

    button = widgets.Button(description="💡 hint", layout=widgets.Layout(width="auto"))
    shown = widgets.HTMLMath()
    steps = iter([("💡 hint", ex.hint, "show the formula"),
                  ("formula", ex.formula, None)])

    def reveal(_: Any) -> None:
        label, text, next_label = next(steps)
        shown.value = (shown.value + "<br>" if shown.value else "") + f"<b>{label}:</b> {text}"
        button.description = next_label or "no more hints"
        button.disabled = next_label is None

    button.on_click(reveal)
    return widgets.VBox([button, shown])
