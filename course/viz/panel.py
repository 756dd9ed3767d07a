"""The pieces every control panel is laid out from, and how it listens to its widgets.

A panel keeps its size whatever its readouts say (reserved heights, fixed rows), and every
widget event runs on the thread that renders (:func:`~course.viz.backend.latest_on_gl_thread`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import ipywidgets as widgets

from .backend import latest_on_gl_thread


def slider_style(readout_format: str = ".0f") -> dict[str, Any]:
    """Common slider options (a fresh Layout each time: widgets must not share one)."""
    return {"continuous_update": True, "readout_format": readout_format,
            "style": {"description_width": "80px"}, "layout": widgets.Layout(width="340px")}


def readout_box(lines: int, width: str | None = None) -> widgets.HTML:
    """An HTML readout whose height is reserved for ``lines`` lines: a longer or shorter
    text never moves the view or the controls below it (it scrolls instead). Without a
    ``width`` it spans its panel."""
    height = f"{1.75 * lines + 0.4:.2f}em"
    return widgets.HTML(layout=widgets.Layout(height=height, min_height=height, width=width,
                                              overflow="auto", flex="0 0 auto"))


def fixed_height(widget: widgets.Widget, height: str = "32px") -> widgets.Widget:
    """A button or row that a panel of limited height never squashes."""
    widget.layout.height = height
    widget.layout.min_height = height
    widget.layout.flex = "0 0 auto"
    return widget


def on_value(widget: widgets.Widget, handler: Callable[..., None]) -> None:
    """Call ``handler(change)`` when ``widget.value`` changes, on the thread that renders
    (``change``: traitlets' mapping, ``change["new"]`` the new value). The handler may take
    more arguments with defaults: a loop binds its index so."""
    widget.observe(latest_on_gl_thread(handler), names="value")
