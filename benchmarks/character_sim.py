"""The simulated character (course.physics.character), measured: simulation rate, tracking
error against kp, fall time, and the largest stable kp at one step, the numbers
docs/physics.md ("A simulated character") and tests/test_physics_character.py quote.

Run:  .venv/bin/python benchmarks/character_sim.py [--repeats 3]

The clip is the CMU walk (cmu_12_01_walk.bvh from $COURSE_DATA_DIR or ../shared/data/bvh)
without its frame 0 (a different pose), 523 frames at 120 fps = 4.35 s; h = 1/600 s (5 steps
per frame); kd = 0.2 sqrt(kp) unless said. The rate is simulated seconds per wall-clock
second of the whole loop (PD law in numpy + mj_step), the best of ``--repeats`` runs.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from course.bvh import load_bvh
from course.physics.character import TrackingResult, build_model, effective_inertia, track

H = 1.0 / 600.0


def clip_path() -> Path:
    env = os.environ.get("COURSE_DATA_DIR")
    base = Path(env) if env else Path(__file__).resolve().parents[2] / "shared" / "data" / "bvh"
    return base / "cmu_12_01_walk.bvh"


def _error(run: TrackingResult) -> str:
    if run.unstable:
        return "unstable"
    return f"{run.error_cm.mean():6.2f} / {run.error_cm.max():6.2f}"


def _fall(run: TrackingResult) -> str:
    if run.unstable:
        return "unstable"
    return f"{run.fall_time:.3f}" if run.fall_time is not None else "no fall"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    path = clip_path()
    if not path.exists():
        sys.exit(f"clip not found: {path}")
    walk = load_bvh(path)[1:]
    character = build_model(walk.skeleton)
    model = character.model
    print(f"{walk!r}; model: {model.nbody - 1} bodies, nq={model.nq}, nv={model.nv}, "
          f"{character.total_mass:.1f} kg, scale {character.scale} m/unit")

    kp = 1000.0
    runs = [track(character, walk, kp=kp, kd=0.2 * np.sqrt(kp), hold_root=True, h=H)
            for _ in range(args.repeats)]
    best = max(runs, key=lambda r: r.rate)
    print(f"rate (root held, kp={kp:g}, h=1/600): {best.rate:.1f} simulated s per wall s "
          f"({best.sim_time:.2f} s in {best.wall_time * 1e3:.0f} ms)")
    free = track(character, walk, kp=kp, kd=0.2 * np.sqrt(kp), h=H)
    print(f"rate (root free, kp={kp:g}): {free.rate:.1f} simulated s per wall s")

    print("\n    kp      kd   held: mean/max err cm   free: fall s   "
          "SPD held: mean/max err cm   SPD free: fall s")
    for kp in (30.0, 100.0, 300.0, 1000.0, 3000.0):
        kd = 0.2 * np.sqrt(kp)
        held = track(character, walk, kp=kp, kd=kd, hold_root=True, h=H)
        fr = track(character, walk, kp=kp, kd=kd, h=H)
        spd = track(character, walk, kp=kp, kd=kd, hold_root=True, h=H, stable_pd=True)
        spd_free = track(character, walk, kp=kp, kd=kd, h=H, stable_pd=True)
        print(f"{kp:7g} {kd:6.2f}   {_error(held):>22s}   {_fall(fr):>12s}   "
              f"{_error(spd):>26s}   {_fall(spd_free):>15s}")

    i_min = float(effective_inertia(character, walk).min())
    predicted = i_min * (2.0 / H) ** 2
    for label, kd_per_kp, spd_on in (("plain PD, kd=0", 0.0, False),
                                    ("plain PD, kd=kp h", H, False),
                                    ("stable PD, kd=kp h", H, True)):
        lo, hi = 100.0, 1e6
        for _ in range(14):
            mid = float(np.sqrt(lo * hi))
            r = track(character, walk, kp=mid, kd=kd_per_kp * mid, hold_root=True, n_frames=61,
                      h=H, stable_pd=spd_on)
            lo, hi = (mid, hi) if (not r.unstable and r.error_cm.max() < 50.0) else (lo, mid)
        print(f"largest stable kp at h=1/600, {label:20s}: {lo:9.0f}  "
              f"(omega h = {np.sqrt(lo / i_min) * H:.2f}; I_min {i_min:.4f} kg m^2, "
              f"omega h = 2 predicts {predicted:.0f})")


if __name__ == "__main__":
    main()
