"""SIMBICON walking 行走, simulated live in 3D with its footprints and capture point (notebook 15).

:class:`WalkingSimulator` plays a :class:`~course.physics.walking.SIMBICON` walk of a MuJoCo
character while it simulates it, on the machinery of every live view of the course: a
:class:`~course.viz.live_simulator.LiveSimulator` (play/pause ticking in the browser, one
step, reset, the readout) beside a :class:`WalkingScene`, a
:class:`~course.viz.scene.SkeletonScene` (a :class:`~course.viz.live_view.LiveView`) whose
camera follows the walker. Each tick of play simulates the frames that keep the walk at its
playback speed (:meth:`WalkingSimulator.advance`: :meth:`~course.physics.simulation.
Simulation.step`, one control frame of 1/60 s each) and draws the last one once.

On the ground it draws where each stance foot landed (the controller's
:class:`~course.physics.walking.Footstep`\\ s: green left, red right), the COM's projection and
the capture point :math:`\\xi = c + \\dot c/\\omega_0` (:func:`course.physics.lip.capture_point`,
:math:`\\omega_0 = \\sqrt{g/h}` with :math:`h` the COM's height above the floor), joined by a
line. The sliders act on the walk as it goes, from the next frame: the speed input
(:attr:`SIMBICON.speed`), the sagittal feedback gains ``c_d`` and ``c_v`` and the swing hip's
targets :attr:`Gait.swing_hip` (:math:`\\theta_{d0}` of swing-lift and of swing-down); the
push button shoves the root with the push sliders' force (size, direction about the vertical:
0 forward, 90 degrees to the left) for :attr:`WalkingSimulator.push_duration` seconds from the
current time; reset walks again from rest with the sliders' settings. The readout says how
many strides it has walked, or when it fell.

As in every view of :mod:`course.viz`, widget events run on the GL thread and setting a
widget's value from code does what moving it does, so tests and notebooks drive it too.
MuJoCo is imported when a walk is built, pyvista with :mod:`course.viz.scene`.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from typing import Any

import ipywidgets as widgets
import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .backend import configure_environment, latest_on_gl_thread
from .ground_markers import COLORS as MARKER_COLORS
from .ground_markers import GroundMarkers, color_key, com_state, y_up
from .live_simulator import LiveSimulator
from .live_view import shade
from .meshes import FLOOR_COLORS, floor_plane, move_points
from .scene import SkeletonScene

configure_environment()

import pyvista as pv  # noqa: E402  (after the environment is set: VTK reads it on import)

WINDOW = (640, 420)  # px: the 3D view, as notebook 14's
COLORS = {"left": "#2bb673", "right": "#e5484d", **MARKER_COLORS}
#: where the camera looks from (towards the walker, y up): its left side, ahead, above
VIEW_DIRECTION = (1.0, 0.62, 0.75)
#: the ground about the walker's root the camera keeps in view (m): sideways, back, ahead
GROUND_IN_VIEW = (0.55, 0.85, 0.55)
FOOTPRINT_CAPACITY = 256  # footprints drawn per foot (the oldest drop out)
MAX_TIME = 60.0  # s: a walk stops there (reset starts another)
KEY = color_key([(COLORS[k], label) for k, label in (
    ("left", "left foot"), ("right", "right foot"), ("com", "COM"),
    ("capture", "capture point ξ"))])  # the readout's last line


class WalkingScene(SkeletonScene):
    """The walker over a floor, its footprints, its COM and capture point on the ground.

    Skeleton units, y up, as :meth:`~course.motion.Motion.forward_kinematics`. The camera
    follows the root (the ``follow`` preset's moves, from :data:`VIEW_DIRECTION`), framing the
    pose and :data:`GROUND_IN_VIEW` about it.

    Parameters
    ----------
    parents : (J,) the skeleton's parents.
    pose : (J, 3) the first pose.
    ground_height : the floor's height (skeleton units).
    foot_width : a footprint's width (skeleton units); its length is the foot's.
    meters : meters per skeleton unit (the character's scale).
    reach : how far (m) the floor reaches from the start, ahead and to each side.
    window_size : (width, height) in pixels.
    """

    def __init__(self, parents: ArrayLike, pose: ArrayLike, *, ground_height: float,
                 foot_width: float, meters: float, reach: float = 20.0,
                 window_size: tuple[int, int] = WINDOW) -> None:
        super().__init__(window_size=window_size, ground=False, camera="follow")
        pose = np.asarray(pose, dtype=np.float64)
        self.ground_height = float(ground_height)
        self.meters = float(meters)
        self.foot_width = float(foot_width)
        u = 1.0 / self.meters  # skeleton units per meter
        side, back, ahead = (g * u for g in GROUND_IN_VIEW)
        root = pose[0]
        corners = np.array([[root[0] + sx, self.ground_height, root[2] + dz]
                            for sx in (-side, side) for dz in (-back, ahead)])
        # the follow camera frames this "clip" of one frame about its root: pose and ground
        self.add_skeleton(parents, pose, name="walker",
                          frame_points=np.concatenate([pose, corners])[None])
        self._aim_follow(root)
        # the floor: under everything the walk can reach, at the simulated floor's height
        r = reach * u
        plane = floor_plane(np.array([root[0] - r, 0.0, root[2] - 0.2 * r]),
                            np.array([root[0] + r, 0.0, root[2] + r]),
                            np.array([root[0], 0.0, root[2] + 0.4 * r]), self.framing.scale)
        points = np.array(plane.points)
        points[:, 1] = self.ground_height
        move_points(plane, points)
        self.plotter.add_mesh(plane, scalars="tile", cmap=list(FLOOR_COLORS),
                              show_scalar_bar=False, ambient=0.35, diffuse=0.7, specular=0.0,
                              pickable=False, reset_camera=False)
        # footprints: one mesh of quads per foot, of fixed size (unused quads collapsed)
        self._prints: dict[str, pv.PolyData] = {}
        self._print_count = {"left": 0, "right": 0}
        self._print_centres: list[tuple[str, Array]] = []
        cap = FOOTPRINT_CAPACITY
        faces = np.column_stack([np.full(cap, 4), np.arange(4 * cap).reshape(cap, 4)]).ravel()
        for foot in ("left", "right"):
            mesh = pv.PolyData(np.tile(root * [1.0, 0.0, 1.0], (4 * cap, 1)), faces=faces)
            actor = self.plotter.add_mesh(mesh, color=COLORS[foot], reset_camera=False,
                                          pickable=False)
            shade(actor, COLORS[foot], specular=0.1)
            self._prints[foot] = mesh
        self._collapse_prints()
        # the COM's projection, the capture point and the push (ground_markers)
        self.markers = GroundMarkers(self, ground_height=self.ground_height, meters=self.meters)
        self._lift = self.markers.lift
        ground = np.array([root[0], self.ground_height, root[2]])
        self.markers.set_ground_points(ground, ground)

    def _aim_follow(self, root: Array) -> None:
        """The follow camera from :data:`VIEW_DIRECTION`, framing the pose and the ground
        about ``root``; it then moves with the root (:meth:`set_pose`)."""
        self.set_camera("follow")
        d = np.asarray(VIEW_DIRECTION, dtype=np.float64)
        d /= np.linalg.norm(d)
        up = np.array([0.0, 1.0, 0.0])
        envelope = self.framing.envelope
        assert envelope is not None  # the frame points are a clip of one frame
        focal, distance = self.framing.fit_view(d, up, self.plotter.window_size,
                                                envelope + root * [1.0, 0.0, 1.0])
        self._look_at(focal, focal + distance * d, up)
        self._follow = (self.skeleton().name, np.array(root, dtype=np.float64))

    def restart(self, pose: ArrayLike) -> None:
        """Back to a walk's start: the pose, no footprints, the camera on the root."""
        pose = np.asarray(pose, dtype=np.float64)
        self.skeleton().move(pose)
        self._aim_follow(pose[0])
        self._print_count = {"left": 0, "right": 0}
        self._print_centres = []
        self._collapse_prints()
        self.show_push(None, None, render=False)

    # -- footprints --------------------------------------------------------------------------

    def _collapse_prints(self) -> None:
        for foot, mesh in self._prints.items():
            n = self._print_count[foot]
            pts = np.array(mesh.points)
            pts[4 * n:] = pts[4 * n - 1] if n else [0.0, self.ground_height, 0.0]
            move_points(mesh, pts)

    def add_footprint(self, side: str, ankle: ArrayLike, forward: ArrayLike, length: float,
                      *, render: bool = False) -> None:
        """A footprint of the ``side`` foot (``"left"``, ``"right"``): a rectangle on the
        ground from just behind the ankle's projection ``ankle (3,)`` ``length`` along the
        ground direction ``forward (3,)``, :attr:`foot_width` wide. Past
        :data:`FOOTPRINT_CAPACITY` per foot the oldest is reused."""
        if side not in self._prints:
            raise ValueError(f"side: 'left' or 'right', got {side!r}")
        a = np.asarray(ankle, dtype=np.float64).reshape(3)
        f = np.asarray(forward, dtype=np.float64).reshape(3) * [1.0, 0.0, 1.0]
        norm = float(np.linalg.norm(f))
        f = f / norm if norm > 1e-9 else np.array([0.0, 0.0, 1.0])
        s = np.array([f[2], 0.0, -f[0]]) * (self.foot_width / 2)  # sideways
        base = np.array([a[0], self.ground_height + 0.4 * self._lift, a[2]])
        heel, toe = base - 0.5 * self.foot_width * f, base + float(length) * f
        quad = np.array([heel - s, heel + s, toe + s, toe - s])
        mesh = self._prints[side]
        k = self._print_count[side] % FOOTPRINT_CAPACITY
        pts = np.array(mesh.points)
        pts[4 * k:4 * k + 4] = quad
        n = self._print_count[side] = self._print_count[side] + 1
        if n < FOOTPRINT_CAPACITY:  # the unused quads collapse onto the newest corner
            pts[4 * n:] = quad[-1]
        move_points(mesh, pts)
        self._print_centres.append((side, base))
        if render:
            self.render()

    @property
    def footprints(self) -> list[tuple[str, Array]]:
        """Every footprint drawn since the start: ``(side, ankle on the ground (3,))``."""
        return [(side, p.copy()) for side, p in self._print_centres]

    def footprint_corners(self, side: str) -> Array:
        """The drawn corners ``(4 K, 3)`` of the ``side`` foot's footprints in use."""
        n = min(self._print_count[side], FOOTPRINT_CAPACITY)
        return np.array(self._prints[side].points[:4 * n])

    # -- the COM and the capture point --------------------------------------------------------

    def set_ground_points(self, com: ArrayLike, capture_point: ArrayLike, *,
                          render: bool = True) -> None:
        """:meth:`GroundMarkers.set_ground_points`, then a render (``render``)."""
        self.markers.set_ground_points(com, capture_point)
        if render:
            self.render()

    @property
    def com_marker(self) -> Array:
        """Where the COM's marker is drawn ``(3,)`` (on the floor)."""
        return self.markers.com_marker

    @property
    def capture_marker(self) -> Array:
        """Where the capture point's ring is drawn ``(3,)`` (on the floor)."""
        return self.markers.capture_marker

    def show_push(self, root: ArrayLike | None, force: ArrayLike | None, *,
                  render: bool = False) -> None:
        """:meth:`GroundMarkers.show_push`, then a render (``render``)."""
        self.markers.show_push(root, force)
        if render:
            self.render()

    @property
    def push_shown(self) -> bool:
        """Whether the push's arrow is drawn."""
        return self.markers.push_shown


class WalkingSimulator(LiveSimulator[WalkingScene]):
    """A SIMBICON walk of ``character`` played live while it simulates (module docstring).

    Parameters
    ----------
    character : :class:`~course.physics.model.Character` with two feet (the CMU one).
    gait : the :class:`~course.physics.walking.Gait` the sliders start from (default
        ``Gait()``); they set its ``c_d``, ``c_v`` and ``swing_hip``.
    speed : the speed input (m/s) to start with; 0 is SIMBICON's own, no input.
    push, push_direction : the push sliders' start: newtons, and degrees about the vertical
        (0 forward, 90 to the left, -90 to the right, 180 back).
    push_duration : how long a push lasts (s).
    max_time : the walk stops after this many simulated seconds.
    playback : simulated seconds per real second that play aims for (1.0: real time).
    max_frames_per_tick : the most control frames (1/60 s each) one tick of play simulates.
    interval : ms between two ticks of play.
    window_size : (width, height) of the 3D view in pixels.

    Attributes
    ----------
    controller : :class:`~course.physics.walking.SIMBICON`, this walk's.
    sim : :class:`~course.physics.simulation.Simulation`, this walk's: ``sim.time``,
        ``sim.model``, ``sim.data`` (MuJoCo, z up).
    pushed : the last push (a :class:`~course.physics.simulation.Push`, its ``start`` the
        simulated time it began), or None.
    """

    frame_time = 1.0 / 60.0  # s: one control frame, the unit of play and of "step"
    h = 1.0 / 600.0  # s: MuJoCo's step, as walk()'s
    torque_limit = 400.0  # N m, as walk()'s
    fall_fraction = 0.6  # fallen: the COM below this share of its start height, as walk()'s

    def __init__(self, character: Any, *, gait: Any | None = None, speed: float = 0.0,
                 push: float = 200.0, push_direction: float = 0.0, push_duration: float = 0.1,
                 max_time: float = MAX_TIME, playback: float = 1.0,
                 max_frames_per_tick: int = 10, interval: int = 50,
                 window_size: tuple[int, int] = WINDOW) -> None:
        from course.physics.walking import Gait, body_parts, neutral_pose
        from course.physics.zmp import foot_radius

        self.character = character
        self.base_gait = Gait() if gait is None else gait
        if not isinstance(self.base_gait, Gait):
            raise ValueError(f"gait: a Gait, got {type(gait).__name__}")
        if not (math.isfinite(push_duration) and push_duration > 0):
            raise ValueError(f"push_duration: a positive time in s, got {push_duration!r}")
        if not (math.isfinite(max_time) and max_time > 0):
            raise ValueError(f"max_time: a positive time in s, got {max_time!r}")
        self.push_duration, self.max_time = float(push_duration), float(max_time)
        self.parts = body_parts(character)
        skel = character.skeleton
        self.pose = neutral_pose(character).forward_kinematics()[0][0]
        #: the floor's height, y-up meters (MuJoCo's floor plane, at z = -foot radius)
        self.ground_height = float(y_up(character.model.geom("floor").pos)[1])
        radius = foot_radius(character)  # skeleton units
        leg = self.parts.left
        tips = [c for c in skel.children(leg.toe) if np.linalg.norm(skel.offsets[c]) > 1e-9]
        # ankle to toe tip along the ground, and the capsules' radius in front of it
        self.foot_length = float(np.linalg.norm(skel.offsets[leg.toe]) + (
            np.linalg.norm(skel.offsets[tips[0]]) if tips else 0.0) + radius)
        scene = WalkingScene(skel.parents, self.pose,
                             ground_height=self.ground_height / character.scale,
                             foot_width=2.0 * radius, meters=character.scale,
                             reach=max(8.0, 0.6 * self.max_time), window_size=window_size)
        g = self.base_gait
        style = {"style": {"description_width": "112px"}, "continuous_update": False}
        sliders: dict[str, widgets.Widget] = {
            "speed": widgets.FloatSlider(value=speed, min=0.0, max=0.5, step=0.05,
                                         description="speed (m/s)", readout_format=".2f",
                                         layout=widgets.Layout(width="360px"), **style),
            "c_d": widgets.FloatSlider(value=g.c_d, min=0.0, max=1.5, step=0.01,
                                       description="c_d", readout_format=".2f",
                                       layout=widgets.Layout(width="360px"), **style),
            "c_v": widgets.FloatSlider(value=g.c_v, min=0.0, max=1.5, step=0.01,
                                       description="c_v", readout_format=".2f",
                                       layout=widgets.Layout(width="360px"), **style),
            "swing_hip_lift": widgets.FloatSlider(
                value=g.swing_hip[0], min=-0.2, max=0.8, step=0.01,
                description="θd0 lift (rad)", readout_format=".2f",
                layout=widgets.Layout(width="360px"), **style),
            "swing_hip_down": widgets.FloatSlider(
                value=g.swing_hip[1], min=-0.2, max=0.8, step=0.01,
                description="θd0 down (rad)", readout_format=".2f",
                layout=widgets.Layout(width="360px"), **style),
            "push": widgets.FloatSlider(value=push, min=0.0, max=800.0, step=10.0,
                                        description="push (N)", readout_format=".0f",
                                        layout=widgets.Layout(width="360px"), **style),
            "push_direction": widgets.FloatSlider(
                value=push_direction, min=-180.0, max=180.0, step=15.0,
                description="push dir (°)", readout_format=".0f",
                layout=widgets.Layout(width="360px"), **style),
        }
        for key in ("speed", "c_d", "c_v", "swing_hip_lift", "swing_hip_down"):
            sliders[key].observe(latest_on_gl_thread(lambda _c: self._settings_changed()),
                                 names="value")
        for key in ("push", "push_direction"):
            sliders[key].observe(latest_on_gl_thread(lambda _c: self._show()), names="value")
        self.push_button = widgets.Button(description="push", icon="hand-o-right")
        self.push_button.on_click(latest_on_gl_thread(lambda _b: self.push()))
        self.pushed: Any = None
        self._last_tick: float | None = None
        self._rate: list[tuple[float, float, float]] = []  # (wall, sim at its start, sim after)
        super().__init__(scene, sliders, buttons=[self.push_button], speed=playback,
                         max_steps_per_tick=max_frames_per_tick, interval=interval,
                         window_size=window_size)

    # -- what the sliders set ------------------------------------------------------------------

    def gait(self) -> Any:
        """The :class:`~course.physics.walking.Gait` of the sliders: the starting gait with
        their ``c_d``, ``c_v`` and ``swing_hip`` (lift, down)."""
        s = self.sliders
        return dataclasses.replace(
            self.base_gait, c_d=float(s["c_d"].value), c_v=float(s["c_v"].value),
            swing_hip=(float(s["swing_hip_lift"].value), float(s["swing_hip_down"].value)))

    @property
    def speed_input(self) -> float | None:
        """The speed slider as SIMBICON's input: m/s, or None at 0 (its own ``c_v v``)."""
        v = float(self.sliders["speed"].value)
        return v if v > 0 else None

    def push_force(self) -> Array:
        """The push sliders' force (3,), N, y up: the size along the direction about the
        vertical (0 forward along +z, 90 degrees to the left, +x)."""
        a = math.radians(float(self.sliders["push_direction"].value))
        return float(self.sliders["push"].value) * np.array([math.sin(a), 0.0, math.cos(a)])

    def _settings_changed(self) -> None:
        """The walk takes the sliders' speed and gait from its next frame."""
        self.controller.speed = self.speed_input
        self.controller.gait = self.gait()
        self._show()

    # -- simulating ------------------------------------------------------------------------------

    @property
    def step_time(self) -> float:
        """One step of :meth:`advance` is a control frame (s): play's unit."""
        return self.frame_time

    def tick(self) -> None:
        """One tick of play: the frames of the real time since the last tick (at the playback
        speed; at least one, at most ``max_frames_per_tick``), so the walk keeps its speed
        when ticks come late or are dropped while the kernel draws."""
        now = time.monotonic()
        last, self._last_tick = self._last_tick, now
        n = self.steps_per_tick
        if last is not None and now - last < 0.5:  # playing on, not starting
            n = int(min(max(round((now - last) * self.speed / self.frame_time), 1),
                        self.max_steps_per_tick))
        else:
            self._rate.clear()
        start = self.sim.time
        self.advance(n)
        self._rate.append((now, start, self.sim.time))
        del self._rate[:-20]

    @property
    def measured_speed(self) -> float | None:
        """Simulated seconds per real second over the last ticks of play (None before two)."""
        r = self._rate
        if len(r) < 2 or r[-1][0] <= r[0][0]:
            return None
        return (r[-1][2] - r[0][2]) / (r[-1][0] - r[0][0])

    def reset(self) -> None:
        """A new walk from rest in the neutral pose, with the sliders' gait and speed."""
        from course.physics.simulation import Fall, Simulation
        from course.physics.walking import SIMBICON

        self.controller = SIMBICON(self.character, self.gait(), speed=self.speed_input)
        self.sim = Simulation(self.character, self.controller.neutral,
                              frame_time=self.frame_time, h=self.h,
                              torque_limit=self.torque_limit,
                              fall=Fall("com", fraction=self.fall_fraction, stop=True),
                              name="walk")
        self.controller.reset(self.sim)
        self.pushed = None
        self._last_tick = None
        self._rate = []
        self.scene.restart(self.pose)
        self._draw_state()
        self._show()

    @property
    def stopped(self) -> bool:
        """Whether the walk has ended: fallen, or at :attr:`max_time`."""
        return self.sim.reason is not None or self.sim.time >= self.max_time - 1e-9

    def advance(self, n: int = 1) -> None:
        """Simulate ``n`` control frames (fewer if the walk ends) and draw the last once."""
        sim, data = self.sim, self.sim.data
        for _ in range(int(n)):
            if self.stopped:
                break
            push = self.pushed
            acting = push is not None and push.active(sim.time, sim.frame_time)
            if acting:  # on every step of the frames it acts in (Push.active of the frame)
                data.xfrc_applied[push.body(self.character), :3] = push.force_z_up()
            before = len(self.controller.footsteps)
            sim.step(self.controller)
            if acting:
                data.xfrc_applied[:, :] = 0.0
            for step in self.controller.footsteps[before:]:
                self._add_footprint(step)
        if self.stopped:
            self.play.playing = False
        self._draw_state()
        self._show()

    def _add_footprint(self, step: Any) -> None:
        """A footprint where ``step``'s foot landed, along the foot as it lies now."""
        leg = self.parts.left if step.side == "left" else self.parts.right
        xpos = self.sim.data.xpos
        forward = y_up(xpos[leg.toe_body] - xpos[leg.foot])
        self.scene.add_footprint(step.side, step.position / self.character.scale, forward,
                                 self.foot_length)

    def push(self) -> None:
        """Push the root with the push sliders' force for :attr:`push_duration` seconds from
        the current time (it acts on the next frames simulated)."""
        from course.physics.simulation import Push

        force = self.push_force()
        if not np.any(force):
            return
        self.pushed = Push(self.character.skeleton.names[0], force, self.sim.time,
                           self.push_duration)
        self._draw_state()
        self._show()

    # -- the state -------------------------------------------------------------------------------

    @property
    def time(self) -> float:
        """Simulated seconds."""
        return self.sim.time

    @property
    def footsteps(self) -> list[Any]:
        """The walk's touch-downs (:class:`~course.physics.walking.Footstep`)."""
        return list(self.controller.footsteps)

    @property
    def strides(self) -> int:
        """Whole strides walked (two steps each)."""
        return len(self.controller.footsteps) // 2

    @property
    def fall_time(self) -> float | None:
        """When the walk fell (s), or None."""
        return self.sim.fall_time

    @property
    def com(self) -> Array:
        """The whole-body COM now (3,), y-up meters."""
        return com_state(self.character, self.sim.model, self.sim.data, self.ground_height)[0]

    @property
    def com_velocity(self) -> Array:
        """The COM's velocity now (3,), y-up m/s: its Jacobian times ``qvel``."""
        return com_state(self.character, self.sim.model, self.sim.data, self.ground_height)[1]

    @property
    def capture_point(self) -> Array:
        """The capture point now ``(x, z)`` (2,), m: :func:`course.physics.lip.capture_point`
        of the COM and its velocity over the floor, :math:`\\omega_0 = \\sqrt{g/h}` with
        :math:`h` the COM's height above it."""
        return com_state(self.character, self.sim.model, self.sim.data, self.ground_height)[2]

    def _draw_state(self) -> None:
        from course.physics.model import motion_from_qpos

        motion = motion_from_qpos(self.character, self.sim.data.qpos[None], self.frame_time)
        positions = motion.forward_kinematics()[0][0]
        push = self.pushed
        acting = push is not None and push.active(self.sim.time, self.frame_time)
        self._balance = self.scene.markers.follow(
            self.character, self.sim.model, self.sim.data, self.ground_height,
            positions[0] if acting else None, push.force if acting else None)
        self.scene.set_pose(positions, render=False)

    def _show(self) -> None:
        t = self.sim.time
        steps = len(self.controller.footsteps)
        if self.sim.fall_time is not None:
            state = (f"<b style='color:{COLORS['right']}'>fell at {self.sim.fall_time:.2f} s"
                     f"</b> after {self.strides} strides ({steps} steps): reset to walk again")
        elif self.stopped:
            state = f"walked {self.strides} strides ({steps} steps) in {t:.0f} s: the end"
        else:
            state = f"t = {t:.2f} s: {self.strides} strides walked ({steps} steps)"
        c, v, xi = self._balance  # as drawn: the sim moves only in advance, which draws
        ahead = 100 * float(np.linalg.norm(xi - c[[0, 2]]))
        lines = [state, f"COM {c[1] - self.ground_height:.2f} m high, {v[2]:+.2f} m/s "
                        f"forward; ξ {ahead:.0f} cm from it"]
        force = self.push_force()
        size = float(np.linalg.norm(force))
        p = self.pushed
        if p is not None:
            end = p.start + p.duration
            when = ("acting now" if p.active(t, self.frame_time) else
                    "from the next frame" if t < p.start + 1e-9 else f"ended at {end:.2f} s")
            lines.append(f"push: {np.linalg.norm(p.force):.0f} N for {p.duration:g} s at "
                         f"{p.start:.2f} s ({when})")
        else:
            lines.append(f"push: {size:.0f} N for {self.push_duration:g} s on the root")
        rate = self.measured_speed
        if self.play.playing and rate is not None:
            lines.append(f"playing at {rate:.2f}× real time (measured)")
        else:
            lines.append(f"play: {self.speed:g}× real time, {self.steps_per_tick} frames "
                         f"of 1/60 s a tick")
        self.readout.value = "<br>".join([*lines, KEY])
        self.scene.render()


def walking_simulator(character: Any, **kwargs: Any) -> WalkingSimulator:
    """A :class:`WalkingSimulator` of ``character`` at rest, ready to play (``kwargs`` go to
    it)."""
    return WalkingSimulator(character, **kwargs)


__all__: Sequence[str] = ("COLORS", "WalkingScene", "WalkingSimulator", "walking_simulator")
