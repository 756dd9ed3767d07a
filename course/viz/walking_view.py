"""SIMBICON's walk seen from above, with sliders: speed, c_d, c_v and a push (notebook 15).

:class:`WalkingView` re-simulates a short walk (:func:`course.physics.walking.walk`, a few
simulated seconds, about a tenth of that in wall time) whenever a slider is released, and
draws the ground from above: the COM's path, the footsteps (where each swing ankle touched
down), the capture point :math:`\\xi = c + \\dot c/\\omega_0` along the way and where the push
came. The figure is matplotlib (Agg), shown as an ``ipywidgets.Image`` beside the sliders; the
run is drawn when it has ended, not while it simulates. Setting a slider's ``.value`` from
code runs the same update, so tests and notebooks can drive it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import ipywidgets as widgets
import numpy as np

from .._typing import Array
from .chain_plots import style_axes
from .figures import agg_figure, figure_png
from .panel import Control, fixed_height, on_value, readout_box, slider_style

G = 9.81
COLORS = {"com": "#3d7dca", "left": "#2bb673", "right": "#e5484d", "capture": "#f5a623",
          "push": "#8e6bd8"}


def capture_points(com: Array, frame_time: float, ground_height: float = 0.0) -> Array:
    """The capture point ``(F, 2)`` (x, z) of a recorded COM path ``com`` (F, 3) (y up, m):
    :math:`\\xi = c + \\dot c/\\omega_0`, the velocity by central differences,
    :math:`\\omega_0 = \\sqrt{g/h}` with :math:`h` the COM's height above the ground."""
    c = np.asarray(com, dtype=float)
    v = np.gradient(c, float(frame_time), axis=0)
    omega0 = np.sqrt(G / np.maximum(c[:, 1] - ground_height, 1e-3))
    out: Array = c[:, [0, 2]] + v[:, [0, 2]] / omega0[:, None]
    return out


class WalkingView(Control):
    """A short SIMBICON walk of ``character`` with sliders for the speed input, the sagittal
    feedback gains ``c_d`` and ``c_v`` and a forward push, drawn from above.

    Parameters
    ----------
    character : :class:`~course.physics.character.Character`
    duration : simulated seconds per run (keep it short: every release re-runs it).
    push_start, push_duration : when the push acts on the root (s).
    simulate : run once now.
    """

    def __init__(self, character: Any, *, duration: float = 4.0, push_start: float = 2.0,
                 push_duration: float = 0.1, simulate: bool = True) -> None:
        from course.physics.walking import Gait

        gait = Gait()
        self.character = character
        self.duration, self.push_start = float(duration), float(push_start)
        self.push_duration = float(push_duration)
        self.result: Any = None
        self.sliders = {
            "speed": widgets.FloatSlider(value=0.0, min=0.0, max=0.5, step=0.05,
                                         description="speed (m/s)", **slider_style(".2f")),
            "c_d": widgets.FloatSlider(value=gait.c_d, min=0.0, max=1.5, step=0.05,
                                       description="c_d", **slider_style(".2f")),
            "c_v": widgets.FloatSlider(value=gait.c_v, min=0.0, max=1.2, step=0.05,
                                       description="c_v", **slider_style(".2f")),
            "push": widgets.FloatSlider(value=0.0, min=-400.0, max=400.0, step=10.0,
                                        description="push (N)", **slider_style(".0f")),
        }
        for s in self.sliders.values():
            s.continuous_update = False  # one run per release
            on_value(s, lambda _c: self.simulate())
        self.readout = readout_box(3)
        self.figure = agg_figure((6.4, 4.2), dpi=90)
        self.ax = self.figure.subplots()
        self.image = widgets.Image(format="png", width=int(6.4 * 90))
        self.button = fixed_height(widgets.Button(description="simulate again", icon="play",
                                                  layout=widgets.Layout(width="160px")))
        self.button.on_click(lambda _b: self.simulate())
        width = "360px"
        note = widgets.HTML("speed 0: SIMBICON's own c_v·v; push: forward (+) or back (−), "
                            f"{self.push_duration:g} s at {self.push_start:g} s")
        panel = widgets.VBox([*self.sliders.values(), note, self.button, self.readout],
                             layout=widgets.Layout(flex="0 0 auto", width=width,
                                                   min_width=width, margin="0 12px 0 0"))
        self.widget = widgets.HBox([panel, self.image], layout=widgets.Layout(
            align_items="flex-start", flex_flow="row wrap"))
        if simulate:
            self.simulate()

    def settings(self) -> dict[str, Any]:
        """The keyword arguments of :func:`~course.physics.walking.walk` the sliders set."""
        from course.physics.simulation import Push
        from course.physics.walking import Gait

        speed = float(self.sliders["speed"].value)
        force = float(self.sliders["push"].value)
        push = (Push(self.character.skeleton.names[0], (0.0, 0.0, force), self.push_start,
                     self.push_duration) if force != 0 else None)
        return {"duration": self.duration, "speed": speed if speed > 0 else None,
                "gait": Gait(c_d=float(self.sliders["c_d"].value),
                             c_v=float(self.sliders["c_v"].value)),
                "push": push}

    def simulate(self) -> None:
        """Run the walk with the sliders' settings and draw it."""
        from course.physics.walking import walk

        self.readout.value = "simulating &hellip;"
        self.result = walk(self.character, **self.settings())
        self.draw()

    def draw(self) -> None:
        r, ax = self.result, self.ax
        ax.clear()
        style_axes(ax)
        com = r.com
        ax.plot(com[:, 2], com[:, 0], color=COLORS["com"], lw=1.2, label="COM")
        xi = capture_points(com, r.motion.frame_time)
        ax.plot(xi[:, 1], xi[:, 0], color=COLORS["capture"], lw=0.8, alpha=0.8,
                label="capture point ξ")
        ax.plot(xi[-1, 1], xi[-1, 0], "x", color=COLORS["capture"], ms=9, mew=2)
        for side in ("left", "right"):
            p = np.array([f.position for f in r.footsteps if f.side == side]).reshape(-1, 3)
            ax.scatter(p[:, 2], p[:, 0], marker="s" if side == "left" else "o", s=22,
                       color=COLORS[side], label=f"{side} foot down", zorder=3)
        push = self.settings()["push"]
        if push is not None:
            k = min(int(round(self.push_start / r.motion.frame_time)), len(com) - 1)
            ax.annotate("push", (com[k, 2], com[k, 0]), xytext=(0, 18),
                        textcoords="offset points", color=COLORS["push"], ha="center",
                        arrowprops={"arrowstyle": "->", "color": COLORS["push"]})
        ax.set(xlabel="z, forward (m)", ylabel="x, left (m)", aspect="equal",
               title="from above: footsteps, COM, capture point")
        ax.legend(frameon=False, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16),
                  ncols=4)
        self.figure.canvas.draw()
        self.image.value = figure_png(self.figure)
        t = r.fall_time if r.fell else r.sim_time
        state = f"fell at {r.fall_time:.2f} s" if r.fell else "still walking"
        self.readout.value = (f"{r.sim_time:.1f} s simulated in {r.wall_time:.2f} s: {state}"
                              f"<br>{r.strides} strides, {len(r.footsteps)} steps, "
                              f"{(com[-1, 2] - com[0, 2]) / t:+.2f} m/s forward")


def walking_view(character: Any, **kwargs: Any) -> WalkingView:
    """A :class:`WalkingView` of ``character``, its first walk simulated."""
    return WalkingView(character, **kwargs)


__all__: Sequence[str] = ("WalkingView", "capture_points", "walking_view")
