"""Interactive figures for the keyframes notebook: Runge's oscillation and the spline family.

Each explorer is a matplotlib figure drawn by Agg and shown as an ``ipywidgets.Image``
beside its sliders. Redraws blit: the static part (axes, grid, the function being
approximated) is rendered once and cached; a slider change restores it and draws only the
curves that moved (``animated=True`` artists), then sends the canvas as a PNG. Setting a
slider's ``.value`` from code runs the same update, so the notebook and tests can drive them.
Imported on its own (``from course.viz.keyframe_plots import ...``): matplotlib and
ipywidgets are not loaded by ``import course.keyframes``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import ipywidgets as widgets
import numpy as np
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from ..keyframes.curves import bezier, catmull_rom, cubic, linear, polynomial
from .chain_plots import style_axes
from .figures import Blitter, agg_figure, figure_png

SCHEME_COLORS = {
    "linear": "#4a5561",
    "cubic (natural)": "#3d7dca",
    "Catmull–Rom": "#e5484d",
    "Bézier (keys as control points)": "#2bb673",
    "polynomial": "#8e6bd8",
}


def spline_family(keys: ArrayLike, times: ArrayLike, t: ArrayLike,
                  derivative: int = 0) -> dict[str, np.ndarray]:
    """Every scheme of the family on the same keys: name -> values (or derivative) at ``t``.

    The Bézier curve takes the keys as its control points over ``[t_0, t_{K-1}]`` (its
    derivative in time is its derivative in ``s`` over the duration)."""
    keys, times, t = (np.asarray(a, dtype=np.float64) for a in (keys, times, t))
    span = times[-1] - times[0]
    return {
        "linear": linear(keys, times, t, derivative=derivative),
        "cubic (natural)": cubic(keys, times, t, derivative=derivative),
        "Catmull–Rom": catmull_rom(keys, times, t, derivative=derivative),
        "Bézier (keys as control points)":
            bezier(keys, (t - times[0]) / span, derivative=derivative) / span**derivative,
        "polynomial": polynomial(keys, times, t, derivative=derivative),
    }


class _BlitImage:
    """A blitted figure (:class:`~course.viz.figures.Blitter`) sent as an ``ipywidgets.Image``."""

    def __init__(self, figure: Figure, artists: Sequence[Any]) -> None:
        self.blitter = Blitter(figure, artists)
        self.image = widgets.Image(format="png", width=int(figure.get_figwidth() * 90))

    def redraw(self) -> None:
        self.blitter.blit()
        self.image.value = figure_png(self.blitter.figure)


def _figure(width: float, height: float, rows: int = 1) -> tuple[Figure, Any]:
    figure = agg_figure((width, height), dpi=90)
    axes = figure.subplots(rows, 1, sharex=True)
    for ax in np.atleast_1d(axes):
        style_axes(ax)  # the notebooks' look, without pyplot's global rcParams
    return figure, axes


class RungeExplorer:
    """Interpolating :math:`f(x) = 1/(1+25x^2)` at ``n`` equally spaced keys on [-1, 1]: the
    polynomial through all keys against the natural cubic spline. Drag the slider."""

    def __init__(self, n: int = 7, max_keys: int = 21) -> None:
        self.x = np.linspace(-1, 1, 801)
        f = 1 / (1 + 25 * self.x**2)
        self.figure, ax = _figure(7.5, 3.6)
        ax.plot(self.x, f, color="#2b3440", lw=1.2, label="$1/(1+25x^2)$")
        ax.set(xlim=(-1.05, 1.05), ylim=(-1.2, 2.0), xlabel="x")
        (self.poly,) = ax.plot([], [], color=SCHEME_COLORS["polynomial"], lw=2, animated=True,
                               label="polynomial through all keys")
        (self.spline,) = ax.plot([], [], color=SCHEME_COLORS["cubic (natural)"], lw=2,
                                 animated=True, label="natural cubic spline")
        (self.keys,) = ax.plot([], [], "o", color="#f08c3a", ms=6, animated=True, label="keys")
        self.text = ax.text(0.02, 0.96, "", transform=ax.transAxes, va="top", animated=True)
        ax.legend(loc="upper right", frameon=False, fontsize=9)
        self.canvas = _BlitImage(self.figure, (self.poly, self.spline, self.keys, self.text))
        self.slider = widgets.IntSlider(value=n, min=3, max=max_keys, description="keys n")
        self.slider.observe(lambda _: self.update(), names="value")
        self.widget = widgets.VBox([self.slider, self.canvas.image])
        self.update()

    def errors(self, n: int) -> tuple[float, float]:
        """Largest error of the polynomial and of the spline over [-1, 1] for ``n`` keys."""
        keys_x = np.linspace(-1, 1, n)
        keys = 1 / (1 + 25 * keys_x**2)
        f = 1 / (1 + 25 * self.x**2)
        return (float(np.abs(polynomial(keys, keys_x, self.x) - f).max()),
                float(np.abs(cubic(keys, keys_x, self.x) - f).max()))

    def update(self) -> None:
        n = self.slider.value
        keys_x = np.linspace(-1, 1, n)
        keys = 1 / (1 + 25 * keys_x**2)
        self.poly.set_data(self.x, polynomial(keys, keys_x, self.x))
        self.spline.set_data(self.x, cubic(keys, keys_x, self.x))
        self.keys.set_data(keys_x, keys)
        poly_err, spline_err = self.errors(n)
        self.text.set_text(f"n = {n}: max error polynomial {poly_err:.3g}, spline {spline_err:.3g}")
        self.canvas.redraw()

    def _ipython_display_(self) -> None:
        from IPython.display import display

        display(self.widget)


class SplineExplorer:
    """The spline family through the same keys, with a slider per key value: position,
    velocity and acceleration stacked, so each scheme's continuity (C⁰, C¹, C²) shows as
    kinks and jumps at the keys (dotted verticals)."""

    def __init__(self, keys: ArrayLike, times: ArrayLike,
                 schemes: Sequence[str] = ("linear", "cubic (natural)", "Catmull–Rom",
                                           "Bézier (keys as control points)")) -> None:
        self.times = np.asarray(times, dtype=np.float64)
        self.t = np.linspace(self.times[0], self.times[-1], 600)
        self.schemes = tuple(schemes)
        self.figure, axes = _figure(7.5, 6.4, rows=3)
        labels = ("position p(t)", "velocity p'(t)", "acceleration p''(t)")
        self.lines: list[dict[str, Any]] = []
        for d, (ax, label) in enumerate(zip(axes, labels, strict=True)):
            for x in self.times:
                ax.axvline(x, color="#c9d1da", lw=0.8, ls=":")
            # fixed limits (a blitted view does not rescale): the sliders' range for positions,
            # twice the first curves' reach for their derivatives
            curves = spline_family(keys, self.times, self.t, d)
            reach = 0.75 if d == 0 else max(np.abs(curves[n]).max() for n in self.schemes)
            ax.set(ylim=(-2 * reach, 2 * reach), ylabel=label)
            self.lines.append({name: ax.plot([], [], color=SCHEME_COLORS[name], lw=1.8,
                                             animated=True, label=name)[0]
                               for name in self.schemes})
        axes[0].legend(loc="upper left", frameon=False, fontsize=8, ncol=2)
        axes[-1].set_xlabel("t")
        (self.markers,) = axes[0].plot([], [], "o", color="#f08c3a", ms=7, animated=True)
        artists = [line for row in self.lines for line in row.values()] + [self.markers]
        self.canvas = _BlitImage(self.figure, artists)
        self.sliders = [
            widgets.FloatSlider(value=float(v), min=-1.2, max=1.2, step=0.05,
                                orientation="vertical", description=f"p{i}",
                                layout=widgets.Layout(height="170px"))
            for i, v in enumerate(np.asarray(keys, dtype=np.float64))
        ]
        for s in self.sliders:
            s.observe(lambda _: self.update(), names="value")
        self.widget = widgets.HBox([widgets.HBox(self.sliders), self.canvas.image])
        self.update()

    @property
    def keys(self) -> np.ndarray:
        return np.array([s.value for s in self.sliders])

    def update(self) -> None:
        keys = self.keys
        for d, row in enumerate(self.lines):
            curves = spline_family(keys, self.times, self.t, derivative=d)
            for name, line in row.items():
                line.set_data(self.t, curves[name])
        self.markers.set_data(self.times, keys)
        self.canvas.redraw()

    def _ipython_display_(self) -> None:
        from IPython.display import display

        display(self.widget)
