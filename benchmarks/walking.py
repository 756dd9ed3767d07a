"""Walking (course.physics.walking, SIMBICON) and stepping to recover (course.physics.stepping)
on the CMU character, measured: strides walked, the real-time factor beside raw ``mj_step`` on
the same model and the same states, the largest push survived while walking and while standing
with and without capture-point stepping, beside notebook 14's standing controllers on its own
pose. docs/walking_control.md quotes these figures.

Run:  .venv/bin/python benchmarks/walking.py [--duration 40] [--tol 10]

Pushes act on the root for 0.1 s. Walking: at eight instants spread over one stride (from
t = 5 s, every 0.0725 s: the stride is 0.58 s), a force survived only if the walker has not
fallen (COM below 60% of its height) 5 s after the push at every one of them; beside it the
figure for t = 5 s alone, which is not monotonic in the force (an isolated survivor).
Standing with and without stepping (the neutral pose, ``stepping.stand_and_step``): from
0.25 s, survived if standing 2 s later. Notebook 14 (``balance.stand`` on ``standing_pose``,
its controllers "none", "ankle", "com"): from 0.25 s, 1.5 s later, as docs/physics.md
measures them. Walking figures are bisections to ``--tol`` N; standing ones are scans (every
force ``tol``, ``2 tol``, ... survived up to the figure, the next one falls), because standing
survival is not monotonic either (the first version of stepping survived a 100 N backward
push, fell at 110-120 and survived 130-150; its bisection found 175, an isolated survivor;
the bisection is printed beside). Stepping is ``stand_and_step``'s default,
``stepping.RECOVERY``.
Directions are y-up: +z forward, +x the character's left. The last line printed is the
summary; each push figure there is the smallest impulse over the four directions (what it
survives from any side). The CMU clip comes from $COURSE_DATA_DIR or ../shared/data/bvh.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from course.bvh import load_bvh
from course.physics import balance
from course.physics.character import Character, Push, build_model
from course.physics.simulation import Fall, Simulation
from course.physics.stepping import largest_push as stepping_push
from course.physics.stepping import stand_and_step
from course.physics.walking import SIMBICON, largest_push

DIRECTIONS = {"forward": (0.0, 0.0, 1.0), "backward": (0.0, 0.0, -1.0),
              "left": (1.0, 0.0, 0.0), "right": (-1.0, 0.0, 0.0)}
DURATION = 0.1  # s, every push
PHASES = tuple(5.0 + 0.0725 * k for k in range(8))  # one stride of the walk (0.58 s)


def clip_path() -> Path:
    env = os.environ.get("COURSE_DATA_DIR")
    base = Path(env) if env else Path(__file__).resolve().parents[2] / "shared" / "data" / "bvh"
    return base / "cmu_12_01_walk.bvh"


def scan(survives: Callable[[float], bool], step: float, limit: float = 3000.0) -> float:
    """The largest force on the grid ``step, 2 step, ...`` up to which every force of the
    grid is survived (0 if ``step`` falls)."""
    force = 0.0
    while force + step <= limit and survives(force + step):
        force += step
    return force


def standing(character: Character, direction: tuple[float, float, float], step: float,
             **run: Any) -> float:
    """:func:`scan` of a standing run: ``stepping=True/False`` (stand_and_step on the neutral
    pose) or ``controller=`` and ``pose=`` (notebook 14's ``balance.stand``)."""
    d = np.asarray(direction)

    def survives(force: float) -> bool:
        push = Push("Hips", force * d, 0.25, DURATION)
        if "stepping" in run:
            return not stand_and_step(character, duration=0.25 + DURATION + 2.0, push=push,
                                      stop_when_fallen=True, **run).fell
        return not balance.stand(character, duration=0.25 + DURATION + 1.5, push=push,
                                 stop_when_fallen=True, **run).fell

    return scan(survives, step)


def rates(character: Character, duration: float) -> tuple[int, float, bool, float, float, float]:
    """Strides, simulated seconds, fell, distance (m), the walk's real-time factor, and raw
    ``mj_step``'s on the same model (the controller's integrator and damping) replaying the
    walk's own frames (each frame's start state and its torques), so both step through the
    same contacts."""
    import mujoco  # type: ignore[import-untyped]

    controller = SIMBICON(character)
    sim = Simulation(character, controller.neutral, frame_time=1 / 60, h=1 / 600,
                     torque_limit=400.0, fall=Fall("com", fraction=0.6, stop=True))
    controller.reset(sim)
    frames: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    start = time.perf_counter()
    reason = None
    while sim.frame < round(duration * 60) and reason is None:
        qpos, qvel = sim.data.qpos.copy(), sim.data.qvel.copy()
        reason = sim.step(controller)
        frames.append((qpos, qvel, sim.data.qfrc_applied.copy()))
    wall = time.perf_counter() - start
    simulated = sim.frame / 60
    com = sim.recording().com
    distance = float(np.hypot(*(com[-1, :2] - com[0, :2])))
    model, data = sim.model, mujoco.MjData(sim.model)
    raw = 0.0
    for qpos, qvel, tau in frames:
        data.qpos[:], data.qvel[:], data.qfrc_applied[:] = qpos, qvel, tau
        t0 = time.perf_counter()
        for _ in range(sim.substeps):
            mujoco.mj_step(model, data)
        raw += time.perf_counter() - t0
    return (len(controller.footsteps) // 2, simulated, reason == "fell", distance,
            simulated / wall, simulated / raw)


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--duration", type=float, default=40.0)
    parser.add_argument("--tol", type=float, default=10.0)
    args = parser.parse_args()
    path = clip_path()
    if not path.exists():
        print(f"CMU clip not found at {path}: skipped")
        return
    character = build_model(load_bvh(path).skeleton)
    strides, simulated, fell, distance, rate, raw = rates(character, args.duration)
    print(f"walk from rest, {args.duration:.0f} s: {strides} strides, fell {fell}, "
          f"{distance:.1f} m")
    print(f"real-time factor: walk {rate:.1f}, raw mj_step on the same model and states {raw:.1f}")
    pose = balance.standing_pose(character)
    print(f"largest push, {DURATION} s on the root (N; impulse N s = N x {DURATION}), "
          f"bisection to {args.tol} N")
    print(f"  {'direction':10s}{'walking':>9s}{'at 5 s':>8s}{'stepping':>10s}{'bisect':>8s}"
          f"{'no step':>9s}{'nb14 none':>11s}{'ankle':>7s}{'com':>7s}")
    walking, stepping, without, nb14 = [], [], [], []
    for label, d in DIRECTIONS.items():
        w = largest_push(character, direction=d, tol=args.tol, duration=DURATION,
                         start=PHASES)
        w5 = largest_push(character, direction=d, tol=args.tol, duration=DURATION)
        s = standing(character, d, args.tol, stepping=True)
        sb = stepping_push(character, stepping=True, direction=d, tol=args.tol,
                           duration=DURATION)
        n = standing(character, d, args.tol, stepping=False)
        nb = [standing(character, d, args.tol, controller=c, pose=pose)
              for c in balance.CONTROLLERS]
        walking.append(w)
        stepping.append(s)
        without.append(n)
        nb14.append(nb)
        print(f"  {label:10s}{w:9.1f}{w5:8.1f}{s:10.1f}{sb:8.1f}{n:9.1f}{nb[0]:11.1f}"
              f"{nb[1]:7.1f}{nb[2]:7.1f}", flush=True)
    worst = np.min(np.array(nb14), axis=0)  # per controller, over the directions
    best = int(np.argmax(worst))
    print(f"notebook 14's best standing controller from any side: {balance.CONTROLLERS[best]!r}"
          f", {DURATION * worst[best]:.1f} N s")
    p, s, q = (DURATION * float(np.min(x)) for x in (walking, stepping, without))
    print(f"walking: {strides} strides in {simulated:.1f} s simulated, real-time factor "
          f"{rate:.1f}, largest push walking {p:.1f} N s, standing with stepping {s:.1f} N s, "
          f"standing without {q:.1f} N s")


if __name__ == "__main__":
    main()
