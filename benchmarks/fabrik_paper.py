"""Aristidou & Lasenby (2011), FABRIK, Table 1 style comparison, with our solvers.

The paper: a single chain of 10 joints, random reachable targets, tolerance 0.01; FABRIK
needs the fewest iterations, CCD more, and the Jacobian methods (transpose, pseudo-inverse,
DLS) far more, with FABRIK also the fastest per solve. Here: 10 unit bones with ball joints
(the paper's chain is unconstrained), 100 targets drawn uniformly in the reachable ball (not
generated from poses, as in the paper), every solve from the straight rest pose, tol 0.01.
The closing note says, from the measured figures, where the table agrees with the paper's
finding and where not, and why. Run: ``.venv/bin/python benchmarks/fabrik_paper.py``.
"""

from __future__ import annotations

import time

import numpy as np

from course.ik import solve
from course.skeleton import chain

N_BONES = 10
TOL = 0.01


def main() -> None:
    sk = chain([1.0] * N_BONES)
    ident = np.tile([1.0, 0, 0, 0], (N_BONES + 1, 1))
    rng = np.random.default_rng(2011)
    d = rng.normal(size=(100, 3))
    ts = d / np.linalg.norm(d, axis=1, keepdims=True) * (
        N_BONES * rng.uniform(0.05, 0.95, (100, 1)) ** (1 / 3))
    print(f"{N_BONES}-bone ball chain, {len(ts)} random reachable targets, tolerance {TOL}\n")
    print(f"{'method':20s} {'mean iters':>10s} {'median iters':>12s} {'ms/solve':>9s} "
          f"{'ms/iter':>8s} {'success':>8s}")
    mean_its, median_its, ms = {}, {}, {}
    for method in ("fabrik", "ccd", "jacobian_transpose", "pseudo_inverse", "dls"):
        solve(sk, ident, np.zeros(3), {"end_effector": ts[0]}, method=method, tol=TOL)
        its, times, ok = [], [], 0
        for t in ts:
            t0 = time.perf_counter()
            r = solve(sk, ident, np.zeros(3), {"end_effector": t}, method=method, tol=TOL,
                      max_iter=5000)
            times.append(time.perf_counter() - t0)
            its.append(r.iterations)
            ok += r.converged
        its, times = np.array(its), np.array(times) * 1e3
        mean_its[method], median_its[method], ms[method] = (its.mean(), np.median(its),
                                                            np.median(times))
        print(f"{method:20s} {its.mean():10.1f} {np.median(its):12.0f} {np.median(times):9.3f} "
              f"{np.median(times / np.maximum(its, 1)):8.3f} {ok / len(ts):8.0%}")
    print(closing_note(mean_its, median_its, ms))


def closing_note(mean_its: dict[str, float], median_its: dict[str, float],
                 ms: dict[str, float]) -> str:
    """Where this run agrees with the paper's finding (FABRIK fewest iterations, CCD next, the
    Jacobian methods far more; FABRIK fastest), judged from the measured figures, and why not."""
    by_its = sorted(mean_its, key=mean_its.get)
    fastest = min(ms, key=ms.get)
    fewer = [m for m in ("jacobian_transpose", "pseudo_inverse", "dls")
             if mean_its[m] <= mean_its["fabrik"]]
    def verdict(ok: bool) -> str:
        return "agrees" if ok else "does not agree"
    lines = ["", "Against the paper:",
             f"  order by mean iterations: {', '.join(by_its)}",
             f"  FABRIK fewer iterations than CCD: {verdict(mean_its['fabrik'] < mean_its['ccd'])}",
             f"  Jacobian transpose far more (3x) than FABRIK: "
             f"{verdict(mean_its['jacobian_transpose'] > 3 * mean_its['fabrik'])}",
             f"  FABRIK fastest per solve: {verdict(fastest == 'fabrik')} (fastest: {fastest})"]
    if fewer:
        lines.append(
            f"  {' and '.join(fewer)}: no more iterations than FABRIK, unlike the paper. Ours "
            "take the full least-squares (Gauss-Newton) step, capped at max_step and "
            "backtracked, which lands in a few steps once near the target, where the paper's "
            "Jacobian baselines crawl; an iteration of theirs costs more (a Jacobian and a "
            "3x3 solve against FABRIK's point moves), which is why FABRIK can still be the "
            "fastest per solve.")
    if mean_its["ccd"] > 1.5 * median_its["ccd"]:
        lines.append("  CCD's mean is well above its median: it crawls on some targets (near "
                     "the root or near full stretch, where each joint's turn is tiny).")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
