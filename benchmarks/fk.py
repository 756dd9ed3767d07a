"""Forward kinematics speed: the library against a component-major quaternion baseline.

Run:  .venv/bin/python benchmarks/fk.py [--frames 10000] [--repeats 7]

Poses are seeded random unit quaternions on the 31 joints of the CMU walk skeleton (its End
Sites dropped), the clip read from $COURSE_DATA_DIR or ../shared/data/bvh. Figures printed:

- library: ``course.fk.forward_kinematics`` on frame-major (F, J, 4) input, everything
  included (checks, the input's layout change); its results have the shapes (F, J, 3) and
  (F, J, 4) but, like the baseline's, component-major memory (frames-fastest strides);
- C-order copy: what ``np.ascontiguousarray`` of both results would add, for reference;
- baseline: the same recursion on input already stored component-major (w, x, y, z as
  separate contiguous (J, F) arrays), one joint at a time, plain elementwise numpy on (F,)
  arrays; the goal is library / baseline <= 1.5;
- frame-major: one joint at a time on (F, 4) slices of frame-major arrays;
- naive: what a first attempt looks like, a Python loop over frames and joints with plain
  numpy quaternion maths on (4,) and (3,) arrays, timed on a subset of frames and
  extrapolated linearly.

All timings are the best of ``--repeats`` runs of ``time.perf_counter``.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from course.bvh import load_bvh
from course.fk import forward_kinematics
from course.rotations import _kernels

REPO = Path(__file__).resolve().parents[1]


def walk_skeleton() -> tuple[list[str], np.ndarray, np.ndarray]:
    """Names, parents and offsets of the CMU walk's 31 joints (End Sites dropped)."""
    folder = Path(os.environ.get("COURSE_DATA_DIR", REPO.parent / "shared" / "data" / "bvh"))
    skeleton = load_bvh(folder / "cmu_12_01_walk.bvh").skeleton
    keep = [j for j, name in enumerate(skeleton.names) if not name.endswith("_end")]
    new = {old: new for new, old in enumerate(keep)}
    return (
        [skeleton.names[j] for j in keep],
        np.array([new.get(int(skeleton.parents[j]), -1) for j in keep]),
        skeleton.offsets[keep],
    )


def random_pose(n_frames: int, n_joints: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n_frames, n_joints, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    return q, rng.normal(scale=10.0, size=(n_frames, 3))


def baseline(parents, offsets, rw, rx, ry, rz, root_position_T):
    """Component-major FK: ``r* (J, F)`` contiguous, returns lists of (F,) components."""
    J = len(parents)
    Q: list = [None] * J
    P: list = [None] * J
    Q[0] = (rw[0], rx[0], ry[0], rz[0])
    P[0] = tuple(root_position_T)
    for j in range(1, J):
        aw, ax, ay, az = Q[parents[j]]
        bw, bx, by, bz = rw[j], rx[j], ry[j], rz[j]
        Q[j] = (
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        )
        vx, vy, vz = offsets[j]
        tx, ty, tz = 2 * (ay * vz - az * vy), 2 * (az * vx - ax * vz), 2 * (ax * vy - ay * vx)
        px, py, pz = P[parents[j]]
        P[j] = (
            px + vx + aw * tx + ay * tz - az * ty,
            py + vy + aw * ty + az * tx - ax * tz,
            pz + vz + aw * tz + ax * ty - ay * tx,
        )
    return Q, P


def frame_major(parents, offsets, R, root_position):
    """One joint at a time on (F, 4) slices of frame-major arrays."""
    Q = np.empty_like(R)
    P = np.empty(R.shape[:-1] + (3,))
    Q[:, 0], P[:, 0] = R[:, 0], root_position
    for j in range(1, len(parents)):
        p = parents[j]
        Q[:, j] = _kernels.quat_mul(Q[:, p], R[:, j])
        P[:, j] = P[:, p] + _kernels.quat_rotate(Q[:, p], offsets[j])
    return P, Q


def naive_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of two (4,) quaternions, written from the formula."""
    wa, va, wb, vb = a[0], a[1:], b[0], b[1:]
    return np.concatenate([[wa * wb - va @ vb], wa * vb + wb * va + np.cross(va, vb)])


def naive_rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """q v q* of a unit (4,) quaternion and a (3,) vector."""
    return naive_mul(naive_mul(q, np.concatenate([[0.0], v])), q * [1, -1, -1, -1])[1:]


def naive(parents, offsets, R, root_position):
    """What a first attempt looks like: loop over frames, then joints, one quaternion at a
    time (no input checks, no library calls)."""
    Q = np.empty_like(R)
    P = np.empty(R.shape[:-1] + (3,))
    for f in range(len(R)):
        Q[f, 0], P[f, 0] = R[f, 0], root_position[f]
        for j in range(1, len(parents)):
            p = parents[j]
            Q[f, j] = naive_mul(Q[f, p], R[f, j])
            P[f, j] = P[f, p] + naive_rotate(Q[f, p], offsets[j])
    return P, Q


def best_of(fn: Callable[[], object], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=10_000)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--naive-frames", type=int, default=100)
    args = parser.parse_args()

    names, parents, offsets = walk_skeleton()
    parents_list = parents.tolist()
    F, J = args.frames, len(names)
    R, root = random_pose(F, J)
    components = [np.ascontiguousarray(R[..., c].T) for c in range(4)]  # 4 x (J, F)
    root_T = np.ascontiguousarray(root.T)

    # Same numbers from all four before timing anything.
    P, Q = forward_kinematics(parents, offsets, R, root)
    Qb, Pb = baseline(parents_list, offsets, *components, root_T)
    P_fm, Q_fm = frame_major(parents_list, offsets, R, root)
    n = args.naive_frames
    P_nv, Q_nv = naive(parents_list, offsets, R[:n], root[:n])
    assert np.allclose(P, np.stack([np.stack(p, -1) for p in Pb], 1), atol=1e-9)
    assert np.allclose(Q, np.stack([np.stack(q, -1) for q in Qb], 1), atol=1e-12)
    assert np.allclose(P, P_fm, atol=1e-9) and np.allclose(P[:n], P_nv, atol=1e-9)
    assert np.allclose(Q, Q_fm, atol=1e-12) and np.allclose(Q[:n], Q_nv, atol=1e-12)

    r = args.repeats
    t_base = best_of(lambda: baseline(parents_list, offsets, *components, root_T), r)
    t_lib = best_of(lambda: forward_kinematics(parents, offsets, R, root), r)
    t_copy = best_of(lambda: (np.ascontiguousarray(P), np.ascontiguousarray(Q)), r)
    t_fm = best_of(lambda: frame_major(parents_list, offsets, R, root), max(2, r // 3))
    t_nv = best_of(lambda: naive(parents_list, offsets, R[:n], root[:n]), 2) * F / n

    print(f"forward kinematics, {F} frames x {J} joints (CMU 12_01 walk skeleton)")
    print(f"  library     forward_kinematics      {t_lib * 1e3:9.2f} ms")
    print(f"  baseline    component-major         {t_base * 1e3:9.2f} ms")
    print(f"  ratio       library / baseline      {t_lib / t_base:9.2f}    (goal <= 1.5)")
    print(f"  C-order copy of both results        {t_copy * 1e3:9.2f} ms  (not needed by numpy)")
    print(
        f"  frame-major per-joint (F,4) slices  {t_fm * 1e3:9.2f} ms  "
        f"({t_fm / t_lib:.1f}x library)"
    )
    print(
        f"  naive loop  frames x joints         {t_nv * 1e3:9.0f} ms  ({t_nv / t_lib:.0f}x library;"
        f" timed on {n} frames, extrapolated to {F})"
    )


if __name__ == "__main__":
    main()
