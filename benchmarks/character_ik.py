"""IK over a clip: a planted foot, two effectors, every frame warm-started (``solve_motion``).

Run:  .venv/bin/python benchmarks/character_ik.py [--frames 500] [--method dls] [--repeats 3]

The CMU walk (read from $COURSE_DATA_DIR or ../shared/data/bvh), its first ``--frames``
frames, is solved with ``root="LeftFoot"`` (the foot stays where it is in frame 0, the hips
move over it) and both hands reaching to moving targets around where they are in frame 0:
the left hand circling in towards the body, the right hand drawn in and out
(``course.ik.hand_targets``, as ``tests/test_ik_character.py``). Figures printed, each the
best of ``--repeats`` runs:

- warm: ``solve_motion`` as it is meant to run, each frame started from the previous
  frame's solution; frames per second of wall time and of CPU time (on a shared machine the
  CPU-time figure is what a quiet one would give; the goal is >= 200 frames/s);
- cold: the same frames each solved alone from the clip's own pose (``warm_start=False``);
- the ratio cold / warm of the time per frame, with the mean iterations per frame of each,
  and how many frames converged (their reasons otherwise).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from course.bvh import load_bvh
from course.ik import hand_targets, solve_motion
from course.motion import Motion

REPO = Path(__file__).resolve().parents[1]


def run(motion: Motion, targets: dict, method: str, warm: bool,
        repeats: int) -> tuple[float, float, object]:
    """Best wall and CPU seconds of ``repeats`` solves of the clip, and the last answer."""
    wall = cpu = np.inf
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        out = solve_motion(motion, targets, method=method, root="LeftFoot", tol=1e-4,
                           warm_start=warm)
        wall = min(wall, time.perf_counter() - w0)
        cpu = min(cpu, time.process_time() - c0)
    return wall, cpu, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=500)
    parser.add_argument("--method", default="dls")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    folder = Path(os.environ.get("COURSE_DATA_DIR", REPO.parent / "shared" / "data" / "bvh"))
    motion = load_bvh(folder / "cmu_12_01_walk.bvh")[:args.frames]
    F = motion.n_frames
    targets = hand_targets(motion)
    print(f"{F} frames of the CMU walk, root LeftFoot, effectors LeftHand + RightHand, "
          f"method {args.method}, tol 1e-4, best of {args.repeats}")
    times = {}
    for label, warm in (("warm", True), ("cold", False)):
        wall, cpu, out = run(motion, targets, args.method, warm, args.repeats)
        times[label] = wall
        reasons = {r: int(n) for r, n in zip(*np.unique(out.reasons, return_counts=True),
                                             strict=True) if r}
        print(f"{label}: {F / wall:7.1f} frames/s wall, {F / cpu:7.1f} frames/s CPU; "
              f"{out.iterations.mean():5.2f} iterations/frame; converged {out.converged.sum()}"
              f"/{F}{f' (else {reasons})' if reasons else ''}; largest residual "
              f"{out.residuals.max():.2e}")
    print(f"cold / warm time per frame: {times['cold'] / times['warm']:.2f}x")


if __name__ == "__main__":
    main()
