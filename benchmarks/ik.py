"""Speed of course.ik against ikpy on a 7-joint chain, and batched throughput.

The chain: 7 unit bones along +x, hinge axes alternating y, z, y, z, y, z, y (so targets fill
3D). 200 seeded targets are the end positions of random joint angles in [-1.5, 1.5] (all
reachable), every solve starts from the zero pose, tolerance 1e-4, and every method (ikpy
included) solves all 200. ikpy solves the same hinge chain built from URDFLinks, timed in the
same run; each row's ``x ikpy`` is ikpy's median time over that row's. Every solve (ikpy's
too) is timed ``REPEATS`` times and its fastest time kept, so that other processes on a shared
machine weigh on neither side; the iterations and success are those of the solve itself.

The ``joints`` column says which joint model a row solves. The issue's chain is the hinge
chain, and every method runs on it. FABRIK is a ball-joint algorithm (it moves points; on
hinges its backward pass turns each hinge by a least-squares fit, slower: see the FABRIK
docstring), so its speed goal is measured on the same 7 bones with ball joints, its own case;
CCD is shown on both. Run: ``.venv/bin/python benchmarks/ik.py``.

``--reach`` prints only the tables of targets at and near full reach (issue 18, item 4): per
method, reach fraction and joint model, how many of 40 seeded random chains converge within
the default iteration budget, and their median iterations (``--engine tree``: on the general
engine), first for the methods alone (``solve(..., reach_start=False)``, the state before
the reach-aware start), then as ``solve`` runs them. Ball chains have 2-6 random bone vectors
and a target in a random direction; hinge chains are planar (2-6 random bones in the xy
plane, every hinge about z) with the target in their plane, where it is reachable. Every
solve starts from the rest pose. ``two_link`` runs on the chains of two bones only (its count
is over those). ``r`` counts the solves that started from the reach-aware start
(``IKResult.start == "reach"``).
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

from course.ik import METHODS, fabrik_batch, solve
from course.rotations import quat_from_axis_angle
from course.skeleton import chain

AXES = np.array([[0, 1, 0], [0, 0, 1]] * 3 + [[0, 1, 0]], float)
HINGE = chain([1.0] * 7, axes=AXES)
BALL = chain([1.0] * 7)
IDENT = np.tile([1.0, 0, 0, 0], (8, 1))
TOL = 1e-4
N_TARGETS = 200
REPEATS = 3
BATCHES = (1, 10, 100)  # small batch sizes set beside single solves
# (method, joint model, goal as a speed-up over ikpy or None)
ROWS = [
    ("dls", "hinge", 25),
    ("pseudo_inverse", "hinge", 25),
    ("jacobian_transpose", "hinge", None),
    ("ccd", "hinge", None),
    ("fabrik", "hinge", None),
    ("ccd", "ball", None),
    ("fabrik", "ball", 80),
]
SKELETONS = {"hinge": HINGE, "ball": BALL}
# 0.9 is where the reach-aware start begins (course.ik._engine.reach.REACH_START: a target at
# exactly 0.9 takes it or not by rounding), 0.85 shows the methods on their own.
REACH_FRACTIONS = (1.0, 0.999, 0.99, 0.95, 0.9, 0.85)
N_CHAINS = 40


def targets(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q = np.tile(IDENT, (n, 1, 1))
    q[:, :7] = quat_from_axis_angle(AXES, rng.uniform(-1.5, 1.5, (n, 7)))
    return HINGE.forward_kinematics(q)[0][:, -1]


def ikpy_chain():
    from ikpy.chain import Chain
    from ikpy.link import OriginLink, URDFLink

    links = [OriginLink()]
    for i, axis in enumerate(AXES):
        links.append(URDFLink(name=f"j{i}", origin_translation=[0.0 if i == 0 else 1.0, 0, 0],
                              origin_orientation=[0, 0, 0], rotation=axis))
    links.append(URDFLink(name="end", origin_translation=[1.0, 0, 0],
                          origin_orientation=[0, 0, 0], joint_type="fixed"))
    return Chain(links, active_links_mask=[False] + [True] * 7 + [False])


def time_ikpy(ts: np.ndarray) -> tuple[np.ndarray, float]:
    c = ikpy_chain()
    times, ok = [], 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for t in ts:
            best = np.inf
            for _ in range(REPEATS):
                t0 = time.perf_counter()
                q = c.inverse_kinematics(t)
                best = min(best, time.perf_counter() - t0)
            times.append(best)
            ok += np.linalg.norm(c.forward_kinematics(q)[:3, 3] - t) < TOL
    return np.array(times), ok / len(ts)


def time_method(method: str, sk, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    solve(sk, IDENT, np.zeros(3), {"end_effector": ts[0]}, method=method)  # warm the cache
    times, its, ok = [], [], 0
    for t in ts:
        best = np.inf
        for _ in range(REPEATS):
            t0 = time.perf_counter()
            r = solve(sk, IDENT, np.zeros(3), {"end_effector": t}, method=method, tol=TOL)
            best = min(best, time.perf_counter() - t0)
        times.append(best)
        its.append(r.iterations)
        ok += r.converged
    return np.array(times), np.array(its), ok / len(ts)


def time_batch(method: str, sk, ts: np.ndarray) -> tuple[float, float]:
    """Best of ``REPEATS`` times of solving all ``ts`` one by one, and as one batch (timed
    alternately, so that both see the same load)."""
    best = [np.inf, np.inf]
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        for t in ts:
            solve(sk, IDENT, np.zeros(3), {"end_effector": t}, method=method, tol=TOL)
        t1 = time.perf_counter()
        solve(sk, IDENT, np.zeros(3), {"end_effector": ts}, method=method, tol=TOL)
        t2 = time.perf_counter()
        best = [min(best[0], t1 - t0), min(best[1], t2 - t1)]
    return best[0], best[1]


def reach_problems(joints: str, fraction: float, seed: int = 18):
    """``N_CHAINS`` seeded random chains (``joints`` "ball" or planar "hinge") and a target at
    ``fraction`` of each one's full reach: (skeleton, target) pairs."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(N_CHAINS):
        n = int(rng.integers(2, 7))
        if joints == "ball":
            bones = rng.normal(size=(n, 3))
            u = rng.normal(size=3)
            sk = chain(bones)
        else:  # planar: bones and target in the xy plane, every hinge about z
            bones = np.hstack([rng.normal(size=(n, 2)), np.zeros((n, 1))])
            u = np.r_[rng.normal(size=2), 0.0]
            sk = chain(bones, axes=[0, 0, 1])
        out.append((sk, fraction * sk.bone_lengths.sum() * u / np.linalg.norm(u)))
    return out


def reach_table(engine: str = "auto", reach_start: bool = True) -> None:
    """Converged count and median iterations at and near full reach (see the docstring)."""
    print(f"targets at a fraction of full reach, {N_CHAINS} seeded random chains each, rest "
          f"start, tol {TOL}, default budgets, engine {engine}, reach_start={reach_start}: "
          f"converged (median iterations) and how many started from the reach-aware start (r)")
    print(f"{'method':20s} {'joints':6s} " + " ".join(f"{f:>16g}" for f in REACH_FRACTIONS))
    for method in METHODS:
        for joints in ("ball", "hinge"):
            cells = []
            for fraction in REACH_FRACTIONS:
                ok, its, seeded = 0, [], 0
                for sk, t in reach_problems(joints, fraction):
                    if method == "two_link" and sk.n_joints != 3:
                        continue
                    r = solve(sk, np.tile([1.0, 0, 0, 0], (sk.n_joints, 1)), np.zeros(3),
                              {"end_effector": t}, method=method, tol=TOL, engine=engine,
                              reach_start=reach_start)
                    ok += bool(r.converged)
                    its.append(r.iterations)
                    seeded += r.start == "reach"
                cells.append(f"{ok:>2d}/{len(its):<2d} ({np.median(its):4.0f}) {seeded:2d}r")
            print(f"{method:20s} {joints:6s} " + " ".join(f"{c:>16s}" for c in cells))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reach", action="store_true",
                        help="only the table of targets at and near full reach")
    parser.add_argument("--engine", choices=("auto", "tree"), default="auto",
                        help="the engine of the reach table")
    args = parser.parse_args()
    if args.reach:
        for reach_start in (False, True):  # the methods alone (before), then the default
            reach_table(args.engine, reach_start)
            print()
        return
    ts = targets(N_TARGETS)
    ik_times, ik_ok = time_ikpy(ts)
    ikpy_ms = np.median(ik_times) * 1e3
    print(f"7-joint chain, {N_TARGETS} seeded reachable targets, zero start pose, tol {TOL}, "
          f"each solve's best of {REPEATS}")
    print(f"ikpy (hinge) {ikpy_ms:.2f} ms median, {np.percentile(ik_times, 90) * 1e3:.2f} ms "
          f"p90 per solve, success {ik_ok:.0%}\n")
    print(f"{'method':20s} {'joints':6s} {'median ms':>9s} {'p90 ms':>7s} {'iters':>6s} "
          f"{'success':>8s} {'x ikpy':>7s}  goal")
    for method, joints, goal in ROWS:
        tm, its, ok = time_method(method, SKELETONS[joints], ts)
        med = np.median(tm) * 1e3
        ratio = ikpy_ms / med
        verdict = "" if goal is None else f">= {goal}x: {'met' if ratio >= goal else 'MISSED'}"
        print(f"{method:20s} {joints:6s} {med:9.3f} {np.percentile(tm, 90)*1e3:7.3f} "
              f"{np.median(its):6.0f} {ok:8.0%} {ratio:7.1f}  {verdict}")

    # Small batches against the same solves one by one (goal: a ratio <= 1 everywhere).
    print(f"\nbatch of B vs the same B solves one by one, ms per solve: singles | batch "
          f"(batch / singles; goal <= 1), each the best of {REPEATS}")
    print(f"{'method':20s} {'joints':6s} " + " ".join(f"{f'B={B}':>24s}" for B in BATCHES))
    for method, joints, _ in ROWS:
        cells = []
        for B in BATCHES:
            one, batch = (t / B for t in time_batch(method, SKELETONS[joints], ts[:B]))
            cells.append(f"{one * 1e3:6.3f} | {batch * 1e3:6.3f} ({batch / one:4.2f}x)")
        print(f"{method:20s} {joints:6s} " + " ".join(f"{c:>24s}" for c in cells))

    B = 10_000
    big = targets(B, seed=1)
    p0 = BALL.rest_positions()
    t0 = time.perf_counter()
    _, its, err = fabrik_batch(p0, big, tol=TOL)
    dt = time.perf_counter() - t0
    print(f"\nbatched over {B} targets (goals: FABRIK >= 50000, DLS >= 30000 solves/s):")
    print(f"  fabrik_batch (positions)     {B/dt:10.0f} solves/s, success {(err < TOL).mean():.1%}")
    for method, sk, goal in (("fabrik", BALL, 50_000), ("dls", HINGE, 30_000)):
        t0 = time.perf_counter()
        r = solve(sk, IDENT, np.zeros(3), {"end_effector": big}, method=method, tol=TOL)
        dt = time.perf_counter() - t0
        print(f"  solve {method:6s} ({'ball' if sk is BALL else 'hinge'}) poses  "
              f"{B/dt:10.0f} solves/s, success {r.converged.mean():.1%}, median iterations "
              f"{np.median(r.iterations):.0f}: {'met' if B / dt >= goal else 'MISSED'}")

    # Parallel hinges (the lecture's 2D arm): every backward-pass turn is exact, plain FABRIK.
    arm = chain([1.0] * 7, axes=[0, 0, 1])
    q = np.tile(IDENT, (N_TARGETS, 1, 1))
    q[:, :7] = quat_from_axis_angle(np.array([0.0, 0, 1]),
                                    np.random.default_rng(3).uniform(-1.5, 1.5, (N_TARGETS, 7)))
    planar = arm.forward_kinematics(q)[0][:, -1]
    r = solve(arm, IDENT, np.zeros(3), {"end_effector": planar}, method="fabrik", tol=TOL)
    print(f"\nFABRIK with hinge constraints on a planar 7-hinge arm ({N_TARGETS} targets): "
          f"success {r.converged.mean():.0%}, median iterations {np.median(r.iterations):.0f}\n")
    reach_table(args.engine)


if __name__ == "__main__":
    main()
