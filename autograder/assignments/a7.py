r"""Assignment a7, walking (lecture 11): the spec ``assignments/a7_walking.py`` is checked by.

* ``capture_point`` is the capture point of the linear inverted pendulum on the ground plane,
  :math:`\xi = c + \dot c/\omega_0`, :math:`\omega_0 = \sqrt{g/h}` with :math:`h` the COM's
  height above the ground (its ``(x, z)``, y up; broadcast over leading dimensions), compared
  with :func:`course.physics.lip.capture_point` of :func:`course.physics.lip.natural_frequency`.
* ``swing_hip_target`` is SIMBICON's sagittal balance feedback :math:`\theta_d = \theta_{d0} +
  c_d\,d + c_v\,v`, :math:`d` and :math:`v` the COM's offset from the stance ankle and its
  velocity along the walking direction :math:`(\sin\psi, 0, \cos\psi)` of the heading
  :math:`\psi` (the world's heading frame), the law of
  :meth:`course.physics.walking.SIMBICON.placement`.
* ``zmp_from_forces`` is the ZMP (centre of pressure) of point contact forces on flat ground,
  :func:`course.physics.zmp.zmp_from_forces` with the ground height given.

Each is also graded by what it achieves on the simulated CMU character (MuJoCo,
:mod:`course.physics`): the student's capture point decides when and where
:class:`course.physics.stepping.CaptureStep` steps after a shove (its ``capture_point``
hook), and the student's feedback places SIMBICON's swing foot
(:class:`course.physics.walking.SIMBICON`, its ``feedback`` hook), the walker pushed
mid-walk. One call per control frame (1/60 s): the grader simulates
the frame's ten steps of 1/600 s with that answer (the reference's runs alike), and judges the
run by whether the character falls, the strides it walks and the steps it takes, against the
reference's.

The mistakes students make each give one definite wrong answer, so the catalogue writes them
as functions of the arguments.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np

from course.physics.lip import G, natural_frequency
from course.physics.lip import capture_point as lip_capture_point
from course.physics.zmp import zmp_from_forces as library_zmp

from ..checks import Check
from ..spec import Assignment, Case, Function, Misconception, Rollout, Run, Test, random_edge_hidden

# --- the capture point -------------------------------------------------------------------------


def capture_reference(com: np.ndarray, com_velocity: np.ndarray, ground_height: Any,
                      gravity: float) -> np.ndarray:
    """The library's capture point of the LIP whose height is the COM's above the ground."""
    c, v = np.asarray(com, dtype=float), np.asarray(com_velocity, dtype=float)
    omega0 = natural_frequency(c[..., 1] - np.asarray(ground_height, dtype=float), gravity)
    out: np.ndarray = lip_capture_point(c[..., [0, 2]], v[..., [0, 2]], omega0[..., None])
    return out


def capture_formula(com: np.ndarray, com_velocity: np.ndarray, ground_height: Any,
                    gravity: float, *, height: str = "above_ground", omega: str = "sqrt",
                    velocity: str = "over") -> np.ndarray:
    r"""The capture point written out, and as students get it wrong: ``height="y"`` takes
    :math:`h` as the COM's y (the ground ignored); ``omega="no_sqrt"`` :math:`\omega_0 = g/h`;
    ``velocity="times"`` :math:`c + \dot c\,\omega_0` (the same as :math:`\omega_0 =
    \sqrt{h/g}`), ``"none"`` :math:`\xi = c`."""
    c, v = np.asarray(com, dtype=float), np.asarray(com_velocity, dtype=float)
    h = c[..., 1] - (0.0 if height == "y" else np.asarray(ground_height, dtype=float))
    w = (gravity / h if omega == "no_sqrt" else np.sqrt(gravity / h))[..., None]
    step = {"over": v[..., [0, 2]] / w, "times": v[..., [0, 2]] * w,
            "none": 0.0 * v[..., [0, 2]]}[velocity]
    out: np.ndarray = c[..., [0, 2]] + step
    return out


def _state(rng: np.random.Generator, ground: float, speed: float = 0.8
           ) -> tuple[np.ndarray, np.ndarray]:
    com = np.array([rng.uniform(-2, 2), ground + rng.uniform(0.6, 1.1), rng.uniform(-2, 2)])
    return com, rng.normal(0, speed, 3) * np.array([1.0, 0.2, 1.0])


def _ground(rng: np.random.Generator) -> float:
    return float(rng.choice([-1.0, 1.0]) * rng.uniform(0.1, 0.6))


def capture_random(rng: np.random.Generator) -> list[Case]:
    cases = []
    for k in range(5):
        ground = _ground(rng)
        com, vel = _state(rng, ground)
        cases.append(Case(f"a moving COM over ground at y = {ground:.2f} m ({k + 1})",
                          (com, vel, ground, G)))
    return cases


def capture_edges(rng: np.random.Generator) -> list[Case]:
    batch_ground = rng.uniform(-0.3, 0.5, 4)
    coms, vels = zip(*(_state(rng, g) for g in batch_ground), strict=True)
    return [
        Case("at rest: the capture point is under the COM",
             (np.array([0.3, 1.2, -0.4]), np.zeros(3), 0.4, G)),
        Case("walking forward at 1 m/s, the COM 0.981 m above a floor at y = 0",
             (np.array([0.0, 0.981, 0.0]), np.array([0.0, 0.0, 1.0]), 0.0, G)),
        Case("on a 0.5 m platform, pushed sideways and back",
             (np.array([0.2, 1.35, -0.1]), np.array([0.6, 0.05, -0.4]), 0.5, G)),
        Case("on the Moon (g = 1.62 m/s²), below the floor's y = 0",
             (np.array([1.0, 0.5, 2.0]), np.array([0.3, 0.0, 0.2]), -0.4, 1.62)),
        Case("a batch of 4 states, each over its own ground height (shapes (4, 3) and (4,))",
             (np.array(coms), np.array(vels), batch_ground, G)),
    ]


def capture_hidden(rng: np.random.Generator) -> list[Case]:
    cases = []
    for k in range(6):
        if k % 3 == 2:
            grounds = rng.uniform(-0.5, 0.5, 3)
            coms, vels = zip(*(_state(rng, g, 1.5) for g in grounds), strict=True)
            cases.append(Case(f"hidden batch of states #{k + 1}",
                              (np.array(coms), np.array(vels), grounds, G)))
        else:
            ground = _ground(rng)
            com, vel = _state(rng, ground, 1.5)
            cases.append(Case(f"hidden state #{k + 1}", (com, vel, ground, G)))
    return cases


# --- SIMBICON's swing-hip feedback --------------------------------------------------------------


def forward(heading: Any) -> np.ndarray:
    """The walking direction of ``heading`` (radians about +y, positive to the left), y up:
    ``(sin ψ, 0, cos ψ)``, +z at 0 (as SIMBICON's heading frame)."""
    psi = np.asarray(heading, dtype=float)
    out: np.ndarray = np.stack([np.sin(psi), np.zeros_like(psi), np.cos(psi)], axis=-1)
    return out


def hip_formula(theta_d0: Any, c_d: float, c_v: float, com: np.ndarray,
                com_velocity: np.ndarray, stance_ankle: np.ndarray, heading: Any, *,
                sign_d: float = 1.0, sign_v: float = 1.0, pivot: str = "ankle",
                along: str = "heading") -> np.ndarray:
    r""":math:`\theta_d = \theta_{d0} + c_d d + c_v v` along the heading, and as students get
    it wrong: ``sign_d`` / ``sign_v`` -1 flip a feedback term; ``pivot="origin"`` measures
    :math:`d` from the world origin; ``along="z"`` takes :math:`d, v` along the world's z axis
    whatever the heading."""
    f = forward(0.0 if along == "z" else heading)
    c, v = np.asarray(com, dtype=float), np.asarray(com_velocity, dtype=float)
    rel = c - (0.0 if pivot == "origin" else np.asarray(stance_ankle, dtype=float))
    d, s = np.sum(rel * f, axis=-1), np.sum(v * f, axis=-1)
    out: np.ndarray = np.asarray(theta_d0 + sign_d * c_d * d + sign_v * c_v * s, dtype=float)
    return out


def hip_reference(*args: Any) -> np.ndarray:
    return hip_formula(*args)


def _hip_args(rng: np.random.Generator, heading: float | None = None,
              ahead: float = 0.15) -> tuple[Any, ...]:
    ankle = np.array([rng.uniform(-3, 3), rng.uniform(0.0, 0.1), rng.uniform(-3, 3)])
    com = ankle + np.array([rng.normal(0, ahead), rng.uniform(0.6, 0.8), rng.normal(0, ahead)])
    psi = float(rng.uniform(-np.pi, np.pi)) if heading is None else heading
    return (float(rng.uniform(0.2, 0.4)), float(rng.uniform(0.3, 1.2)),
            float(rng.uniform(0.1, 0.6)), com, rng.normal(0, 0.6, 3) * np.array([1, 0.1, 1]),
            ankle, psi)


def hip_random(rng: np.random.Generator) -> list[Case]:
    return [Case(f"a walking state, heading {a[6]:.2f} rad ({k + 1})", a)
            for k, a in enumerate(_hip_args(rng) for _ in range(5))]


def hip_edges(rng: np.random.Generator) -> list[Case]:
    batch = [_hip_args(rng, heading=0.7) for _ in range(3)]
    return [
        Case("the COM over the stance ankle and at rest: no feedback",
             (0.3, 0.8, 0.3, np.array([0.2, 0.75, 1.0]), np.zeros(3),
              np.array([0.2, 0.05, 1.0]), 0.0)),
        Case("heading 0: the COM 10 cm ahead of the ankle, 0.5 m/s forward",
             (0.3, 0.8, 0.3, np.array([0.1, 0.7, 2.1]), np.array([0.0, 0.0, 0.5]),
              np.array([0.1, 0.0, 2.0]), 0.0)),
        Case("walking along +x (heading π/2): the COM behind the ankle, still moving on",
             (0.3, 0.7, 0.2, np.array([3.0, 0.7, 1.0]), np.array([0.4, 0.0, 0.1]),
              np.array([3.05, 0.0, 0.9]), float(np.pi / 2))),
        Case("walking back towards the origin (heading π), far from it",
             _hip_args(rng, heading=float(np.pi))),
        Case("a batch of 3 states at heading 0.7 rad (com, com_velocity, stance_ankle (3, 3))",
             (0.3, 0.8, 0.3, np.array([b[3] for b in batch]), np.array([b[4] for b in batch]),
              np.array([b[5] for b in batch]), 0.7)),
    ]


def hip_hidden(rng: np.random.Generator) -> list[Case]:
    return [Case(f"hidden walking state #{k + 1}", _hip_args(rng, ahead=0.25)) for k in range(6)]


# --- the ZMP of contact forces -----------------------------------------------------------------


def zmp_reference(positions: np.ndarray, forces: np.ndarray, ground_height: Any) -> np.ndarray:
    """The library's ZMP of point forces on flat ground at ``ground_height``."""
    out: np.ndarray = library_zmp(positions, forces, ground_height=ground_height)
    return out


def zmp_formula(positions: np.ndarray, forces: np.ndarray, ground_height: Any, *,
                moment: float = -1.0, weights: str = "normal") -> np.ndarray:
    r""":math:`p_x = \sum_i [x_i f_{i,y} - (y_i - p_y) f_{i,x}] / \sum_i f_{i,y}` (and
    :math:`p_z`), and as students get it wrong: ``moment`` +1 adds the horizontal forces'
    moment, 0 leaves it out; ``weights="none"`` averages the points, ``"norm"`` weighs them by
    :math:`|f_i|` (the tangential forces counted in the weight)."""
    r, f = np.asarray(positions, dtype=float), np.asarray(forces, dtype=float)
    py = np.asarray(ground_height, dtype=float) * np.ones(r.shape[:-2])
    if weights == "normal":
        w, push = f[..., 1], moment * (r[..., 1] - py[..., None])[..., None] * f
    else:  # the points averaged, the forces' moment forgotten with their direction
        w = np.ones(r.shape[:-1]) if weights == "none" else np.linalg.norm(f, axis=-1)
        push = np.zeros_like(f)
    total = w.sum(axis=-1)
    px = (r[..., 0] * w + push[..., 0]).sum(axis=-1) / total
    pz = (r[..., 2] * w + push[..., 2]).sum(axis=-1) / total
    out: np.ndarray = np.stack([px, py, pz], axis=-1)
    return out


def _contacts(rng: np.random.Generator, n: int, ground: float, lift: float = 0.08
              ) -> tuple[np.ndarray, np.ndarray]:
    r = np.column_stack([rng.uniform(-0.3, 0.3, n), ground + rng.uniform(0.0, lift, n),
                         rng.uniform(-0.3, 0.3, n)])
    f = np.column_stack([rng.normal(0, 40, n), rng.uniform(40, 400, n), rng.normal(0, 40, n)])
    return r, f


def zmp_random(rng: np.random.Generator) -> list[Case]:
    cases = []
    for n in (3, 4, 5, 6, 8):
        ground = float(rng.uniform(-0.2, 0.2))
        cases.append(Case(f"{n} contacts, some above the ground at y = {ground:.2f}",
                          (*_contacts(rng, n, ground), ground)))
    return cases


def zmp_edges(rng: np.random.Generator) -> list[Case]:
    feet = np.array([[-0.1, 0.0, 0.0], [0.1, 0.0, 0.0], [-0.1, 0.0, 0.2], [0.1, 0.0, 0.2]])
    r, f = zip(*(_contacts(rng, 4, 0.05) for _ in range(2)), strict=True)
    return [
        Case("four contacts on the ground, equal vertical forces",
             (feet, np.tile([0.0, 150.0, 0.0], (4, 1)), 0.0)),
        Case("on the ground, more weight on the toes, some friction",
             (feet, np.array([[5.0, 50.0, 2.0], [5.0, 50.0, 2.0], [-3.0, 250.0, 8.0],
                              [-3.0, 250.0, 8.0]]), 0.0)),
        Case("two contacts 5 cm above the ground plane, pushed forward",
             (np.array([[0.0, 0.05, 0.0], [0.0, 0.05, 0.3]]),
              np.array([[0.0, 200.0, 40.0], [10.0, 200.0, 40.0]]), 0.0)),
        Case("one contact, leaning on it (a force with a big sideways part)",
             (np.array([[0.4, 0.1, -0.2]]), np.array([[60.0, 300.0, -30.0]]), 0.02)),
        Case("a batch of 2 frames of 4 contacts (shapes (2, 4, 3), ground (2,))",
             (np.array(r), np.array(f), np.array([0.05, 0.05]))),
    ]


def zmp_hidden(rng: np.random.Generator) -> list[Case]:
    cases = []
    for k in range(6):
        ground = float(rng.uniform(-0.3, 0.3))
        cases.append(Case(f"hidden contacts #{k + 1}",
                          (*_contacts(rng, int(rng.integers(2, 9)), ground, 0.15), ground)))
    return cases


# --- the rollouts: the simulated CMU character -------------------------------------------------

FRAME = 1.0 / 60.0  # s: one call of the student's function, ten MuJoCo steps
WALK_FRAMES = 240  # 4 s of walking, pushed at 2 s
STEP_FRAMES = 132  # 2.2 s of standing, shoved at t = 0
STEP_LATE = 0.1  # s: a first step this much before or after the reference's is wrong
ROLLOUT_HINT = ("a correct function takes well under a millisecond here: look for work it "
                "repeats needlessly in every call (a print, a sleep, a long loop)")


@cache
def cmu_character() -> Any:
    """The CMU walker as MuJoCo bodies (:func:`course.physics.model.build_model`), or None
    where MuJoCo or the clip is missing (the rollout tests then have no cases)."""
    try:
        from course.data import load
        from course.physics.model import build_model

        return build_model(load("cmu_12_01_walk", download=False).skeleton)
    except Exception:  # noqa: BLE001 - no MuJoCo, no clip: no runs here
        return None


@dataclass(eq=False)
class Simulated:
    """A rollout's state: the simulation, its controller, and the answer the controller uses
    for the frame being simulated (the grader's, carried between calls)."""

    sim: Any
    controller: Any
    answer: Any = None
    frames: int = 0


def character_simulation(controller: Any, velocity: Any, push: Any = None) -> Any:
    """The character in its neutral pose, every body moving at ``velocity`` (y-up, m/s: a
    shove at t = 0), under ``controller`` (reset on it)."""
    from course.physics.model import Y_TO_Z_MATRIX
    from course.physics.simulation import Fall, Simulation

    character = cmu_character()
    qvel = np.zeros(character.model.nv)
    qvel[:3] = Y_TO_Z_MATRIX @ np.asarray(velocity, dtype=float)  # the free root's, world
    sim = Simulation(character, controller.neutral, qvel, frame_time=FRAME, h=1.0 / 600.0,
                     torque_limit=400.0, push=push, fall=Fall("com", fraction=0.6, stop=False))
    controller.reset(sim)
    return sim


def _com_state(state: Simulated) -> tuple[np.ndarray, np.ndarray]:
    """The COM and its velocity now, y up (the frame's kinematics are current; the velocity
    pass is run here, as the controller's own step would)."""
    from course.physics.model import Y_TO_Z_MATRIX, import_mujoco

    mj, sim = import_mujoco(), state.sim
    mj.mj_comVel(sim.model, sim.data)
    mj.mj_subtreeVel(sim.model, sim.data)
    root = sim.character.bodies[0]
    to_y = Y_TO_Z_MATRIX.T
    return to_y @ sim.data.subtree_com[root], to_y @ sim.data.subtree_linvel[root]


def _advance(state: Simulated, answer: Any) -> Simulated:
    """One frame of the simulation with ``answer`` in use; a fallen character lies still."""
    if state.sim.fall_time is None:
        state.answer = answer
        state.sim.step(state.controller)
        state.frames += 1
    return state


# the capture point steering CaptureStep


def _start_stepping(args: tuple[Any, ...]) -> Simulated:
    """CaptureStep with the answer as its capture point; every body shoved to the call's
    ``com_velocity`` at t = 0."""
    from course.physics.stepping import CaptureStep

    state = Simulated(None, None)
    controller = CaptureStep(cmu_character(), capture_point=lambda *_: state.answer)
    state.controller, state.sim = controller, character_simulation(controller, args[1])
    return state


def _capture_call(state: Simulated) -> tuple[Any, ...]:
    com, vel = _com_state(state)
    return com, vel, float(state.sim.model.geom_pos[0, 2]), G


def _fell(state: Simulated) -> float | None:
    t: float | None = state.sim.fall_time
    return t


def _shove(velocity: Any) -> str:
    """``shoved backward at 0.30 m/s`` for a y-up velocity along one axis."""
    v = np.asarray(velocity, dtype=float)
    k = int(np.argmax(np.abs(v)))
    way = {(2, True): "forward", (2, False): "backward", (0, True): "to the left",
           (0, False): "to the right"}.get((k, bool(v[k] > 0)), "")
    return f"shoved {way} at {abs(v[k]):.2f} m/s"


def _times(n: int, what: str = "step") -> str:
    return f"{n} {what}{'s' * (n != 1)}"


def stepping_verdict(yours: Run, reference: Run, start: tuple[Any, ...]) -> str | None:
    """Whether the shoved character falls, and when its first recovery step starts, against
    the reference's (which steps and stays up)."""
    mine, ref = yours.states[-1], reference.states[-1]
    push = _shove(start[1])
    ref_first = ref.controller.capture_points[0][0]
    steps = mine.controller.capture_points
    fell = _fell(mine)
    if fell is not None and _fell(ref) is None:
        when = (f", the first at {steps[0][0]:.2f} s," if steps else
                " (your capture point never left its feet)")
        return (f"{push}, the character starts {_times(len(steps))}{when} and falls at "
                f"{fell:.2f} s; with the reference's capture point its first step starts at "
                f"{ref_first:.2f} s and it stays up for {STEP_FRAMES * FRAME:g} s")
    if not steps:
        return (f"{push}, the character never steps: your capture point stays over its feet, "
                f"where the reference's leaves them at {ref_first:.2f} s")
    t = steps[0][0]
    if abs(t - ref_first) > STEP_LATE:
        how = "late" if t > ref_first else "early"
        return (f"{push}, the character's first recovery step starts at {t:.2f} s, "
                f"{abs(t - ref_first):.2f} s {'later' if how == 'late' else 'earlier'} than "
                f"with the reference's capture point ({ref_first:.2f} s): yours leaves the "
                f"feet too {how}")
    return None


STEPPING = Rollout(STEP_FRAMES, _advance, stepping_verdict, _start_stepping, _capture_call,
                   seconds=30.0, hint=ROLLOUT_HINT)


def _first_call(start: Any, call: Any, at: int, n: int, velocity: np.ndarray
                ) -> tuple[Any, ...]:
    """The arguments of a run's first call: the run started with ``velocity`` at ``at``."""
    args: list[Any] = [None] * n
    args[at] = velocity
    out: tuple[Any, ...] = call(start(tuple(args)))
    return out


def stepping_runs(rng: np.random.Generator) -> list[Case]:
    if cmu_character() is None:
        return []
    cases = []
    for v in (-0.25, -0.27):
        velocity = np.array([0.0, 0.0, v])
        cases.append(Case(
            f"standing, {_shove(velocity)}: its capture point leaves its feet, and it must "
            f"step then (within {STEP_LATE:g} s of the reference) and stay up",
            _first_call(_start_stepping, _capture_call, 1, 4, velocity)))
    return cases


# SIMBICON's feedback placing the swing foot

#: the push every walk gets, mid-walk
WALK_PUSH = (np.array([0.0, 0.0, -100.0]), 2.0, 0.1)


def _start_walking(args: tuple[Any, ...]) -> Simulated:
    """SIMBICON with the answer as its sagittal feedback, every body moving at the call's
    ``com_velocity`` at t = 0, pushed by :data:`WALK_PUSH`."""
    from course.physics.simulation import Push
    from course.physics.walking import SIMBICON

    state = Simulated(None, None)
    controller = SIMBICON(cmu_character(), feedback=lambda *_: float(state.answer))
    force, when, duration = WALK_PUSH
    state.controller, state.sim = controller, character_simulation(
        controller, args[4], Push("Hips", force, when, duration))
    return state


def _walk_call(state: Simulated) -> tuple[Any, ...]:
    from course.physics.model import Y_TO_Z_MATRIX

    com, vel = _com_state(state)
    c = state.controller
    stance, _ = c.legs()
    ankle = Y_TO_Z_MATRIX.T @ state.sim.data.xpos[stance.foot]
    gait = c.gait
    return (gait.swing_hip[0 if c.phase == "lift" else 1], gait.c_d, gait.c_v, com, vel, ankle,
            c.heading)


def walking_verdict(yours: Run, reference: Run, start: tuple[Any, ...]) -> str | None:
    """Whether the walker falls, and the strides it walks, against the reference's."""
    mine, ref = yours.states[-1], reference.states[-1]
    strides, ref_strides = (len(s.controller.footsteps) // 2 for s in (mine, ref))
    seconds = WALK_FRAMES * FRAME
    force, when, _ = WALK_PUSH
    push = f"pushed {np.linalg.norm(force):.0f} N backward at {when:g} s"
    fell = _fell(mine)
    if fell is not None and _fell(ref) is None:
        after = "before the push" if fell < when else f"it was {push}"
        return (f"the walker falls at {fell:.2f} s, after {_times(strides, 'stride')} ({after}); "
                f"with the reference's feedback it walks {ref_strides} strides in {seconds:g} s "
                "and stays up")
    if strides < ref_strides - 1:
        return (f"the walker walks only {_times(strides, 'stride')} in {seconds:g} s (the "
                f"reference's: {ref_strides}): its feet do not keep up")
    return None


WALKING = Rollout(WALK_FRAMES, _advance, walking_verdict, _start_walking, _walk_call,
                  seconds=30.0, hint=ROLLOUT_HINT)


def walking_runs(rng: np.random.Generator) -> list[Case]:
    if cmu_character() is None:
        return []
    return [Case(f"walking 4 s from {what}, pushed 100 N backward at 2 s for 0.1 s",
                 _first_call(_start_walking, _walk_call, 4, 7, np.array([0.0, 0.0, v])))
            for what, v in (("rest", 0.0), ("a forward shove of 0.2 m/s", 0.2))]


# --- the catalogue of known mistakes -----------------------------------------------------------

MISCONCEPTIONS = (
    Misconception(
        "omega_from_y", "capture_point", "ω₀ from the COM's y, not its height above the ground",
        "ω₀ = √(g/h) with h the pendulum's length: the COM's height above the ground under "
        "the foot, com[..., 1] - ground_height. The COM's y is that only on a floor at y = 0.",
        wrong=lambda *a: capture_formula(*a, height="y")),
    Misconception(
        "times_omega", "capture_point", "ċ·ω₀ instead of ċ/ω₀ (or ω₀ = √(h/g))",
        "ξ - c must be a length: the velocity (m/s) divided by ω₀ = √(g/h) (1/s). ċ·ω₀, the "
        "same as dividing by √(h/g), is an acceleration and puts ξ about ω₀² ≈ 10 times too "
        "far.", wrong=lambda *a: capture_formula(*a, velocity="times")),
    Misconception(
        "omega_not_rooted", "capture_point", "ω₀ = g/h without the square root",
        "The pendulum is c̈ = (g/h)(c - p), so ω₀² = g/h and ω₀ = √(g/h): yours divides the "
        "velocity by g/h.", wrong=lambda *a: capture_formula(*a, omega="no_sqrt")),
    Misconception(
        "no_velocity", "capture_point", "the COM's ground projection, without the velocity term",
        "The capture point is where the foot must go for the pendulum to come to rest, "
        "ξ = c + ċ/ω₀: a moving COM needs a foot ahead of it. Yours returns the COM's own "
        "(x, z), right only at rest.", wrong=lambda *a: capture_formula(*a, velocity="none")),
    Misconception(
        "c_d_sign", "swing_hip_target", "the c_d term subtracted",
        "A COM ahead of the stance ankle (d > 0) is falling forward: the swing foot must land "
        "further forward to catch it, θ_d = θ_d0 + c_d d + c_v v. Yours subtracts c_d d and "
        "steps back.", wrong=lambda *a: hip_formula(*a, sign_d=-1.0)),
    Misconception(
        "c_v_sign", "swing_hip_target", "the c_v term subtracted",
        "A COM moving forward (v > 0) needs a longer step to stop it: θ_d = θ_d0 + c_d d + "
        "c_v v. Yours subtracts c_v v, so the faster the walker goes the shorter it steps.",
        wrong=lambda *a: hip_formula(*a, sign_v=-1.0)),
    Misconception(
        "d_from_origin", "swing_hip_target", "d measured from the world origin, not the "
        "stance ankle",
        "d is the COM's offset from the stance ankle, the pendulum's pivot: "
        "(com - stance_ankle) · f. The COM's own position grows with every step walked.",
        wrong=lambda *a: hip_formula(*a, pivot="origin")),
    Misconception(
        "heading_ignored", "swing_hip_target", "d and v along the world's z axis, not the "
        "walking direction",
        "The feedback is in the heading frame: d and v along f = (sin ψ, 0, cos ψ), the "
        "direction the character walks. Along the world's z axis it only holds for ψ = 0.",
        wrong=lambda *a: hip_formula(*a, along="z")),
    Misconception(
        "moment_sign", "zmp_from_forces", "the horizontal forces' moment with the wrong sign",
        "The moment about p of f at r is (r - p) × f; its horizontal part vanishes for "
        "p_x = Σ [x f_y - (y - p_y) f_x] / Σ f_y and p_z alike: a contact above the ground "
        "pushed forward moves the ZMP back, a minus.",
        wrong=lambda *a: zmp_formula(*a, moment=1.0)),
    Misconception(
        "vertical_only", "zmp_from_forces", "the horizontal forces left out",
        "Σ r_i f_{i,y} / Σ f_{i,y} is the ZMP only when every contact is on the ground plane; "
        "above it a horizontal force has a lever arm y_i - p_y: subtract (y_i - p_y) f_{i,x} "
        "(and f_{i,z}) in the sums.", wrong=lambda *a: zmp_formula(*a, moment=0.0)),
    Misconception(
        "unweighted_mean", "zmp_from_forces", "the mean of the contact points, not weighted by "
        "their normal forces",
        "The ZMP is where the resultant of the ground's forces acts: each contact weighs by its "
        "vertical (normal) force f_y, p = Σ r_i f_{i,y} / Σ f_{i,y} (plus the horizontal "
        "forces' moment). Yours averages the points equally.",
        wrong=lambda *a: zmp_formula(*a, weights="none")),
    Misconception(
        "norm_weighted", "zmp_from_forces", "the points weighted by |f|, not by the normal force",
        "Only the vertical part f_y of a contact force presses on the ground and weighs its "
        "point; the tangential (friction) part enters through its moment, -(y_i - p_y) f_x, "
        "not the weight. Yours weighs each point by the whole force's length |f_i|.",
        wrong=lambda *a: zmp_formula(*a, weights="norm")),
)


# --- the assignment ----------------------------------------------------------------------------

_FUNCTIONS = (
    Function("capture_point", ("com", "com_velocity", "ground_height", "gravity"),
             capture_reference, Check(None, atol=1e-9, rtol=1e-9, noun="capture point")),
    Function("swing_hip_target",
             ("theta_d0", "c_d", "c_v", "com", "com_velocity", "stance_ankle", "heading"),
             hip_reference, Check(None, atol=1e-9, rtol=1e-9, noun="swing hip target")),
    Function("zmp_from_forces", ("positions", "forces", "ground_height"), zmp_reference,
             Check(None, atol=1e-9, rtol=1e-9, noun="ZMP")),
)

ASSIGNMENT = Assignment(
    key="a7",
    title="Walking: the capture point, SIMBICON's feedback and the ZMP",
    template="a7_walking.py",
    functions=_FUNCTIONS,
    tests=(
        *random_edge_hidden("capture_point", capture_random, capture_edges, capture_hidden),
        Test("capture_point: a shoved character steps where it points",
             "capture_point", 1.0, stepping_runs, rollout=STEPPING),
        *random_edge_hidden("swing_hip_target", hip_random, hip_edges, hip_hidden),
        Test("swing_hip_target: the character walks 4 s and is pushed", "swing_hip_target",
             1.0, walking_runs, rollout=WALKING),
        *random_edge_hidden("zmp_from_forces", zmp_random, zmp_edges, zmp_hidden),
    ),
    misconceptions=MISCONCEPTIONS,
)
