"""Mass–spring cloth speed: implicit Euler (Newton) steps per second, explicit Euler beside it.

Run:  .venv/bin/python benchmarks/mass_spring.py [--sizes 10 30 50] [--steps 10] [--h 0.0167]

For each n×n grid cloth (pinned at two corners, starting flat, ``course.physics.grid_cloth``
defaults: 1 kg, k = 1000 N/m) the simulation first runs ``--steps`` implicit steps (the cloth
falls and swings), then from that state times

- implicit: ``course.physics.step(..., "implicit")`` at ``h`` (1/60 s: one step per frame),
  with the default solver (Newton + Jacobi-preconditioned CG; its mean Newton iterations
  per step are printed beside it) and with the sparse LU solver (on the first 3 states);
- explicit: one explicit Euler step (the baseline: one force evaluation, no solve), and
  ``h_max = 2 / ω_max`` (``ω_max²`` the largest eigenvalue of ``M⁻¹K`` at rest), the
  stability limit of the explicit family (symplectic Euler is stable below it; explicit
  Euler gains energy even there), hence how many explicit steps one 1/60 s frame needs.

Timings are the mean over ``--steps`` steps (a step's cost depends on the state, so the same
states are timed for every method), measured as the process's CPU time
(``time.process_time``: on a shared, oversubscribed machine the wall clock mostly measures
the other jobs; the CG solver's wall-clock time is printed beside it); the growth of cost
with the particle count N is printed as the exponent ``p`` in ``cost ∝ N^p`` between sizes.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from course.physics import grid_cloth, step


def omega_max(cloth) -> float:
    """The cloth's highest angular frequency at rest: √ of the largest eigenvalue of M⁻¹K."""
    from scipy.sparse import diags
    from scipy.sparse.linalg import eigsh

    s = cloth.system
    free = np.repeat(s.free, 3)
    K = s.spring_hessian(cloth.positions)[free][:, free]
    scale = diags(1 / np.sqrt(np.repeat(s.masses[s.free], 3)))
    return float(np.sqrt(eigsh(scale @ K @ scale, k=1, which="LA",
                               return_eigenvectors=False)[0]))


def timed(system, states, h: float, method: str = "implicit", **options
          ) -> tuple[float, float, list]:
    """Mean wall-clock and CPU seconds per step over ``states``, and the steps' results."""
    t, cpu = time.perf_counter(), time.process_time()
    out = [step(system, x, v, h, method, **options) for x, v in states]
    n = len(states)
    return (time.perf_counter() - t) / n, (time.process_time() - cpu) / n, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 30, 50])
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--h", type=float, default=1 / 60)
    args = parser.parse_args()
    h = args.h
    print(f"implicit Euler at h = {h:.4f} s vs explicit Euler; mean over {args.steps} steps;"
          "\ntimes are CPU time per step (wall clock for CG beside it)\n")
    print(f"{'cloth':>7} {'N':>5} {'springs':>7} | {'implicit CG':>11} {'(wall)':>9} {'Newton':>6} "
          f"{'steps/s':>7} | {'implicit LU':>11} | {'explicit':>9} {'h_max':>8} "
          f"{'steps/frame':>11} | {'CG / explicit':>13}")
    rows = []
    for n in args.sizes:
        cloth = grid_cloth(n, n)
        s = cloth.system
        x, v = cloth.positions, np.zeros_like(cloth.positions)
        for _ in range(args.steps):  # let it fall first: a moving cloth, not the flat start
            x, v, _ = step(s, x, v, h)
        states = []
        for _ in range(args.steps):
            states.append((x, v))
            x, v, _ = step(s, x, v, h)
        wall_cg, t_cg, results = timed(s, states, h)
        # SuperLU is the slow one: a few states are enough to see its growth
        _, t_lu, _ = timed(s, states[:3], h, solver="direct")
        _, t_ex, _ = timed(s, states * 10, h, "explicit")
        newton = np.mean([r.stats.iterations for r in results])
        h_max = 2 / omega_max(cloth)
        per_frame = int(np.ceil((1 / 60) / h_max))
        rows.append((s.n_particles, t_cg, t_lu, t_ex))
        print(f"{n:>3}x{n:<3} {s.n_particles:>5} {len(s.springs):>7} | "
              f"{1e3 * t_cg:>8.1f} ms {1e3 * wall_cg:>6.0f} ms {newton:>6.1f} {1 / t_cg:>7.1f} | "
              f"{1e3 * t_lu:>8.1f} ms | "
              f"{1e6 * t_ex:>6.0f} µs {1e3 * h_max:>5.2f} ms {per_frame:>11d} | "
              f"{t_cg / t_ex:>12.0f}x")
    print("\ncost growth between sizes (CPU time), cost ∝ N^p:")
    for (n0, *t0), (n1, *t1) in zip(rows, rows[1:], strict=False):
        p = [np.log(b / a) / np.log(n1 / n0) for a, b in zip(t0, t1, strict=True)]
        print(f"  N {n0:>5} -> {n1:>5} (x{n1 / n0:.0f}): implicit CG p = {p[0]:.2f}, "
              f"implicit LU p = {p[1]:.2f}, explicit p = {p[2]:.2f}")
    print("\nOne frame of 1/60 s: implicit takes one step; explicit needs 'steps/frame' steps,"
          "\nso per frame the ratio is (CG / explicit) / (steps/frame).")


if __name__ == "__main__":
    main()
