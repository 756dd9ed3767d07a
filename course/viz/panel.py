"""The pieces every control panel is laid out from, and how it listens to its widgets.

A panel keeps its size whatever its readouts say (reserved heights, fixed rows), and every
widget event runs on the thread that renders (:func:`~course.viz.backend.latest_on_gl_thread`).

The views (:mod:`~course.viz.rotation_views`, :mod:`~course.viz.fk_view`,
:mod:`~course.viz.clip_player`, :mod:`~course.viz.ik_playground_view`,
:mod:`~course.viz.full_body_ik_view`) are each a :class:`Control`, which displays itself in a
notebook and also works from code: ``.sliders`` (name -> widget), ``.readout`` (an HTML
widget with the numbers), ``.scene`` (the 3D view; e.g. ``.scene.joint_positions``) and
``.widget`` (the whole layout). Setting a slider's ``.value`` from code runs the same update
as dragging it, so tests and notebooks can drive them. Per event the math (FK, IK) runs once
on small arrays and the views are updated in place; clip playback is paced on the kernel's
event loop (one picture at a time, see :mod:`course.viz.playback`), so no cell ever blocks.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import ipywidgets as widgets
import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .backend import latest_on_gl_thread

if TYPE_CHECKING:
    from .scene import SkeletonScene


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


class Control:
    """Common shape of every control: a layout, its sliders, a readout and a scene."""

    widget: widgets.Widget
    sliders: dict[str, widgets.Widget]
    readout: widgets.HTML

    def _ipython_display_(self) -> None:
        from IPython.display import display

        display(self.widget)

    @classmethod
    def _widgets(cls, w: widgets.Widget) -> list[widgets.Widget]:
        return [w, *(x for c in getattr(w, "children", ()) for x in cls._widgets(c))]

    def close(self) -> None:
        """Close the widgets and free the render window."""
        for w in self._widgets(self.widget):
            w.close()
        scene = getattr(self, "scene", None)
        if scene is not None:
            scene.close()


# -- sliders and readouts ----------------------------------------------------------------------


def angle_slider(description: str, value: float = 0.0, limit: float = 180.0
                 ) -> widgets.FloatSlider:
    """A slider in degrees (what students read); the math converts to radians."""
    return widgets.FloatSlider(value=value, min=-limit, max=limit, step=1.0,
                               description=description, **slider_style())


def side_by_side(*children: widgets.Widget) -> widgets.HBox:
    """A row of panels that keep their width (the sliders and their numbers stay readable)
    beside views that shrink to fit a narrow notebook (see ``SkeletonScene.widget``); what
    does not fit wraps to the next line instead of leaving the output."""
    for child in children:
        if child.layout.min_width is None:  # a panel: fixed
            child.layout.flex = "0 0 auto"
            child.layout.margin = "0 12px 0 0"
    return widgets.HBox(list(children), layout=widgets.Layout(
        align_items="flex-start", flex_flow="row wrap", width="100%"))


def number(x: float, fmt: str = "+.3f") -> str:
    """``x`` in ``fmt``, and never ``-0.000`` (a tiny negative number, rounded)."""
    text = format(float(x), fmt)
    return format(0.0, fmt) if float(text) == 0 else text


def matrix_html(R: Array) -> str:
    """The rows of ``R`` as an HTML table of :func:`number` cells."""
    rows = "".join(
        "<tr>" + "".join(f"<td style='padding:0 8px;text-align:right'>{number(v)}</td>"
                         for v in r)
        + "</tr>" for r in R
    )
    return f"<table style='font-family:monospace'>{rows}</table>"


def iterations(n: int) -> str:
    """``"1 iteration"``, ``"12 iterations"``."""
    return f"{n} iteration{'' if n == 1 else 's'}"


def vec(v: ArrayLike, fmt: str = "+.3f") -> str:
    """``v``'s entries as ``(a, b, c)``, each a :func:`number`."""
    return "(" + ", ".join(number(x, fmt) for x in np.ravel(v)) + ")"


# -- an IK target: its x/y/z sliders, its drag pad, the methods --------------------------------


def set_sliders(sliders: dict[str, widgets.Widget], position: Array) -> None:
    """Put ``position (3,)`` into the x/y/z sliders, clipped to their ranges."""
    for k, c in enumerate("xyz"):
        s = sliders[c]
        s.value = float(np.clip(position[k], s.min, s.max))


def clipped_to_sliders(sliders: dict[str, widgets.Widget], position: Array) -> Array:
    """``position (3,)`` clipped to the ranges of the x/y/z sliders."""
    lo = np.array([sliders[c].min for c in "xyz"])
    hi = np.array([sliders[c].max for c in "xyz"])
    out: Array = np.clip(np.asarray(position, dtype=np.float64), lo, hi)
    return out


def snapped(slider: widgets.Widget, old: float, new: float) -> bool:
    """The browser moved ``old`` onto the slider's step grid (``min + n step``, the nearest
    point): it does so when it shows a value that lies between two steps, and sends the
    snapped value back. That is the same value to the student, not a move of theirs."""
    step = slider.step
    if not step:
        return False
    n = (new - slider.min) / step
    return bool(abs(new - old) <= step / 2 * (1 + 1e-9) and abs(n - round(n)) < 1e-6)


def ik_methods() -> tuple[str, ...]:
    """The methods course.ik.solve offers: its registry, :mod:`course.ik.methods`."""
    from course.ik.methods import METHODS

    return METHODS


def target_drag_pad(scene: SkeletonScene, center: ArrayLike, half: float | None,
                    position: ArrayLike, on_drag: Any, size: int = 180,
                    normal: Array | None = None, box: ArrayLike | None = None) -> Any:
    """A pad that drags the target in the plane the view's camera faces, or across
    ``normal`` (views that take no mouse: browser-rendered, static), see
    :mod:`course.viz.drag_pad`."""
    from .drag_pad import ViewPlaneDrag

    return ViewPlaneDrag(scene.plotter.camera, center, half, position, on_drag, size=size,
                         normal=normal, box=box)


# -- a chain's joints and the camera that faces them -------------------------------------------


def dof_axes(skeleton: Any, j: int) -> Array:
    """The rotation axes of joint j's sliders, ``(dof, 3)``, composed in order (intrinsic):
    a hinge has its axis, a universal joint its two axes, a ball joint z, y, x (BVH's
    ``Zrotation Yrotation Xrotation``); End Sites none."""
    types = getattr(skeleton, "joint_types", None)
    jt = types[j] if types is not None else None
    if jt is not None and getattr(jt, "dof", 3) == 0:
        return np.zeros((0, 3))
    if jt is not None and getattr(jt, "axis", None) is not None:
        return np.asarray(jt.axis, dtype=np.float64).reshape(1, 3)
    if jt is not None and getattr(jt, "axes", None) is not None:
        return np.asarray(jt.axes, dtype=np.float64).reshape(-1, 3)
    if skeleton.names[j].endswith("_end") and not skeleton.children(j):
        return np.zeros((0, 3))
    return np.eye(3)[[2, 1, 0]]


def hinge_plane_normal(skeleton: Any, joints: Sequence[int], orientations: Array
                       ) -> Array | None:
    """The world axis ``n`` of the hinges among ``joints`` when they all turn about it (a
    planar arm: what they move stays in planes across ``n``), else None (a ball or universal
    joint among them, hinges about two axes, no hinge). ``orientations``: the global
    orientations ``Q_j (J, 4)`` of the pose; a hinge's world axis is ``Q_j a_j``."""
    from course.rotations import quat_rotate

    axes = []
    for j in joints:
        a = dof_axes(skeleton, j)
        if len(a) > 1:
            return None
        if len(a):
            axes.append(quat_rotate(orientations[j], a[0] / np.linalg.norm(a[0])))
    if not axes or any(np.linalg.norm(np.cross(a, axes[0])) > 1e-9 for a in axes):
        return None
    n: Array = axes[0]
    return n


def ancestors(skeleton: Any, j: int) -> list[int]:
    """The joints above ``j``, from its parent to the root (those that move it)."""
    out = []
    while (j := int(skeleton.parents[j])) >= 0:
        out.append(j)
    return out


def facing_camera(normal: Array | None) -> str | None:
    """The camera preset that looks along ``normal`` (a world axis), if one does."""
    if normal is None:
        return None
    for preset, axis in (("front", 2), ("side", 0), ("top", 1)):
        if abs(normal[axis]) > 1 - 1e-9:
            return preset
    return None

