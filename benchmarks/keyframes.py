"""Keyframe evaluation speed: every interpolation scheme on 1 000 joints x 10 000 times.

Run:  .venv/bin/python benchmarks/keyframes.py [--joints 1000] [--times 10000] [--keys 100]

Seeded random keys at uneven times: positions (K, J, 3) for the position schemes, unit
quaternions (K, J, 4), each about 60 degrees from the previous, for the rotation schemes.
Every scheme evaluates the J curves at T times spread over the key range, in chunks of
``--chunk`` times (one vectorised call per chunk: the output of a chunk is chunk x J x 4
floats, so memory stays bounded). Printed per scheme: the best of ``--repeats`` runs of the
whole T x J evaluation (taken round-robin over the schemes, so a burst of load hits all
alike), nanoseconds per (joint, time) and the ratio to ``linear``, the baseline measured
beside it in the same run (the machine is shared; ratios are what to compare).
``polynomial`` uses only the first 8 keys: with all K keys it would be Runge's nonsense,
and its cost grows with K by construction.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np

from course import keyframes as kf
from course import rotations as rot


def keys(n_keys: int, n_joints: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Uneven key times (K,), positions (K, J, 3) and rotation keys (K, J, 4)."""
    rng = np.random.default_rng(seed)
    times = np.cumsum(rng.uniform(0.5, 1.5, size=n_keys))
    positions = np.cumsum(rng.normal(size=(n_keys, n_joints, 3)), axis=0)
    steps = rot.quat_from_rotvec(rng.normal(size=(n_keys - 1, n_joints, 3)) * 0.6)
    q = [rot.quat_normalize(rng.normal(size=(n_joints, 4)))]
    for s in steps:
        q.append(rot.quat_mul(s, q[-1]))
    return times, positions, np.array(q)


def best_times(fns: dict[str, Callable[[], object]], repeats: int) -> dict[str, float]:
    """Best of ``repeats`` runs per function, taken round-robin (every function once per
    round), so a burst of load on the shared machine hits all of them alike."""
    best = dict.fromkeys(fns, np.inf)
    for _ in range(repeats):
        for name, fn in fns.items():
            start = time.perf_counter()
            fn()
            best[name] = min(best[name], time.perf_counter() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--joints", type=int, default=1000)
    parser.add_argument("--times", type=int, default=10000)
    parser.add_argument("--keys", type=int, default=100)
    parser.add_argument("--chunk", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()

    times, positions, quats = keys(args.keys, args.joints)
    t = np.linspace(times[0], times[-1], args.times)
    chunks = np.array_split(t, max(1, args.times // args.chunk))
    few = slice(0, 8)
    t_few = np.linspace(times[0], times[7], args.times)
    chunks_few = np.array_split(t_few, len(chunks))
    tangents = kf.cubic_tangents(positions, times)
    schemes: dict[str, Callable[[np.ndarray], np.ndarray]] = {
        "linear": lambda c: kf.linear(positions, times, c),
        "hermite (given tangents)": lambda c: kf.hermite(positions, tangents, times, c),
        "cubic (natural, with solve)": lambda c: kf.cubic(positions, times, c),
        "catmull_rom (time)": lambda c: kf.catmull_rom(positions, times, c),
        "catmull_rom (centripetal)": lambda c: kf.catmull_rom(positions, times, c,
                                                              knots="centripetal"),
        "catmull_rom velocity": lambda c: kf.catmull_rom(positions, times, c, derivative=1),
        "slerp_keys": lambda c: kf.slerp_keys(quats, times, c),
        "squad": lambda c: kf.squad(quats, times, c),
    }
    runs = {name: (lambda fn=fn: [fn(c) for c in chunks]) for name, fn in schemes.items()}
    runs["polynomial (8 keys)"] = lambda: [kf.polynomial(positions[few], times[few], c)
                                           for c in chunks_few]
    best = best_times(runs, args.repeats)

    print(f"{args.joints} joints x {args.times} times, {args.keys} keys at uneven times, "
          f"{len(chunks)} chunks, best of {args.repeats} (round-robin)")
    print(f"{'scheme':30} {'seconds':>8} {'ns/(joint*time)':>16} {'/ linear':>9}")
    n = args.joints * args.times
    for name, seconds in best.items():
        print(f"{name:30} {seconds:8.3f} {1e9 * seconds / n:16.1f} "
              f"{seconds / best['linear']:9.2f}")


if __name__ == "__main__":
    main()
