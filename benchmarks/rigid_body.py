"""Rigid-body integrators, measured: the numbers docs/physics.md and tests/test_rigid_body.py
quote, and the cost of a step.

Run:  .venv/bin/python benchmarks/rigid_body.py

- energy drift of a free tumbling box (1 kg, half-extents 0.2 × 0.1 × 0.15 m, ω = (1, 2, 3)
  rad/s) over 1 s, for each integrator, orientation update and h, and the ratio per halving;
- the precession rate of a symmetric top against Ω = (I₃ − I₁)/I₁ ω₃;
- the Dzhanibekov flip time of ``t_handle()`` spun at 10 rad/s about its intermediate axis
  (perturbation 1e-3), against Euler's equations solved by scipy to 1e-11;
- the rest height of a dropped box against ``b − m g / (4 k)``;
- the stability limit of the contact spring, by bisection on h: a box resting flat on 4
  corners, nudged 0.1 µm up (the vertical mode, ω = √(4k/m)) or tilted 1 µrad about z (its
  stiffest rocking mode, ω = √(4 k a² / I_z)), counts as unstable over 2000 steps when it
  strays 1000 times the nudge, or when its largest deviation in the last 500 steps is twice
  that in steps 500-1000 (a slow growth). Symplectic Euler without damping should fail at
  h ω = 2, explicit Euler with damping d per corner at h = d/k;
- microseconds per step (process CPU time: the machine is shared).
"""

from __future__ import annotations

import time

import numpy as np
from scipy.integrate import solve_ivp

from course.physics import (
    INTEGRATORS,
    ROTATION_UPDATES,
    Ground,
    RigidBody,
    box,
    simulate_rigid,
    t_handle,
)
from course.rotations import matrix_from_quat, quat_from_rotvec

ZERO_G = (0.0, 0.0, 0.0)
M, HALF, K = 1.0, np.array([0.1, 0.05, 0.075]), 1e4
REST = HALF[1] - M * 9.81 / (4 * K)


def energy_drift() -> None:
    body = box(1.0, [0.2, 0.1, 0.15])
    s = body.state(omega=[1.0, 2.0, 3.0], q=quat_from_rotvec([0.3, -0.5, 0.7]))
    steps = (1e-2, 5e-3, 2.5e-3)
    print("free-body energy drift over 1 s, (E(1 s) - E(0)) / E(0):")
    print(f"{'':24}" + "".join(f"{f'h = {1e3 * h:g} ms':>14}" for h in steps) + "   ratios")
    for method in INTEGRATORS:
        for rotation in ROTATION_UPDATES:
            drift = []
            for h in steps:
                E = simulate_rigid(body, s, h, round(1 / h), method=method, rotation=rotation,
                                   gravity=ZERO_G).energy.total
                drift.append((E[-1] - E[0]) / E[0])
            ratios = " ".join(f"{a / b:.3f}" for a, b in zip(drift[:-1], drift[1:], strict=True))
            print(f"  {method:>10} {rotation:>10}" + "".join(f"{d:14.4e}" for d in drift)
                  + f"   {ratios}")


def precession() -> None:
    I1, I3, w3 = 1.0, 1.6, 5.0
    top = RigidBody(mass=1.0, inertia=np.diag([I1, I1, I3]))
    for h in (2e-3, 1e-3):
        run = simulate_rigid(top, top.state(omega=[1.0, 0.0, w3]), h, round(1 / h),
                             gravity=ZERO_G)
        w = run.omega_body
        rate = np.polyfit(run.t, np.unwrap(np.arctan2(w[:, 1], w[:, 0])), 1)[0]
        print(f"symmetric top, h = {1e3 * h:g} ms: precession {rate:.5f} rad/s, closed form "
              f"{(I3 - I1) / I1 * w3:.5f} (relative error {rate / ((I3 - I1) / I1 * w3) - 1:.1e})")


def flip() -> None:
    body = t_handle()
    moments = np.diag(body.inertia)
    w0, eps = 10.0, 1e-3
    spin = w0 * np.array([1.0, eps, eps])
    ref = solve_ivp(lambda t, w: np.cross(moments * w, w) / moments, (0, 3), spin, rtol=1e-11,
                    atol=1e-12, events=lambda t, w: w[0]).t_events[0][0]
    Ix, Iy, Iz = moments
    rate = w0 * np.sqrt((Ix - Iy) * (Iz - Ix) / (Iy * Iz))
    print(f"T-handle moments {moments} kg m²; growth rate λ = {rate:.3f}/s, "
          f"ln(1/ε)/λ = {np.log(1 / eps) / rate:.3f} s, Euler's equations: flip at {ref:.4f} s")
    for h in (4e-3, 2e-3, 1e-3):
        run = simulate_rigid(body, body.state(omega=spin), h, round(2 / h), gravity=ZERO_G)
        t = run.t[np.flatnonzero(run.omega_body[:, 0] < 0)[0]]
        print(f"  h = {1e3 * h:g} ms: flips at {t:.3f} s")


def rest() -> None:
    body = box(M, HALF)
    s = body.state(x=[0, 0.3, 0], v=[0.5, 0, 0], q=quat_from_rotvec([0.3, 0.2, -0.4]),
                   omega=[1.0, 2.0, -1.0])
    run = simulate_rigid(body, s, 1e-3, 2500, ground=Ground(k=K, d=40.0, friction=5.0))
    up = np.argmax(np.abs(matrix_from_quat(run.q[-1])[1]))
    print(f"dropped box at rest after 2.5 s: height {run.x[-1, 1]:.9f} m, closed form "
          f"b - m g/(4k) = {HALF[up] - M * 9.81 / (4 * K):.9f} m; |v| "
          f"{np.abs(run.v[-1]).max():.1e}, |ω| {np.abs(run.omega[-1]).max():.1e}")


def unstable(h: float, method: str, d: float, tilt: bool) -> bool:
    body = box(M, HALF)
    nudge = 1e-7
    s = body.state(x=[0, REST + (0 if tilt else nudge), 0],
                   q=quat_from_rotvec([0, 0, 1e-6 if tilt else 0.0]))
    run = simulate_rigid(body, s, h, 2000, method=method, ground=Ground(k=K, d=d))
    corner = np.abs(run.x[:, 1] - REST + HALF[0] * np.abs(matrix_from_quat(run.q)[:, 1, 0]))
    return bool(run.exploded_at is not None or corner.max() > 1e3 * nudge
                or corner[1500:].max() > 2 * corner[500:1000].max())


def boundary(method: str, d: float, tilt: bool, lo: float, hi: float) -> float:
    for _ in range(14):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if unstable(mid, method, d, tilt) else (mid, hi)
    return 0.5 * (lo + hi)


def stability() -> None:
    vertical = np.sqrt(4 * K / M)
    I_z = box(M, HALF).inertia[2, 2]
    rocking = np.sqrt(4 * K * HALF[0] ** 2 / I_z)
    h = boundary("symplectic", 0.0, False, 0.5 / vertical, 4 / vertical)
    print(f"symplectic Euler, d = 0, vertical mode ω = {vertical:.1f}/s: unstable above "
          f"h = {1e3 * h:.4f} ms, h ω = {h * vertical:.4f}")
    h = boundary("symplectic", 0.0, True, 0.5 / rocking, 4 / rocking)
    print(f"symplectic Euler, d = 0, rocking mode ω = {rocking:.1f}/s: unstable above "
          f"h = {1e3 * h:.4f} ms, h ω = {h * rocking:.4f}")
    d = 20.0
    h = boundary("explicit", d, False, 0.1 * d / K, 4 * d / K)
    print(f"explicit Euler, d = {d:g} N s/m: unstable above h = {1e3 * h:.4f} ms, "
          f"h / (d/k) = {h / (d / K):.4f}")


def speed() -> None:
    body = box(M, HALF)
    s = body.state(x=[0, 0.3, 0], q=quat_from_rotvec([0.3, 0.2, -0.4]), omega=[1.0, 2.0, -1.0])
    for rotation in ROTATION_UPDATES:
        t = time.process_time()
        simulate_rigid(body, s, 1e-3, 2000, rotation=rotation, ground=Ground(k=K, d=40.0))
        print(f"  {rotation:>10}: {(time.process_time() - t) / 2000 * 1e6:.0f} µs per step "
              f"(one box, 8 contact points)")


def main() -> None:
    energy_drift()
    precession()
    flip()
    rest()
    stability()
    speed()


if __name__ == "__main__":
    main()
