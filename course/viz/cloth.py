"""A live cloth: a pyvista mesh of a mass–spring cloth, updated in place, with controls.

:class:`ClothScene` draws a :class:`course.physics.Cloth` as one quad mesh whose point array is
overwritten on every step (smooth normals are recomputed by a VTK filter downstream; nothing
is rebuilt), with its pinned corners as spheres. :class:`ClothSimulator` adds the controls:
stiffness and time-step sliders, the integrator, play/pause (``widgets.Play``, ticking in the
browser), single steps and a reset, and a readout with the energy and the Newton statistics
of each implicit step. As in every view of :mod:`course.viz`, every widget event runs on the GL
thread (:func:`~course.viz.backend.latest_on_gl_thread`), and setting a widget's value from
code does what clicking it does.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import ipywidgets as widgets
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .backend import configure_environment, latest_on_gl_thread
from .live_simulator import LiveSimulator, log_slider
from .live_view import LiveView, shade
from .meshes import as_positions, move_points
from .scene import PALETTE

configure_environment()

import pyvista as pv  # noqa: E402  (after the environment is set: VTK reads it on import)
from vtkmodules.vtkFiltersCore import vtkPolyDataNormals  # noqa: E402
from vtkmodules.vtkRenderingCore import vtkPolyDataMapper  # noqa: E402

if TYPE_CHECKING:
    from course.physics import NewtonStats

Array = NDArray[np.float64]

FRONT, BACK = PALETTE[0][0], PALETTE[0][1]  # blue above, amber below: the fold is readable
PIN_COLOR = "#e5484d"


class ClothScene(LiveView):
    """A cloth in 3D, its points overwritten in place by :meth:`set_positions`.

    A :class:`~course.viz.live_view.LiveView`: the backend choice, rendering, :meth:`widget`,
    :meth:`show`, :meth:`screenshot` and :meth:`close` are every scene's.

    Parameters
    ----------
    cloth : a :class:`course.physics.Cloth` (its quads and pinned particles are drawn).
    positions : (N, 3) the first state; default the cloth's rest positions.
    window_size : (width, height) in pixels.
    """

    def __init__(self, cloth: Any, positions: ArrayLike | None = None, *,
                 window_size: tuple[int, int] = (640, 480)) -> None:
        super().__init__(window_size)
        x = cloth.positions if positions is None else positions
        faces = np.column_stack([np.full(len(cloth.quads), 4), cloth.quads]).ravel()
        self.mesh = pv.PolyData(self._checked(x, cloth.n_particles).copy(), faces=faces)
        normals = vtkPolyDataNormals()  # re-run by VTK whenever the points change
        normals.SetInputData(self.mesh)
        normals.SplittingOff()
        normals.ConsistencyOff()  # the grid's quads already agree on their orientation
        mapper = vtkPolyDataMapper()
        mapper.SetInputConnection(normals.GetOutputPort())
        mapper.ScalarVisibilityOff()
        self.actor = pv.Actor(mapper=mapper)
        shade(self.actor, FRONT, specular=0.15)
        back = pv.Property()
        back.color, back.ambient, back.diffuse = BACK, 0.18, 0.85
        self.actor.backface_prop = back
        self.plotter.add_actor(self.actor, reset_camera=False, pickable=False)
        size = float(np.ptp(cloth.positions, axis=0).max())
        pins = cloth.positions[cloth.system.fixed]
        if len(pins):  # they never move: glyphed once
            balls = pv.PolyData(pins).glyph(geom=pv.Sphere(radius=0.025 * size), scale=False,
                                            orient=False)
            self.plotter.add_mesh(balls, color=PIN_COLOR, smooth_shading=True, specular=0.35,
                                  reset_camera=False, pickable=False)
        self._frame_cloth(cloth, size)

    @staticmethod
    def _checked(x: ArrayLike, n: int) -> Array:
        p = np.asarray(x, dtype=np.float64)
        if p.shape != (n, 3):
            raise ValueError(f"positions must have shape ({n}, 3), got {p.shape}")
        return p

    def _frame_cloth(self, cloth: Any, size: float) -> None:
        """An iso view of the box the cloth can swing through: from its pins down one length."""
        lo, hi = cloth.positions.min(axis=0), cloth.positions.max(axis=0)
        lo = np.minimum(lo, [lo[0], hi[1] - 1.1 * size, lo[2] - 0.5 * size])
        hi = np.maximum(hi, [hi[0], hi[1], hi[2] + 0.2 * size])
        center, radius = (lo + hi) / 2, float(np.linalg.norm(hi - lo)) / 2
        d = np.array([0.8, 0.45, 1.0]) / np.linalg.norm([0.8, 0.45, 1.0])
        self.plotter.camera.view_angle = 30.0
        self._look_at(center, center + 0.8 * radius / np.sin(np.radians(15.0)) * d, (0, 1, 0))

    @property
    def positions(self) -> Array:
        """The drawn positions ``(N, 3)`` (a copy)."""
        return np.array(self.mesh.points, dtype=np.float64)

    def set_positions(self, positions: ArrayLike, *, render: bool = True) -> None:
        """Overwrite the mesh's points (the same arrays: nothing is re-created)."""
        move_points(self.mesh, as_positions(positions, self.mesh.n_points))
        if render:
            self.render()


class ClothSimulator(LiveSimulator[ClothScene]):
    """A cloth simulated live: sliders for the stiffness ``k`` and the time step ``h``, the
    integrator, play/pause, one step, reset; the readout shows the time, the energy and, for
    implicit Euler, each step's Newton iterations, line-search backtracks and ``‖∇E‖``.

    Parameters
    ----------
    cloth : a :class:`course.physics.Cloth`.
    method : ``"implicit"``, ``"symplectic"`` or ``"explicit"``.
    h : the first time step (s).
    speed : the simulated seconds per real second that play aims for (1.0: real time). Each
        tick of play (every ``interval`` ms) takes as many steps of ``h`` as that needs, at
        least one and at most ``max_steps_per_tick`` (the cost cap): at a small ``h`` play is
        slower than ``speed``, and the readout says so ("0.05× real time").
    """

    def __init__(self, cloth: Any, *, method: str = "implicit", h: float = 1 / 60,
                 speed: float = 1.0, max_steps_per_tick: int = 10, interval: int = 40,
                 window_size: tuple[int, int] = (640, 480)) -> None:
        from course.physics import METHODS

        if method not in METHODS:
            raise ValueError(f"method: must be one of {METHODS}, got {method!r}")
        self.base = cloth
        self.cloth = cloth
        if not speed > 0 or int(max_steps_per_tick) < 1 or int(interval) < 1:
            raise ValueError("speed, max_steps_per_tick and interval must be positive")
        self.last: NewtonStats | None = None  # the statistics of the last implicit step
        sliders = {
            "stiffness": log_slider("stiffness k", cloth.stiffness, 10.0, 1e5, ".0f"),
            "h": log_slider("time step h", h, 1e-4, 0.1, ".4f"),
            "method": widgets.Dropdown(options=list(METHODS), value=method,
                                       description="integrator",
                                       style={"description_width": "90px"},
                                       layout=widgets.Layout(width="260px")),
        }
        sliders["stiffness"].observe(latest_on_gl_thread(self._stiffness_changed), names="value")
        for name in ("h", "method"):  # (h changes the steps per tick: shown)
            sliders[name].observe(latest_on_gl_thread(lambda _c: self._show()), names="value")
        super().__init__(ClothScene(cloth, window_size=window_size), sliders, speed=speed,
                         max_steps_per_tick=max_steps_per_tick, interval=interval,
                         window_size=window_size)

    def _stiffness_changed(self, change: Mapping[str, float]) -> None:
        self.cloth = self.base.with_stiffness(change["new"])
        self._show()

    def reset(self) -> None:
        """Back to the flat cloth at rest, time 0."""
        self.x = self.cloth.positions.copy()
        self.v = np.zeros_like(self.x)
        self.time, self.steps, self.last = 0.0, 0, None
        self.exploded = False
        self.scene.set_positions(self.x, render=False)
        self._show()

    def advance(self, n: int = 1) -> None:
        """Take ``n`` steps and draw the result once."""
        from course.physics import step

        if self.exploded:
            return
        h, method = self.sliders["h"].value, self.sliders["method"].value
        with np.errstate(over="ignore", invalid="ignore"):
            for _ in range(n):
                x, v, stats = step(self.cloth.system, self.x, self.v, h, method)
                if not (np.all(np.isfinite(x)) and np.abs(x).max() < 1e3):
                    self.exploded = True  # stop here: a blown-up state cannot be drawn
                    self.play.playing = False
                    break
                self.x, self.v, self.last = x, v, stats
                self.time += h
                self.steps += 1
        self.scene.set_positions(self.x, render=False)
        self._show()

    def _show(self) -> None:
        # every term, so the parts add up to E; round(., 4) + 0.0 prints no "-0.0000"
        e = self.cloth.system.energy(self.x, self.v)
        total, kinetic, spring, gravity = (round(v, 4) + 0.0
                                           for v in (e.total, e.kinetic, e.spring, e.gravity))
        speed = self.playback_speed
        lines = [f"t = {self.time:.3f} s simulated ({self.steps} steps)",
                 f"play: {self.steps_per_tick} steps of h per tick, {speed:.2g}× real time"
                 + (f" (capped at {self.max_steps_per_tick} steps per tick)"
                    if speed < 0.99 * self.speed else ""),
                 f"energy E = {total:+.4f} J = kinetic {kinetic:.4f} + spring {spring:.4f} "
                 f"+ gravity ({gravity:+.4f})"]
        if self.last is not None:
            s = self.last
            lines.append(f"Newton: {s.iterations} iterations, {s.backtracks} backtracks, "
                         f"‖∇E‖ = {s.gradient_norm:.1e}"
                         + (f", PD fix ×{s.pd_fixes}" if s.pd_fixes else ""))
        if self.exploded:
            lines.append("<b style='color:#e5484d'>exploded: the step was unstable; "
                         "reset, and try a smaller h or implicit Euler</b>")
        self.readout.value = "<br>".join(lines)
        self.scene.render()


def cloth_simulator(cloth: Any | None = None, **kwargs: Any) -> ClothSimulator:
    """A live cloth (default: a 20×20 cloth pinned at two corners): see :class:`ClothSimulator`."""
    if cloth is None:
        from course.physics import grid_cloth

        cloth = grid_cloth(20, 20)
    return ClothSimulator(cloth, **kwargs)
