"""BVH reading and writing speed, as ratios against baselines measured beside them.

* Loading a real clip (CMU 01_01, 2752 frames x 96 channels) against numpy's C parser reading
  the same frame lines alone, the floor of any loader that checks nothing: the ratio is what
  the hierarchy, the checks and the Euler-to-quaternion conversion cost on top.
* Saving chains 1000 and 4000 joints deep: size and time ratios near 4 mean linear growth
  (indentation stops growing at a fixed depth; a tab per level made it 16).

Run: ``.venv/bin/python benchmarks/bvh.py`` (needs the shared clips, see ``course/data``).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from course.bvh import format_bvh, load_bvh, parse_bvh

CLIP = Path(os.environ.get("COURSE_DATA_DIR", Path(__file__).resolve().parents[2] / "shared"
                           / "data" / "bvh")) / "01_01.bvh"
REPEATS = 15


def best_of(f, repeats: int = REPEATS) -> float:
    """The fastest of ``repeats`` runs of ``f`` (seconds of CPU time: the machine is shared)."""
    f()
    times = []
    for _ in range(repeats):
        start = time.process_time()
        f()
        times.append(time.process_time() - start)
    return min(times)


def deep_chain(depth: int) -> str:
    lines = ["HIERARCHY", "ROOT J0", "{", "OFFSET 0 0 0", "CHANNELS 1 Zrotation"]
    for j in range(1, depth):
        lines += [f"JOINT J{j}", "{", "OFFSET 0 1 0", "CHANNELS 1 Zrotation"]
    lines += ["}"] * depth + ["MOTION", "Frames: 1", "Frame Time: 0.1", "5 " * depth]
    return "\n".join(lines) + "\n"


def main() -> None:
    text = CLIP.read_text()
    rows = text.split("Frame Time:")[1].splitlines()[1:]
    load = best_of(lambda: load_bvh(CLIP))
    floor = best_of(lambda: np.loadtxt(rows, comments=None, ndmin=2))
    print(f"load {CLIP.name}: {load * 1e3:.1f} ms; numpy.loadtxt of its frame lines alone: "
          f"{floor * 1e3:.1f} ms; ratio {load / floor:.2f}")

    motions = {depth: parse_bvh(deep_chain(depth)) for depth in (1000, 4000)}
    sizes = {depth: len(format_bvh(m)) for depth, m in motions.items()}
    times = {depth: best_of(lambda m=m: format_bvh(m), 3) for depth, m in motions.items()}
    print(f"save chains 1000 / 4000 deep: {sizes[1000] / 1e6:.2f} / {sizes[4000] / 1e6:.2f} MB "
          f"(ratio {sizes[4000] / sizes[1000]:.2f}), {times[1000] * 1e3:.0f} / "
          f"{times[4000] * 1e3:.0f} ms (ratio {times[4000] / times[1000]:.2f}); linear is 4")


if __name__ == "__main__":
    main()
