"""A live rigid body 刚体: its boxes drawn in 3D, moved in place, with controls (lecture 8).

:class:`RigidBodyScene` draws a :class:`course.physics.rigid_body.RigidBody` whose contact
points are the corners of boxes (8 per box, in :func:`~course.physics.rigid_body.box_corners`'
order: :func:`~course.physics.rigid_body.box` has one, :func:`~course.physics.rigid_body.t_handle`
two) as one mesh, its points overwritten by :meth:`RigidBodyScene.set_state` (``x + R r₀``;
nothing is rebuilt), over a floor at ``y = 0`` when there is ground. :class:`RigidBodySimulator`
adds the controls: the time step ``h`` and the ground's stiffness ``k``, a push (an impulse at
the body's highest corner, so it turns as well as moves: ``ΔL = (p − x) × Δp``), play/pause,
one step and reset; the readout shows the time, the energy and ``‖L‖``. As in
:mod:`course.viz.cloth`, widget events run on the GL thread and setting a widget's value from
code does what clicking it does.
"""

from __future__ import annotations

from typing import Any

import ipywidgets as widgets
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .backend import configure_environment, latest_on_gl_thread
from .live_simulator import LiveSimulator, log_slider
from .live_view import LiveView, shade
from .meshes import move_points
from .scene import PALETTE

configure_environment()

import pyvista as pv  # noqa: E402  (after the environment is set: VTK reads it on import)

Array = NDArray[np.float64]

BODY_COLOR = PALETTE[0][0]
FLOOR_COLOR = "#d9dee4"
# the six faces of a box, as indices into its 8 corners (index 4 ix + 2 iy + iz, 0 for −)
_FACES = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4],
                   [1, 5, 7, 3]])


def _quat_matrix(q: Array) -> Array:
    from course.rotations import matrix_from_quat

    return np.asarray(matrix_from_quat(q), dtype=np.float64)


class RigidBodyScene(LiveView):
    """A rigid body's boxes in 3D, moved in place by :meth:`set_state`.

    A :class:`~course.viz.live_view.LiveView`: rendering, :meth:`widget`, :meth:`show`,
    :meth:`screenshot` and :meth:`close` are every scene's.

    Parameters
    ----------
    body : a :class:`~course.physics.rigid_body.RigidBody` whose ``points`` (P, 3) are the
        corners of P / 8 boxes.
    floor : draw the ground ``y = 0``.
    center, radius : the region the camera frames (m).
    window_size : (width, height) in pixels.
    """

    def __init__(self, body: Any, *, floor: bool = True, center: ArrayLike = (0.0, 0.2, 0.0),
                 radius: float = 0.5, window_size: tuple[int, int] = (640, 480)) -> None:
        points = np.asarray(body.points, dtype=np.float64)
        if points.ndim != 2 or len(points) == 0 or len(points) % 8:
            raise ValueError(f"body.points: expected the corners of boxes, 8 per box, got "
                             f"shape {points.shape}")
        super().__init__(window_size)
        self.body_points = points
        n_boxes = len(points) // 8
        faces = (_FACES[None] + 8 * np.arange(n_boxes)[:, None, None]).reshape(-1, 4)
        cells = np.column_stack([np.full(len(faces), 4), faces]).ravel()
        self.mesh = pv.PolyData(points.copy(), faces=cells)
        self.actor = self.plotter.add_mesh(self.mesh, color=BODY_COLOR, reset_camera=False,
                                           pickable=False, show_edges=True, edge_color="#1f4f85")
        shade(self.actor, BODY_COLOR, specular=0.25)
        if floor:
            plane = pv.Plane(center=(0.0, 0.0, 0.0), direction=(0.0, 1.0, 0.0),
                             i_size=4 * radius, j_size=4 * radius)
            self.plotter.add_mesh(plane, color=FLOOR_COLOR, reset_camera=False, pickable=False)
        self._aim(np.asarray(center, dtype=np.float64), float(radius))

    def _aim(self, center: Array, radius: float) -> None:
        d = np.array([0.8, 0.55, 1.0]) / np.linalg.norm([0.8, 0.55, 1.0])
        self.plotter.camera.view_angle = 30.0
        self._look_at(center, center + radius / np.sin(np.radians(15.0)) * d, (0, 1, 0))

    @property
    def positions(self) -> Array:
        """The drawn corners ``(P, 3)`` in the world (a copy)."""
        return np.array(self.mesh.points, dtype=np.float64)

    def set_state(self, x: ArrayLike, q: ArrayLike, *, render: bool = True) -> None:
        """Move the body to the centre of mass ``x`` (3,) and orientation ``q`` (4,), unit,
        (w, x, y, z): the corners become ``x + R r₀`` (the same arrays: nothing re-created)."""
        x = np.asarray(x, dtype=np.float64)
        q = np.asarray(q, dtype=np.float64)
        if x.shape != (3,) or q.shape != (4,):
            raise ValueError(f"x, q: expected shapes (3,) and (4,), got {x.shape} and {q.shape}")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(q))):
            raise ValueError("x, q: contain NaN or infinite values")
        move_points(self.mesh, x + self.body_points @ _quat_matrix(q).T)
        if render:
            self.render()


class RigidBodySimulator(LiveSimulator[RigidBodyScene]):
    """A rigid body simulated live (symplectic Euler, exact rotation update).

    Parameters
    ----------
    body : a :class:`~course.physics.rigid_body.RigidBody` with box corners as points.
    start : its first :class:`~course.physics.rigid_body.RigidState` (one body).
    ground : penalty contact with ``y = 0`` (then gravity too, and a ``k`` slider; the
        damping is ``0.3 √(k m)``, the friction 1 N s/m) or a free body in space.
    h : the first time step (s).
    max_steps_per_tick : the most steps one tick of play (every 40 ms) takes.
    """

    def __init__(self, body: Any, start: Any, *, ground: bool = True, h: float = 2e-3,
                 k: float = 1e4, max_steps_per_tick: int = 40, center: ArrayLike = (0, 0.2, 0),
                 radius: float = 0.5, window_size: tuple[int, int] = (640, 480)) -> None:
        if int(max_steps_per_tick) < 1:
            raise ValueError("max_steps_per_tick must be positive")
        self.body, self.start, self.ground = body, start, bool(ground)
        scene = RigidBodyScene(body, floor=ground, center=center, radius=radius,
                               window_size=window_size)
        sliders: dict[str, widgets.Widget] = {"h": log_slider("time step h", h, 1e-4, 0.05,
                                                              ".4f")}
        if ground:
            sliders["k"] = log_slider("stiffness k", k, 1e2, 1e6, ".0f")
        sliders["push"] = widgets.FloatSlider(
            value=1.0, min=0.0, max=5.0, step=0.1, description="push (m/s)",
            readout_format=".1f", continuous_update=False, style={"description_width": "90px"},
            layout=widgets.Layout(width="360px"))
        for slider in sliders.values():
            slider.observe(latest_on_gl_thread(lambda _c: self._show()), names="value")
        self.push_button = widgets.Button(description="push", icon="hand-o-right")
        self.push_button.on_click(latest_on_gl_thread(lambda _b: self.push()))
        super().__init__(scene, sliders, buttons=[self.push_button],
                         max_steps_per_tick=max_steps_per_tick, interval=40,
                         window_size=window_size)

    def _options(self) -> dict[str, Any]:
        from course.physics.rigid_body import Ground

        if not self.ground:
            return {"gravity": (0.0, 0.0, 0.0)}
        k = float(self.sliders["k"].value)
        return {"ground": Ground(k=k, d=0.3 * np.sqrt(k * self.body.mass), friction=1.0)}

    def reset(self) -> None:
        """Back to the start state, time 0."""
        self.state = self.start
        self.time, self.steps, self.exploded = 0.0, 0, False
        self.scene.set_state(self.state.x, self.state.q, render=False)
        self._show()

    def advance(self, n: int = 1) -> None:
        """Take ``n`` steps and draw the result once."""
        from course.physics.rigid_body import RigidState, simulate_rigid

        if self.exploded:
            return
        h = float(self.sliders["h"].value)
        run = simulate_rigid(self.body, self.state, h, int(n), blowup=20.0, **self._options())
        last = len(run.x) - 1
        self.state = RigidState(x=run.x[last], v=run.v[last], q=run.q[last], L=run.L[last])
        self.time += last * h
        self.steps += last
        if run.exploded_at is not None:
            self.exploded = True
            self.play.playing = False
        self.scene.set_state(self.state.x, self.state.q, render=False)
        self._show()

    def push(self) -> None:
        """An impulse ``Δp = m · push`` along +x at the highest corner: ``v += Δp/m``,
        ``L += (p − x) × Δp``."""
        from course.physics.rigid_body import RigidState, point_torque

        corners = self.scene.positions
        p = corners[int(np.argmax(corners[:, 1]))]
        dp = np.array([self.body.mass * float(self.sliders["push"].value), 0.0, 0.0])
        s = self.state
        self.state = RigidState(x=s.x, v=s.v + dp / self.body.mass, q=s.q,
                                L=s.L + point_torque(p, s.x, dp))
        self._show()

    def _show(self) -> None:
        from course.physics.rigid_body import rigid_energy

        e = rigid_energy(self.body, self.state, **self._options())
        lines = [f"t = {self.time:.3f} s simulated ({self.steps} steps, "
                 f"{self.steps_per_tick} per tick)",
                 f"energy E = {float(e.total) + 0.0:+.4f} J, ‖L‖ = "
                 f"{float(np.linalg.norm(self.state.L)):.4f} kg m²/s",
                 f"centre x = ({', '.join(f'{c:+.3f}' for c in self.state.x)}) m"]
        if self.exploded:
            lines.append("<b style='color:#e5484d'>exploded: the step was unstable; "
                         "reset, and try a smaller h or a softer k</b>")
        self.readout.value = "<br>".join(lines)
        self.scene.render()


def rigid_body_simulator(kind: str = "box", **kwargs: Any) -> RigidBodySimulator:
    """A live rigid body: ``"box"`` (a 20 cm cube dropped tilted onto penalty ground) or
    ``"t_handle"`` (the T-handle spun at 10 rad/s about its intermediate axis, in space);
    ``kwargs`` go to :class:`RigidBodySimulator`."""
    from course.physics.rigid_body import box, t_handle

    if kind == "box":
        cube = box(1.0, (0.1, 0.1, 0.1))
        start = cube.state(x=(0.0, 0.3, 0.0), q=(np.cos(0.15), np.sin(0.15), 0.0, 0.0))
        return RigidBodySimulator(cube, start, **kwargs)
    if kind == "t_handle":
        handle = t_handle()
        start = handle.state(omega=(10.0, 0.01, 0.0))
        options: dict[str, Any] = {"ground": False, "h": 1e-3, "center": (0.0, 0.0, 0.0),
                                   "radius": 0.12}
        return RigidBodySimulator(handle, start, **{**options, **kwargs})
    raise ValueError(f"kind: must be 'box' or 't_handle', got {kind!r}")
