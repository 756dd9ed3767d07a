"""course.control measured: policy-gradient training time and % of LQR's cost, the REINFORCE
estimator's bias (in standard errors) and the variance each baseline saves, value iteration
against LQR as the grid is refined, the iLQR swing-up, and the Riccati iteration against
scipy's DARE solver, and the LQR balance of the CMU character, on two feet against notebook
14's controllers on the same pushes and on one leg — the figures docs/control.md quotes.

Run:  .venv/bin/python benchmarks/control.py [--seeds 3] [--skip-vi] [--skip-character]

The character's pushes follow benchmarks/physics_balance.py (0.1 s on the root from 0.25 s,
standing 1.5 s after it, bisection to 5 N, torque limit 400 N m, h = 1/600 s; a diverged run
counts as a fall); the CMU clip comes from $COURSE_DATA_DIR or ../shared/data/bvh.

On one core: BLAS is held to one thread (set before numpy loads) and nothing here runs in
parallel. Wall times are ``time.perf_counter`` around each call, on whatever else the
machine is doing; the costs, gains and z-scores are deterministic for the seeds printed.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from course.control import (  # noqa: E402
    LinearGaussianPolicy,
    LQTask,
    Pendulum,
    PendulumGrid,
    ValueBaseline,
    double_integrator,
    linear_inverted_pendulum,
    lqr_infinite_horizon,
    pendulum_swing_up,
    reinforce_gradient,
    sample_rollouts,
    train_reinforce,
    value_iteration,
)


def training(seeds: int) -> tuple[float, float]:
    """Each case and seed trained and printed; the first case's seed 0 as (% of LQR's cost
    at the end, wall seconds), the figures of the summary line."""
    di = double_integrator(dt=0.1)
    lipm = linear_inverted_pendulum(dt=0.05, com_height=0.9)
    cases = [
        ("double integrator, T = 50, sigma 0.5, 100 episodes/iter, lr 0.1",
         LQTask.make(di.A, di.B, 0.1 * np.eye(2), [[0.1]], 50),
         {"sigma": 0.5, "batch_size": 100, "learning_rate": 0.1, "iterations": 300}),
        ("LIPM (lecture 11), T = 40, sigma 0.1 m, 200 episodes/iter, lr 0.1",
         LQTask.make(lipm.A, lipm.B, np.diag([1.0, 0.1]), [[1.0]], 40,
                     initial_cov=0.01 * np.eye(2)),
         {"sigma": 0.1, "batch_size": 200, "learning_rate": 0.1, "iterations": 500}),
    ]
    print("== REINFORCE (value baseline, Adam) from K = 0; cost of the learned u = -Kx")
    summary: tuple[float, float] | None = None
    for label, task, kwargs in cases:
        print(f"  {label}")
        print(f"    LQR gain {np.array2string(task.lqr_gain()[0], precision=3)}, "
              f"J(0) / J_LQR = {task.cost(np.zeros((1, 2))) / task.lqr_cost():.3g}")
        for seed in range(seeds):
            start = time.perf_counter()
            result = train_reinforce(task, seed=seed, **kwargs)  # type: ignore[arg-type]
            seconds = time.perf_counter() - start
            ratio = result.cost_history / result.lqr_cost
            within = int(np.argmax(ratio < 1.1)) if np.any(ratio < 1.1) else -1
            per_iteration = seconds / kwargs["iterations"]
            reached = (f"within 10% at iteration {within} ({within * per_iteration:.2f} s)"
                       if within >= 0 else "never within 10%")
            if summary is None:
                summary = (100 * float(ratio[-1]), seconds)
            print(f"    seed {seed}: {seconds:5.2f} s for {kwargs['iterations']} iterations, "
                  f"{reached}, final {100 * ratio[-1]:.2f}% of LQR's cost, "
                  f"K = {np.array2string(result.K[0], precision=3)}")
    assert summary is not None
    return summary


def estimator(batches: int) -> None:
    di = double_integrator(dt=0.1)
    task = LQTask.make(di.A, di.B, 0.1 * np.eye(2), [[0.1]], 20, discount=0.9)
    policy = LinearGaussianPolicy(0.5 * task.lqr_gain(), 0.5)
    exact = task.gradient(policy.K, 0.5)[0]
    rng = np.random.default_rng(20)
    value = ValueBaseline.fit(sample_rollouts(task, policy, 2000, rng), task.discount)
    found: dict[str, list[np.ndarray]] = {"none": [], "mean": [], "value": []}
    start = time.perf_counter()
    for _ in range(batches):
        batch = sample_rollouts(task, policy, 500, rng)
        for name in ("none", "mean"):
            found[name].append(reinforce_gradient(batch, policy, discount=0.9,
                                                  baseline=name)[0])  # type: ignore[arg-type]
        found["value"].append(reinforce_gradient(batch, policy, discount=0.9,
                                                 baseline=value)[0])
    seconds = time.perf_counter() - start
    print(f"\n== REINFORCE estimator, double integrator T = 20, gamma 0.9, K = K_LQR / 2, "
          f"sigma 0.5: {batches} batches x 500 episodes ({seconds:.1f} s)")
    print(f"  exact gradient {np.array2string(exact, precision=4)}")
    none_var = np.array(found["none"]).var(0, ddof=1)
    for name, samples in found.items():
        s = np.array(samples)
        z = (s.mean(0) - exact) / (s.std(0, ddof=1) / np.sqrt(batches))
        ratio = none_var / s.var(0, ddof=1)
        print(f"  baseline {name:5s}: mean {np.array2string(s.mean(0), precision=4)}, bias "
              f"{np.array2string(z, precision=2)} standard errors, variance "
              f"{np.array2string(ratio, precision=1)}x lower than without")


def dynamic_programming() -> None:
    pendulum = Pendulum(dt=0.05)
    print("\n== value iteration, pendulum dt = 0.05 s, gamma 0.98, 21 torques in +-5 N m, "
          "|omega| <= 8 rad/s; gain fitted near the top vs LQR (discounted)")
    rng = np.random.default_rng(0)
    x = rng.uniform([-0.1, -0.3], [0.1, 0.3], (400, 2))
    for n in (61, 81, 101, 151):
        grid = PendulumGrid(n_theta=n, n_omega=n)
        start = time.perf_counter()
        result = value_iteration(pendulum, grid, discount=0.98, tol=1e-4)
        seconds = time.perf_counter() - start
        linear = pendulum.linearize_upright()
        K = lqr_infinite_horizon(linear.A, linear.B, result.Q, result.R, discount=0.98).K[0]
        u = result.greedy_torque(x, np.linspace(-5, 5, 2001))
        fitted, *_ = np.linalg.lstsq(x, -u, rcond=None)
        error = 100 * np.abs(fitted - K) / np.abs(K)
        print(f"  {n:3d} x {n:3d}: {seconds:5.2f} s, {result.iterations} sweeps, K_fit "
              f"{np.array2string(fitted, precision=2)} vs LQR "
              f"{np.array2string(K, precision=2)}: {error[0]:.1f}% / {error[1]:.1f}% off")


def ilqr() -> None:
    times = []
    result = None
    for _ in range(3):
        start = time.perf_counter()
        result = pendulum_swing_up()
        times.append(time.perf_counter() - start)
    assert result is not None
    print(f"\n== iLQR swing-up (1 kg, 1 m, dt 0.02 s, 4 s): {statistics.median(times):.2f} s, "
          f"{result.iterations} iterations, cost {result.cost_history[0]:.1f} -> "
          f"{result.cost:.2f}, final state {np.array2string(result.x[-1], precision=4)}, "
          f"max |u| {np.max(np.abs(result.u)):.2f} N m ({result.reason})")


def riccati(problems: int) -> None:
    import scipy.linalg

    rng = np.random.default_rng(5)
    worst, iterations, seconds = 0.0, [], 0.0
    for _ in range(problems):
        n, m = int(rng.integers(1, 7)), int(rng.integers(1, 3))
        A = rng.standard_normal((n, n))
        A *= 1.2 / max(np.max(np.abs(np.linalg.eigvals(A))), 1e-9)
        B = rng.standard_normal((n, m))
        Q, R = np.eye(n), np.eye(m)
        start = time.perf_counter()
        result = lqr_infinite_horizon(A, B, Q, R)
        seconds += time.perf_counter() - start
        P = scipy.linalg.solve_discrete_are(A, B, Q, R)
        worst = max(worst, float(np.max(np.abs(result.P - P)) / np.max(np.abs(P))))
        iterations.append(result.iterations)
    print(f"\n== Riccati iteration vs scipy.linalg.solve_discrete_are, {problems} random "
          f"systems (n <= 6, spectral radius 1.2): worst relative difference of P "
          f"{worst:.1e}; iterations median {statistics.median(iterations):.0f}, max "
          f"{max(iterations)}; {1e3 * seconds / problems:.1f} ms each")
    slow = double_integrator(dt=0.001)
    for method in ("iteration", "doubling"):
        start = time.perf_counter()
        result = lqr_infinite_horizon(slow.A, slow.B, np.eye(2), [[1.0]], tol=1e-10,
                                      method=method)  # type: ignore[arg-type]
        seconds = time.perf_counter() - start
        print(f"  double integrator dt = 1 ms, {method:9s}: {result.iterations:6d} steps, "
              f"{1e3 * seconds:7.1f} ms ({result.reason})")


DIRECTIONS = {"forward": (0.0, 0.0, 1.0), "backward": (0.0, 0.0, -1.0),
              "sideways": (1.0, 0.0, 0.0)}
#: One leg is not symmetric sideways: on the left foot (+x) a +x push moves the COM out over
#: the stance foot's edge, a -x push towards the lifted foot.
ONE_LEG_DIRECTIONS = {**DIRECTIONS, "sideways -x": (-1.0, 0.0, 0.0)}


def character_lqr() -> tuple[float, float, float] | None:
    """The LQR balance of the CMU character (course.physics.lqr_balance) on two feet beside
    ``none``, ``ankle`` and ``com`` on the same pushes, and on one leg (the left); the worst
    direction's impulse (N s) of the two-foot LQR, of ``com`` and of the one-leg LQR, or None
    without the clip."""
    from pathlib import Path

    import mujoco  # type: ignore[import-untyped]

    from course.bvh import load_bvh
    from course.physics.balance import CONTROLLERS, largest_push, standing_pose
    from course.physics.character import build_model
    from course.physics.lqr_balance import design, lqr_largest_push, lqr_stand, survived

    env = os.environ.get("COURSE_DATA_DIR")
    base = Path(env) if env else Path(__file__).resolve().parents[2] / "shared" / "data" / "bvh"
    path = base / "cmu_12_01_walk.bvh"
    if not path.exists():
        print(f"\n== LQR balance of the character: CMU clip not found at {path}, skipped")
        return None
    mujoco.set_mju_user_warning(lambda message: None)  # diverged runs are counted, not logged
    character = build_model(load_bvh(path).skeleton)
    designs = {}
    for label, stance in (("two feet", None), ("one leg (left)", 0)):
        start = time.perf_counter()
        lqr = designs[label] = design(character, stance=stance)
        seconds = time.perf_counter() - start
        eq = lqr.equilibrium
        print(f"\n== LQR balance, CMU character on {label} ({character.total_mass:.1f} kg, "
              f"nv = {character.model.nv}, {lqr.B.shape[1]} torques): design {seconds:.1f} s")
        print(f"  tutorial height search: {1e3 * eq.tutorial_height:.3f} mm leaves root "
              f"{np.array2string(eq.tutorial_root_force, precision=3)} (N, N m)")
        print(f"  with the tilt: {1e3 * eq.height:.3f} mm, tilt "
              f"{np.array2string(1e3 * eq.tilt, precision=3)} mrad, root residual "
              f"{np.abs(eq.root_force).max():.1e}; spectral radius of A - BK "
              f"{lqr.spectral_radius:.10f}, max |K| {np.abs(lqr.K).max():.1f}")
        run = lqr_stand(character, lqr, duration=3.0)
        print(f"  unpushed 3 s: standing {survived(run)}, COM moved "
              f"{1e3 * np.linalg.norm(run.com[-1] - run.com[0]):.3f} mm, max |root force| "
              f"{np.abs(run.torques[:, :6]).max()}, {run.sim_time / run.wall_time:.1f} s/s")
    pose = standing_pose(character)
    print("\n  largest push (N, 0.1 s; impulse N s in brackets):")
    names = (*CONTROLLERS, "lqr", "lqr one leg")
    print(f"  {'direction':12s}" + "".join(f"{c:>18s}" for c in names))
    found: dict[str, dict[str, float]] = {}
    for label, d in ONE_LEG_DIRECTIONS.items():
        forces = {"lqr one leg": lqr_largest_push(character, designs["one leg (left)"],
                                                  direction=d)}
        if label in DIRECTIONS:
            forces |= {c: largest_push(character, pose, controller=c, direction=d)
                       for c in CONTROLLERS}
            forces["lqr"] = lqr_largest_push(character, designs["two feet"], direction=d)
        found[label] = forces
        print(f"  {label:12s}" + "".join(f"{forces[c]:9.1f} ({0.1 * forces[c]:5.2f})"
                                        if c in forces else f"{'':>18s}" for c in names))
    worst = {}
    for c in ("lqr", "com", "lqr one leg"):
        direction = min((label for label in found if c in found[label]),
                        key=lambda label, c=c: found[label][c])
        worst[c] = 0.1 * found[direction][c]
        print(f"  worst direction of {c}: {direction}, {worst[c]:.2f} N s")
    return worst["lqr"], worst["com"], worst["lqr one leg"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--batches", type=int, default=400)
    parser.add_argument("--skip-vi", action="store_true")
    parser.add_argument("--skip-character", action="store_true")
    args = parser.parse_args()
    percent, seconds = training(args.seeds)
    estimator(args.batches)
    if not args.skip_vi:
        dynamic_programming()
    ilqr()
    riccati(100)
    pushes = None if args.skip_character else character_lqr()
    standing = ("LQR standing: not measured" if pushes is None else
                f"LQR standing survives {pushes[0]:.2f} N s (com controller {pushes[1]:.2f} N s), "
                f"one-leg {pushes[2]:.2f} N s")
    print("\n(summary: each push its worst direction; policy gradient on the double integrator, "
          "seed 0)")
    print(f"control: {standing}; policy gradient reaches {percent:.1f}% of LQR cost in "
          f"{seconds:.2f} s on 1 core")

if __name__ == "__main__":
    main()
