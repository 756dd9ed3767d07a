r"""The simulation loop 仿真循环 of a MuJoCo character: one :class:`Simulation`, any controller.

Shaped as dm_control's ``Environment.step`` (``before_step`` → ``physics.step`` × n →
``after_step``). A :class:`Simulation` owns its own copy of a character's model
(:meth:`~course.physics.model.Character.fresh_model`) and its ``MjData``; one call of
:meth:`Simulation.step` advances one *frame* (``frame_time``: the control, recording and
``on_frame`` period) by :attr:`~Simulation.substeps` MuJoCo steps of ``h``. What drives it is
a :class:`Controller`, which supplies only torques.

Frame ``i`` (``n`` steps, step ``k`` at ``t = ((i - 1) n + k) h``):

before the frame
    the controller's ``before_frame(sim)`` (an optional hook: a state machine, a gain
    schedule);
before each step
    the :class:`Push` acting on this step (its midpoint in the push's interval) goes into
    ``xfrc_applied``; with a :class:`HeldRoot` the root's position (interpolated towards
    frame ``i``) and velocity are set to the clip's ("hand of God");
each step
    ``mj_step1`` (kinematics, COM, Jacobians of the current state), then the controller's
    ``torques(sim, t)`` — the root's six entries zeroed (it is never actuated), each
    component clipped to ``±torque_limit`` — into ``qfrc_applied``, then ``mj_step2``
    (``mj_step1`` + ``mj_step2`` is ``mj_step``, bit for bit, for these integrators);
after the frame
    the held root is put back on the clip; kinematics and COM of the new state; the
    divergence test (MuJoCo's bad-qacc warning, or a non-finite ``qpos``) and the fall test
    (:class:`Fall`); the frame recorded (``qpos``, the applied torques, the COM), then
    ``on_frame(i, frame)`` called with it as a 1-frame :class:`~course.motion.Motion`.

:meth:`Simulation.run` resets a controller and steps until ``n_frames`` are recorded or a stop
reason ends it early; it returns a :class:`Recording`. ``h`` must divide the frame:
:func:`substeps` refuses a step that does not (rather than rounding it silently)::

    sim = Simulation(character, qpos, qvel, frame_time=clip.frame_time, h=1 / 600,
                     push=Push("Hips", (0, 0, 200), start=0.5, duration=0.1))
    record = sim.run(PD(targets, kp=1000, kd=6.3), n_frames=clip.n_frames)
"""

from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .._validate import as_array, as_count, as_positive, as_time_step
from ..motion import Motion
from .model import Y_TO_Z_MATRIX, Character, import_mujoco, motion_from_qpos

#: How close ``frame_time / n`` must be to the requested ``h`` (relative) for ``h`` to divide
#: the frame. Not 1e-9: BVH files write the frame time rounded (the CMU clips' ``.0083333``
#: for 1/120 s is 4e-6 off), and ``h = 1/600`` must be accepted on them; ``1/300`` (2.5 steps
#: of a 1/120 s frame) is refused.
STEP_RTOL = 1e-4

#: Why a run ended: all its frames done, fallen (:attr:`Fall.stop`), or diverged
#: (``stop_when_diverged``).
Reason = Literal["end", "fell", "diverged"]


def substeps(frame_time: float, h: float) -> int:
    """The number ``n`` of steps of ``h`` in one frame of ``frame_time`` seconds.

    The step used is then ``frame_time / n``, within :data:`STEP_RTOL` of ``h``.

    Raises
    ------
    ValueError
        Naming ``h`` and the frame time, with the nearest steps that divide it, if no whole
        number of steps fits (e.g. ``h = 1/300`` s for a 1/120 s frame: 2.5 steps); or if
        either is not a positive number.
    """
    h = as_time_step(h)
    frame_time = as_positive(frame_time, "frame_time")
    ratio = frame_time / h
    n = round(ratio)
    if n < 1 or abs(frame_time / n - h) > STEP_RTOL * h:
        near = sorted({max(1, math.floor(ratio)), max(1, math.ceil(ratio))})
        options = " or ".join(f"{frame_time / k:.6g} s (n = {k})" for k in near)
        raise ValueError(
            f"h: a step of {h:.6g} s does not divide the frame time {frame_time:.6g} s "
            f"({ratio:.4g} steps per frame); pass h = frame_time / n for a whole n, e.g. "
            f"{options}")
    return n


# -- pushes ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class Push:
    """An external force 外力 on one body for a while: a shove.

    Attributes
    ----------
    joint : str
        Name of the skeleton joint whose body is pushed (the force acts at that body's centre
        of mass), e.g. the root or a spine joint. Checked against a character by
        :meth:`body`.
    force : array_like, shape (3,)
        Newtons, y-up world frame; stored as a float ndarray.
    start : float
        Seconds after the start of the simulation.
    duration : float
        Seconds; positive.

    The force is applied on every step whose midpoint ``(k + 1/2) h`` lies in
    ``[start, start + duration)``, through MuJoCo's ``xfrc_applied``.
    """

    joint: str
    force: tuple[float, float, float] | Array
    start: float
    duration: float

    def __post_init__(self) -> None:
        if not isinstance(self.joint, str):
            raise TypeError(f"Push.joint: a joint name (str), got {type(self.joint).__name__}")
        force = np.array(self.force, dtype=float)
        if force.shape != (3,) or not np.all(np.isfinite(force)):
            raise ValueError(f"Push.force: 3 finite newtons (y-up), got {self.force!r}")
        if not (math.isfinite(self.start) and self.start >= 0.0):
            raise ValueError(f"Push.start: a time >= 0 s, got {self.start!r}")
        if not (math.isfinite(self.duration) and self.duration > 0.0):
            raise ValueError(f"Push.duration: a positive time in s, got {self.duration!r}")
        force.flags.writeable = False
        object.__setattr__(self, "force", force)
        object.__setattr__(self, "start", float(self.start))
        object.__setattr__(self, "duration", float(self.duration))

    @property
    def impulse(self) -> float:
        """``|force| * duration`` in N s."""
        return float(np.linalg.norm(self.force)) * self.duration

    def body(self, character: Character) -> int:
        """MuJoCo body id of :attr:`joint` in ``character``; ValueError if it has none."""
        names = character.skeleton.names
        if self.joint not in names:
            some = ", ".join(repr(n) for n in names[:6])
            raise ValueError(
                f"Push.joint: {self.joint!r} is not a joint of the skeleton "
                f"({len(names)} joints: {some}, ...)"
            )
        b = character.bodies[names.index(self.joint)]
        if b < 0:
            raise ValueError(
                f"Push.joint: {self.joint!r} is an End Site, it has no body; push its parent"
            )
        return b

    def active(self, t: float, h: float) -> bool:
        """Whether the step ``[t, t + h)`` pushes (its midpoint is in the push's interval)."""
        mid = t + 0.5 * h
        return self.start <= mid < self.start + self.duration

    def force_z_up(self) -> Array:
        """The force in MuJoCo's z-up world frame (N)."""
        out: Array = Y_TO_Z_MATRIX @ np.asarray(self.force)
        return out


# -- what a run is given, what it gives back -------------------------------------------------


@dataclass(frozen=True, eq=False)
class HeldRoot:
    """The root moved along the clip instead of simulated ("hand of God").

    Before every step of frame ``i`` the root's position is set to the point ``(k+1)/n`` of
    the way from frame ``i-1``'s to frame ``i``'s, its orientation to frame ``i``'s and its
    velocity to frame ``i-1``'s; after the frame (the step moved it by ``h v``) it is put back
    on frame ``i``.

    Attributes
    ----------
    qpos : ndarray, shape (F, 7)
        The root's ``qpos`` per frame (z-up meters, then the quaternion).
    qvel : ndarray, shape (F, 6)
        The root's ``qvel`` per frame.
    """

    qpos: Array
    qvel: Array

    def __post_init__(self) -> None:
        qpos = as_array(self.qpos, "HeldRoot.qpos", (7,))
        qvel = as_array(self.qvel, "HeldRoot.qvel", (6,))
        if qpos.ndim != 2 or qvel.shape[0] != qpos.shape[0]:
            raise ValueError(f"HeldRoot: qpos (F, 7) and qvel (F, 6) of as many frames, got "
                             f"{qpos.shape} and {qvel.shape}")
        object.__setattr__(self, "qpos", qpos)
        object.__setattr__(self, "qvel", qvel)


@dataclass(frozen=True)
class Fall:
    """When the character has fallen: tested after every frame.

    Attributes
    ----------
    measure : {"root", "com"}
        What falls: the root's height (``qpos[2]``) or the whole-body COM's (``subtree_com``
        of the root), z-up meters.
    height : float, optional
        Fallen below this height (m); default ``fraction`` of the initial one.
    fraction : float
        See ``height``.
    stop : bool
        End the run at the first fallen frame (:attr:`Recording.reason` ``"fell"``).
    """

    measure: Literal["root", "com"] = "root"
    height: float | None = None
    fraction: float = 0.5
    stop: bool = False

    def __post_init__(self) -> None:
        if self.measure not in ("root", "com"):
            raise ValueError(f"Fall.measure: 'root' or 'com', got {self.measure!r}")
        if self.height is not None:
            object.__setattr__(self, "height", float(as_array(self.height, "Fall.height")))
        object.__setattr__(self, "fraction", as_positive(self.fraction, "Fall.fraction"))


@dataclass(frozen=True, eq=False)
class Recording:
    """What :meth:`Simulation.run` returns: one row per recorded frame (frame 0 the start).

    Attributes
    ----------
    qpos : ndarray, shape (F, nq)
    torques : ndarray, shape (F, nv)
        ``qfrc_applied`` of the last step of each frame (zeros for frame 0): the
        controller's torques after the root was zeroed and the limit applied.
    com : ndarray, shape (F, 3)
        Whole-body COM, z-up meters.
    frame_time, h : float
        Seconds per frame and per step.
    fall_time : float or None
        Seconds at the first fallen frame (:class:`Fall`).
    unstable : bool
        Whether the run diverged (MuJoCo's bad-qacc warning, or a non-finite ``qpos``).
    reason : {"end", "fell", "diverged"}
        Why it ended.
    wall_time : float
        Wall-clock seconds of the loop (``on_frame`` included).
    """

    qpos: Array = field(repr=False)
    torques: Array = field(repr=False)
    com: Array = field(repr=False)
    frame_time: float
    h: float
    fall_time: float | None
    unstable: bool
    reason: Reason
    wall_time: float

    @property
    def n_frames(self) -> int:
        """Frames recorded, the initial one included."""
        return int(self.qpos.shape[0])

    @property
    def sim_time(self) -> float:
        """Simulated seconds."""
        return (self.n_frames - 1) * self.frame_time


# -- the controller interface ------------------------------------------------------------------


class Controller(ABC):
    r"""What drives a :class:`Simulation`: a control law :math:`\tau = \pi(q, \dot q, t)` that
    supplies only torques.

    On every step the simulation calls :meth:`torques` with itself: ``sim.model`` and
    ``sim.data`` hold the current state :math:`(q, \dot q)` = ``(data.qpos, data.qvel)``
    after ``mj_step1`` (kinematics, COM ``data.subtree_com``, what ``mj_jac*`` needs), and ``t``
    is the time at the step's start. The returned :math:`\tau` (nv,) is in generalized
    coordinates: a ball joint's three entries are a torque about its own axes (N m), as its
    ``qvel`` is an angular velocity in its own frame. The simulation zeroes the free root's
    six entries (it is never actuated: the character can fall), clips every component to
    ``±torque_limit`` and applies it through ``qfrc_applied``; pushes, the held root, the
    fall and divergence tests, recording and ``on_frame`` are the simulation's, not the
    controller's.

    A controller implements :meth:`torques`; :meth:`reset` (once per run) and
    :meth:`before_frame` (once per frame, dm_control's ``before_step``: a walking
    controller's state machine, a gain schedule) are optional. The joint laws
    (:class:`~course.physics.controllers.PD`, :class:`~course.physics.controllers.StablePD`)
    are in :mod:`course.physics.controllers`, the balance controllers in
    :mod:`course.physics.balance`.
    """

    def reset(self, sim: Simulation) -> None:  # noqa: B027 - optional, empty by default
        """Prepare for a run of ``sim``: called once by :meth:`Simulation.run`, after the
        initial state is set (``mj_forward`` done) and before the first step. It may configure
        ``sim.model``, the simulation's own copy (:class:`~course.physics.controllers.StablePD`
        sets its damping and integrator). Nothing by default."""

    def before_frame(self, sim: Simulation) -> None:  # noqa: B027 - optional, as reset
        """Called at the start of every frame, before its steps, with ``sim.frame`` already
        the frame they lead to and ``sim.data`` the state the last frame ended in. Nothing by
        default."""

    @abstractmethod
    def torques(self, sim: Simulation, t: float) -> Array:
        r"""Generalized forces :math:`\tau` ``(nv,)`` for the current state of ``sim`` at ``t``
        seconds (the step's start), ``sim.frame`` the frame the step leads to. The root's
        entries are ignored; the simulation clips the rest. The array may be the controller's
        own buffer (it is copied)."""


class Simulation:
    """One run of a MuJoCo character, a frame at a time (module docstring).

    Parameters
    ----------
    character : Character
    qpos : array_like, shape (nq,)
        The initial state (z-up, :func:`~course.physics.model.qpos_from_motion`).
    qvel : array_like, shape (nv,), optional
        Its velocities; default at rest.
    frame_time : float
        Seconds per frame.
    h : float
        The step; it must divide ``frame_time`` (:func:`substeps`).
    gravity : bool
        ``False``: no gravity.
    torque_limit : float
        Per-component limit of the controller's torques (N m); ``inf``: none.
    push : Push, optional
        An external force during the run (its time counts from frame 0).
    held_root : HeldRoot, optional
        Move the root along a clip instead of simulating it.
    fall : Fall, optional
        The fall test; default: none (``fall_time`` stays None).
    stop_when_diverged : bool
        End the run at the first diverged frame (:attr:`Recording.reason` ``"diverged"``).
    on_frame : callable, optional
        ``on_frame(i, frame)`` after each frame ``i = 1, 2, ...`` with the frame as a 1-frame
        Motion named ``name`` (y-up, skeleton units).
    name : str
        The name of the Motions given to ``on_frame``.

    Attributes
    ----------
    model, data : mujoco.MjModel, mujoco.MjData
        The simulation's own (a controller's ``reset`` may configure ``model``).
    frame : int
        The frame the steps in progress lead to; between steps, the last one recorded.
    substeps : int
        Steps per frame; ``h`` is then ``frame_time / substeps``.
    actuated : ndarray of bool, shape (nv,)
        The DOFs torques act on (all but the root's six).
    """

    def __init__(
        self,
        character: Character,
        qpos: ArrayLike,
        qvel: ArrayLike | None = None,
        *,
        frame_time: float,
        h: float = 1.0 / 600.0,
        gravity: bool = True,
        torque_limit: float = math.inf,
        push: Push | None = None,
        held_root: HeldRoot | None = None,
        fall: Fall | None = None,
        stop_when_diverged: bool = False,
        on_frame: Callable[[int, Motion], None] | None = None,
        name: str = "simulated",
    ) -> None:
        self.substeps = substeps(frame_time, h)
        self.frame_time = float(frame_time)
        self.h = self.frame_time / self.substeps
        self.torque_limit = as_positive(torque_limit, "torque_limit", allow_zero=True,
                                        allow_inf=True)
        self._lowest = -self.torque_limit
        self.character, self.push, self.held_root, self.fall = character, push, held_root, fall
        self.stop_when_diverged, self.on_frame, self.name = stop_when_diverged, on_frame, name
        self._mj = mujoco = import_mujoco()
        model = character.fresh_model()
        model.opt.timestep = self.h
        if not gravity:
            model.opt.gravity[:] = 0.0
        self.model, self.data = model, mujoco.MjData(model)
        self.data.qpos[:] = as_array(qpos, "qpos", (model.nq,))
        self.data.qvel[:] = 0.0 if qvel is None else as_array(qvel, "qvel", (model.nv,))
        mujoco.mj_forward(model, self.data)
        self.actuated = np.ones(model.nv, dtype=bool)
        self.actuated[:6] = False  # the free root
        self._push_body = push.body(character) if push is not None else -1
        self._push_force = push.force_z_up() if push is not None else np.zeros(3)
        self._root = character.bodies[0]
        self._tau = np.zeros(model.nv)
        self._bad_qacc = mujoco.mjtWarning.mjWARN_BADQACC
        self.frame = 0
        self.fall_time: float | None = None
        self.unstable = False
        self.reason: Reason | None = None
        self._fall_below = None if fall is None else (
            fall.height if fall.height is not None else fall.fraction * self._fall_measure())
        self._qpos = [self.data.qpos.copy()]
        self._torques = [self.data.qfrc_applied.copy()]
        self._com = [self.data.subtree_com[self._root].copy()]

    @property
    def time(self) -> float:
        """Simulated seconds at the last recorded frame."""
        return self.frame * self.frame_time

    def run(self, controller: Controller | None, n_frames: int) -> Recording:
        """Reset ``controller`` (``None``: no torques at all, a passive ragdoll), then
        :meth:`step` until ``n_frames`` frames are recorded (the initial one included) or the
        run stops early; the :class:`Recording`."""
        n_frames = as_count(n_frames, "n_frames")
        held = self.held_root
        if held is not None and n_frames > held.qpos.shape[0]:
            raise ValueError(f"n_frames: {n_frames} frames, but the held root has "
                             f"{held.qpos.shape[0]}")
        if controller is not None:
            controller.reset(self)
        start = time.perf_counter()
        while self.frame < n_frames - 1 and self.step(controller) is None:
            pass
        wall = time.perf_counter() - start
        return self.recording(wall)

    def step(self, controller: Controller | None) -> Reason | None:
        """Simulate one frame: the steps with their pushes and torques, then the frame's tests,
        recording and ``on_frame`` (module docstring). ``controller`` must have been reset on
        this simulation (:meth:`run` does it). Returns why the run stops (None: go on)."""
        if self.reason is not None:
            raise RuntimeError(f"the simulation has stopped ({self.reason}); start a new one")
        model, data, n, h = self.model, self.data, self.substeps, self.h
        step1, step2, apply = self._mj.mj_step1, self._mj.mj_step2, self._apply  # hot loop
        self.frame = i = self.frame + 1
        if controller is not None:
            controller.before_frame(self)
        torques = None if controller is None else controller.torques
        presets = self.push is not None or self.held_root is not None
        for k in range(n):
            t = ((i - 1) * n + k) * h  # not t += h: no rounding builds up over a long run
            if presets:
                self._before_step(i, k, t)
            step1(model, data)  # kinematics, COM and Jacobians of the current state
            if torques is not None:
                apply(torques(self, t))
            step2(model, data)
        return self._after_frame(i)

    def recording(self, wall_time: float = 0.0) -> Recording:
        """The frames recorded so far."""
        return Recording(
            qpos=np.array(self._qpos), torques=np.array(self._torques),
            com=np.array(self._com), frame_time=self.frame_time, h=self.h,
            fall_time=self.fall_time, unstable=self.unstable, reason=self.reason or "end",
            wall_time=wall_time)

    # -- the parts of a frame -----------------------------------------------------------------

    def _before_step(self, i: int, k: int, t: float) -> None:
        """Step ``k`` of frame ``i``: the push (on or off) and the held root."""
        data, push = self.data, self.push
        if push is not None:
            data.xfrc_applied[self._push_body, :3] = (
                self._push_force if push.active(t, self.h) else 0.0)
        held = self.held_root
        if held is not None:
            alpha = (k + 1) / self.substeps
            data.qpos[:3] = (1 - alpha) * held.qpos[i - 1, :3] + alpha * held.qpos[i, :3]
            data.qpos[3:7] = held.qpos[i, 3:7]
            data.qvel[:6] = held.qvel[i - 1]

    def _apply(self, torques: Array) -> None:
        """``torques`` (nv,) into ``qfrc_applied``: each component clipped to
        ``±torque_limit``, the root's zeroed (``torques`` itself is left as it is)."""
        tau = self._tau
        if getattr(torques, "shape", None) != tau.shape:
            raise ValueError(f"controller: torques of shape {tau.shape} (nv) expected, got "
                             f"{np.shape(torques)}")
        np.clip(torques, self._lowest, self.torque_limit, out=tau)
        tau[:6] = 0.0  # the free root (not self.actuated)
        self.data.qfrc_applied[:] = tau

    def _after_frame(self, i: int) -> Reason | None:
        """The end of frame ``i``: its tests, recording and ``on_frame``; why the run stops."""
        mj, model, data = self._mj, self.model, self.data
        if self.held_root is not None:  # the step moved the root by h v: put it back
            data.qpos[:7] = self.held_root.qpos[i]
        mj.mj_kinematics(model, data)
        mj.mj_comPos(model, data)
        if data.warning[self._bad_qacc].number > 0 or not np.all(np.isfinite(data.qpos)):
            self.unstable = True
        if (self.fall_time is None and self._fall_below is not None
                and self._fall_measure() < self._fall_below):
            self.fall_time = i * self.frame_time
        self._qpos.append(data.qpos.copy())
        self._torques.append(data.qfrc_applied.copy())
        self._com.append(data.subtree_com[self._root].copy())
        if self.on_frame is not None:
            self.on_frame(i, motion_from_qpos(self.character, self._qpos[-1][None],
                                              self.frame_time, name=self.name))
        if self.fall is not None and self.fall.stop and self.fall_time is not None:
            self.reason = "fell"
        elif self.stop_when_diverged and self.unstable:
            self.reason = "diverged"
        return self.reason

    def _fall_measure(self) -> float:
        """The height :class:`Fall` tests (m): the root's or the COM's."""
        if self.fall is not None and self.fall.measure == "com":
            return float(self.data.subtree_com[self._root][2])
        return float(self.data.qpos[2])


__all__ = [
    "STEP_RTOL",
    "Controller",
    "Fall",
    "HeldRoot",
    "Push",
    "Recording",
    "Simulation",
    "substeps",
]
