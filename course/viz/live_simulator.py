"""A simulation played live beside its 3D view: play/pause, one step, reset and a readout.

:class:`LiveSimulator` is what :class:`~course.viz.cloth.ClothSimulator` and
:class:`~course.viz.rigid_body_view.RigidBodySimulator` share: the buttons and the readout, the
panel of controls at a fixed width beside the view, and how many steps of the time step ``h``
one tick of play takes. A subclass builds its scene and its sliders, then hands them over;
it steps (:meth:`LiveSimulator.advance`), starts again (:meth:`LiveSimulator.reset`) and
writes the readout (:meth:`LiveSimulator._show`). As in every view of :mod:`course.viz`, every
widget event runs on the GL thread (:func:`~course.viz.backend.latest_on_gl_thread`), and
setting a widget's value from code does what clicking it does.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from typing import Generic, TypeVar

import ipywidgets as widgets
import numpy as np

from .backend import latest_on_gl_thread
from .live_view import LiveView

S = TypeVar("S", bound=LiveView)


def log_slider(description: str, value: float, lo: float, hi: float, fmt: str
               ) -> widgets.FloatLogSlider:
    """A slider over ``[lo, hi]`` on a log scale, one value per release."""
    return widgets.FloatLogSlider(
        value=value, base=10, min=np.log10(lo), max=np.log10(hi), step=0.05,
        description=description, readout_format=fmt, continuous_update=False,
        style={"description_width": "90px"}, layout=widgets.Layout(width="360px"))


class LiveSimulator(ABC, Generic[S]):
    """Controls beside a live scene: play/pause (``widgets.Play``, ticking in the browser),
    one step, reset, the subclass's sliders and an HTML readout.

    Parameters
    ----------
    scene : the view, shown right of the controls at its window's width.
    sliders : the controls under the buttons; ``sliders["h"]`` is the time step (s), unless
        the subclass overrides :attr:`step_time`.
    buttons : more buttons, between "step" and "reset".
    speed : the simulated seconds per real second that play aims for (1.0: real time).
    max_steps_per_tick : the most steps one tick of play takes (the cost cap).
    interval : the time between two ticks of play (ms).
    window_size : (width, height) of the scene in pixels.
    """

    PANEL_WIDTH = 380  # px: the controls and the readout; fixed, so the view never moves

    def __init__(self, scene: S, sliders: Mapping[str, widgets.Widget], *,
                 buttons: Sequence[widgets.Button] = (), speed: float = 1.0,
                 max_steps_per_tick: int, interval: int, window_size: tuple[int, int]) -> None:
        self.scene = scene
        self.sliders = dict(sliders)
        self.speed, self.max_steps_per_tick = float(speed), int(max_steps_per_tick)
        self.play = widgets.Play(value=0, min=0, max=10**9, step=1, interval=int(interval),
                                 description="play")
        self.step_button = widgets.Button(description="step", icon="step-forward")
        self.reset_button = widgets.Button(description="reset", icon="undo")
        self._buttons = [self.play, self.step_button, *buttons, self.reset_button]
        width = f"{self.PANEL_WIDTH}px"  # long readout lines wrap inside it
        self.readout = widgets.HTML(layout=widgets.Layout(width=width, min_width=width))
        self.play.observe(latest_on_gl_thread(lambda _c: self.tick()), names="value")
        self.step_button.on_click(latest_on_gl_thread(lambda _b: self.advance(1)))
        self.reset_button.on_click(latest_on_gl_thread(lambda _b: self.reset()))
        self.panel = widgets.VBox([widgets.HBox(self._buttons), *self.sliders.values(),
                                   self.readout],
                                  layout=widgets.Layout(flex="0 0 auto", width=width,
                                                        min_width=width, margin="0 12px 0 0"))
        view = scene.widget()
        w = f"{window_size[0]}px"  # the view keeps its size whatever the readout says
        view.layout.width, view.layout.min_width, view.layout.flex = w, w, "0 0 auto"
        self.widget = widgets.HBox([self.panel, view], layout=widgets.Layout(
            align_items="flex-start", flex_flow="row wrap"))
        self.reset()

    def _ipython_display_(self) -> None:
        from IPython.display import display

        display(self.widget)

    @abstractmethod
    def reset(self) -> None:
        """Back to the first state, time 0."""

    @abstractmethod
    def advance(self, n: int = 1) -> None:
        """Take ``n`` steps and draw the result once."""

    @abstractmethod
    def _show(self) -> None:
        """Write the readout and render the scene."""

    @property
    def step_time(self) -> float:
        """Simulated seconds one step of :meth:`advance` takes: the ``h`` slider's value (a
        subclass whose steps are whole frames of a fixed length returns that)."""
        return float(self.sliders["h"].value)

    @property
    def steps_per_tick(self) -> int:
        """How many steps of :attr:`step_time` one tick of play takes: enough for ``speed``,
        capped."""
        wanted = self.speed * self.play.interval / 1000 / self.step_time
        return int(min(max(round(wanted), 1), self.max_steps_per_tick))

    @property
    def playback_speed(self) -> float:
        """Simulated seconds per real second while playing (1.0: real time)."""
        return float(self.steps_per_tick * self.step_time / (self.play.interval / 1000))

    def tick(self) -> None:
        """What one tick of play does: :attr:`steps_per_tick` steps, drawn once."""
        self.advance(self.steps_per_tick)

    def close(self) -> None:
        """Close the widgets and free the render window."""
        for w in (*self._buttons, *self.sliders.values(), self.readout, self.widget):
            w.close()
        self.scene.close()
