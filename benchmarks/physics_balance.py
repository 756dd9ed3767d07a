"""Static balance (course.physics.balance), measured: simulation rate of :func:`stand`, the
largest push each controller survives on the bundled sample and the CMU skeleton, and the
largest stable kp of plain and stable PD tracking, the numbers docs/physics.md ("A character
that stands: static balance") and tests/test_physics_balance.py quote.

Run:  .venv/bin/python benchmarks/physics_balance.py [--repeats 3] [--no-kp]

Pushes act on the root for 0.1 s from t = 0.25 s; the character survives when its COM is
above 60% of its initial height 1.5 s after the push ends; bisection to 5 N. h = 1/600 s,
joint PD kp 1000, kd 5, COM PD 1000 N/m, 200 N s/m, torque limit 400 N m (the defaults of
``stand``). Directions are y-up: +z is where the feet point (forward), +x the character's
left. The CMU clip comes from $COURSE_DATA_DIR or ../shared/data/bvh and is skipped when
absent.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from course.bvh import load_bvh
from course.physics.balance import CONTROLLERS, largest_push, stand, standing_pose
from course.physics.character import build_model, effective_inertia, track

SAMPLE = Path(__file__).resolve().parents[1] / "course" / "data" / "samples" / "wave.bvh"
DIRECTIONS = {"forward": (0.0, 0.0, 1.0), "backward": (0.0, 0.0, -1.0), "sideways": (1.0, 0.0, 0.0)}


def clip_path() -> Path:
    env = os.environ.get("COURSE_DATA_DIR")
    base = Path(env) if env else Path(__file__).resolve().parents[2] / "shared" / "data" / "bvh"
    return base / "cmu_12_01_walk.bvh"


def balance(name: str, path: Path, repeats: int) -> None:
    motion = load_bvh(path)
    character = build_model(motion.skeleton)
    pose = standing_pose(character)
    print(f"\n== {name}: {character.total_mass:.1f} kg, nv = {character.model.nv}")
    for controller in CONTROLLERS:
        rate = max(stand(character, pose, controller=controller, duration=3.0).rate
                   for _ in range(repeats))
        print(f"  stand, {controller:5s}: {rate:6.1f} simulated s per wall s")
    print("  largest push (N, 0.1 s; impulse N s in brackets):")
    print(f"  {'direction':10s}" + "".join(f"{c:>18s}" for c in CONTROLLERS))
    for label, d in DIRECTIONS.items():
        forces = [largest_push(character, pose, controller=c, direction=d) for c in CONTROLLERS]
        print(f"  {label:10s}" + "".join(f"{f:9.1f} ({0.1 * f:5.2f})" for f in forces))


def kp_ceiling(walk_path: Path) -> None:
    walk = load_bvh(walk_path)[1:]
    character = build_model(walk.skeleton)
    i_min = float(effective_inertia(character, walk).min())
    print(f"\n== largest stable kp, CMU walk, root held, 0.5 s; I_min = {i_min:.4f} kg m^2")
    print(f"  {'h':>7s} {'law':28s} {'kp_max':>10s} {'kp_max h^2 / I_min':>20s}")
    for h in (1.0 / 600.0, 1.0 / 120.0):
        for label, stable_pd, kd_h in (
            ("plain PD, kd = 0", False, 0.0),
            ("plain PD, kd = kp h", False, 1.0),
            ("stable PD, kd = kp h", True, 1.0),
            ("stable PD, kd = 10 kp h", True, 10.0),
        ):
            def ok(kp: float, stable_pd: bool = stable_pd, kd_h: float = kd_h,
                   h: float = h) -> bool:
                run = track(character, walk, kp=kp, kd=kd_h * kp * h, hold_root=True,
                            n_frames=61, h=h, stable_pd=stable_pd)
                return not run.unstable and run.error_cm.max() < 50.0

            lo, hi = 10.0, 1e8
            for _ in range(14):
                mid = float(np.sqrt(lo * hi))
                lo, hi = (mid, hi) if ok(mid) else (lo, mid)
            print(f"  1/{round(1 / h):<5d} {label:28s} {lo:10.3g} {lo * h * h / i_min:20.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-kp", action="store_true", help="skip the kp-ceiling table")
    args = parser.parse_args()
    balance("sample (course/data/samples/wave.bvh)", SAMPLE, args.repeats)
    path = clip_path()
    if path.exists():
        balance("CMU (cmu_12_01_walk.bvh)", path, args.repeats)
        if not args.no_kp:
            kp_ceiling(path)
    else:
        print(f"\nCMU clip not found at {path}: skipped")


if __name__ == "__main__":
    main()
