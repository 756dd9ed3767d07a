r"""Assignment a6, physics: the spec ``assignments/a6_physics.py`` is checked by.

* ``rigid_body_step`` is one semi-implicit (symplectic) Euler step in angular-momentum form,
  compared with :func:`course.physics.rigid_body.step_rigid` (``method="symplectic"``,
  ``rotation="quaternion"``, no gravity, the force and torque applied): :math:`v^+ = v + hf/m`,
  :math:`x^+ = x + hv^+`, :math:`L^+ = L + h\tau`, :math:`\omega = R I_0^{-1} R^T L^+` with
  :math:`R` the orientation at the start, :math:`q^+ = \mathrm{unit}(q + \frac h2 [0, \omega]
  \otimes q)`; :math:`-q^+` is the same answer.
* ``pd_torque`` is a ball joint's PD torque :math:`\tau = k_p\,r - k_d\,\omega` clipped per
  component to :math:`\pm` ``limit``, :math:`r` the rotation vector of the shortest turn
  :math:`q^{-1}\bar q` (in the joint's own frame, where :math:`\omega` is given).
* ``balance_torque`` is the Jacobian-transpose balance torque :math:`\tau = J_c^T f`,
  :math:`f = k_p(\bar c - c) - k_d\dot c`, of a planar chain standing on a fixed foot, with
  :math:`J_c = \sum_i m_i J_{c_i}/M` the Jacobian of the whole body's centre of mass (no gravity
  compensation).

The mistakes students make each give one definite wrong answer, so the catalogue writes them
as functions of the arguments.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from course import rotations as rot
from course.physics.rigid_body import RigidBody, RigidState, step_rigid, t_handle

from ..checks import Check, QuatCheck, TupleCheck, show
from ..spec import (
    Assignment,
    Case,
    Function,
    Misconception,
    Rollout,
    Run,
    Test,
    random_edge_hidden,
)

# --- the rigid-body step -----------------------------------------------------------------------


def step_reference(x: np.ndarray, v: np.ndarray, q: np.ndarray, L: np.ndarray, mass: float,
                   inertia_body: np.ndarray, force: np.ndarray, torque: np.ndarray, h: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The library's symplectic step with the quaternion update, the force and torque given."""
    body = RigidBody(mass=mass, inertia=inertia_body)
    s = step_rigid(body, RigidState.create(x=x, v=v, q=q, L=L), h, method="symplectic",
                   rotation="quaternion", gravity=np.zeros(3),
                   applied=lambda _: (force, torque))
    return s.x, s.v, s.q, s.L


def step_formula(x: np.ndarray, v: np.ndarray, q: np.ndarray, L: np.ndarray, mass: float,
                 inertia_body: np.ndarray, force: np.ndarray, torque: np.ndarray, h: float, *,
                 omega: str = "world", renormalise: bool = True, explicit: bool = False
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    r"""The step written out, and as students get it wrong: ``omega="body"`` takes
    :math:`\omega = I_0^{-1}L^+` (the body-frame inertia, not rotated), ``"transposed"``
    :math:`R^T I_0^{-1} R L^+` (rotated the wrong way); ``renormalise=False`` leaves
    :math:`q^+` off the unit sphere; ``explicit`` moves :math:`x` with the old :math:`v`."""
    v_new = v + h * np.asarray(force) / mass
    x_new = x + h * (v if explicit else v_new)
    L_new = L + h * np.asarray(torque)
    R = rot.matrix_from_quat(q)
    inv = np.linalg.inv(inertia_body)
    w = {"world": R @ inv @ R.T, "body": inv, "transposed": R.T @ inv @ R}[omega] @ L_new
    q_new = q + 0.5 * h * rot.quat_mul(np.r_[0.0, w], q)
    if renormalise:
        q_new = q_new / np.linalg.norm(q_new)
    return x_new, v_new, q_new, L_new


def _variant(**how: Any) -> Any:
    return lambda *args: step_formula(*args, **how)


StepArgs = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, np.ndarray,
                 np.ndarray, np.ndarray, float]


def _random_quat(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=4)
    unit: np.ndarray = q / np.linalg.norm(q)
    return unit


def _inertia(rng: np.random.Generator, diagonal: bool = True) -> np.ndarray:
    """A body-frame inertia: principal moments that satisfy the triangle inequality, on the
    axes or turned by a random rotation (a body frame off its principal axes)."""
    a, b = rng.uniform(0.2, 1.0, 2)
    moments = np.array([a, b, rng.uniform(abs(a - b) + 0.05, a + b - 0.02)])
    I0 = np.diag(moments)
    if not diagonal:
        R = rot.matrix_from_quat(_random_quat(rng))
        I0 = R @ I0 @ R.T
    return I0


def _step_args(rng: np.random.Generator, h: float = 0.01, *, q: np.ndarray | None = None,
               torque: bool = True, diagonal: bool = True, spin: float = 3.0) -> StepArgs:
    I0 = _inertia(rng, diagonal)
    return (rng.normal(0, 1, 3), rng.normal(0, 1, 3),
            _random_quat(rng) if q is None else q, rng.normal(0, spin, 3) * np.diag(I0),
            float(rng.uniform(0.5, 5.0)), I0, rng.normal(0, 3, 3),
            rng.normal(0, 1, 3) if torque else np.zeros(3), h)


def step_random(rng: np.random.Generator) -> list[Case]:
    return [Case(f"a spinning body, h = {h:g}", _step_args(rng, h))
            for h in (0.01, 1 / 60, 1 / 100, 0.02, 0.005)]


def step_edges(rng: np.random.Generator) -> list[Case]:
    handle = t_handle()
    q = _random_quat(rng)
    omega = np.array([20.0, 0.1, 0.05])  # about the bar: the intermediate axis
    L_handle = rot.matrix_from_quat(q) @ handle.inertia @ omega
    return [
        Case("no torque (L must stay what it is)", _step_args(rng, torque=False)),
        Case("at the identity orientation (R = I)",
             _step_args(rng, q=np.array([1.0, 0.0, 0.0, 0.0]))),
        Case("a body frame off its principal axes (I₀ not diagonal)",
             _step_args(rng, diagonal=False)),
        Case("a fast spin with a big step (h = 0.05)", _step_args(rng, 0.05, spin=10.0)),
        Case("a T-handle spinning about its bar (the intermediate axis)",
             (np.zeros(3), np.zeros(3), q, L_handle, handle.mass, handle.inertia, np.zeros(3),
              np.zeros(3), 1e-3)),
    ]


def step_hidden(rng: np.random.Generator) -> list[Case]:
    return [Case(f"hidden rigid body #{i + 1}",
                 _step_args(rng, float(rng.choice([0.005, 0.01, 1 / 60, 0.03])),
                            diagonal=bool(rng.random() < 0.5)))
            for i in range(8)]


def _explicit(got: Any, *args: Any) -> bool:
    """x⁺ = x + h v (the old velocity), whatever the rest."""
    x, v, *_, h = args
    return bool(np.allclose(got[0], x + h * v, atol=1e-9)
                and not np.allclose(got[0], step_reference(*args)[0], atol=1e-6))


# --- the rigid-body step, run for seconds ------------------------------------------------------

STEP_RUN = 300  # steps of each simulated body (1.5 s at h = 0.005: a T-handle flips thrice)
#: what a rollout test that ran out of its time says after its figures (measured with
#: benchmarks/rollout_pace.py: a correct step costs 0.6-1.4 ms through the sandbox on an idle
#: 2-core machine, 2-3.6 ms at load 8, loops or numpy, where 22-37 ms would fit the 20 s)
ROLLOUT_HINT = ("a correct step takes 1-4 ms here, with plain Python loops or numpy alike: "
                "look for work your function repeats needlessly in every call (a print, a "
                "sleep, a loop far longer than its bodies or joints)")


def _carry_body(args: StepArgs, answer: Any) -> StepArgs:
    """The next step's arguments: the body's new state, the rest as it was."""
    x, v, q, L = (np.asarray(a, dtype=float) for a in answer)
    return (x, v, q, L, *args[4:])


def _flips(q: np.ndarray, L: np.ndarray, inertia_body: np.ndarray, h: float
           ) -> np.ndarray | None:
    """The times a body spun about its intermediate principal axis turns over (its spin about
    that axis, ω in the body frame, changes sign: the Dzhanibekov flip); None for a body not
    spun so."""
    inv = np.linalg.inv(inertia_body)
    R = rot.matrix_from_quat(q / np.linalg.norm(q, axis=-1, keepdims=True))
    omega = np.einsum("ij,tkj,tk->ti", inv, R, L)  # I₀⁻¹ Rᵀ L, step by step
    spin = omega @ np.linalg.eigh(inertia_body)[1][:, 1]
    if abs(spin[0]) < 0.5 * np.linalg.norm(omega[0]):
        return None
    flips: np.ndarray = h * (np.flatnonzero(np.sign(spin[1:]) != np.sign(spin[:-1])) + 2)
    return flips


def _times(t: np.ndarray) -> str:
    return ", ".join(f"{x:.2f} s" for x in t[:3]) + (" ..." if len(t) > 3 else "")


def run_verdict(yours: Run, reference: Run, start: StepArgs) -> str | None:
    """What a simulated body did wrong, if anything: its quaternion left the unit sphere,
    its angular momentum changed other than by the torque, it tumbled (flipped) unlike the
    reference, or its orientation or centre of mass left the reference's."""
    x, _, q, L = (np.array([a[i] for a in yours.answers]) for i in range(4))
    xr, _, qr, _ = (np.array([a[i] for a in reference.answers]) for i in range(4))
    h, torque = start[8], np.asarray(start[7])
    t = h * np.arange(1, len(yours.answers) + 1)
    norm = np.linalg.norm(q, axis=1)
    k = int(np.argmax(np.abs(norm - 1)))
    if abs(norm[k] - 1) > 1e-6:
        return (f"|q| is {norm[k]:.7g} at t = {t[k]:.2f} s (after {k + 1} steps): the "
                "orientation is no longer a rotation")
    L_exact = start[3] + t[:, None] * torque  # L changes by h τ a step, exactly
    off = np.linalg.norm(L - L_exact, axis=1)
    k = int(np.argmax(off))
    if off[k] > 1e-9 * (1 + np.linalg.norm(L_exact[k])):
        return (f"L is {show(L[k], 4)} at t = {t[k]:.2f} s, where L₀ + t τ = "
                f"{show(L_exact[k], 4)}: angular momentum changes only by the torque")
    apart = rot.quat_angle(q, qr)
    if apart.max() > 1e-3:
        k = int(np.argmax(apart > 1e-3))
        mine, theirs = _flips(q, L, start[5], h), _flips(qr, L_exact, start[5], h)
        tumble = ""
        if mine is not None and theirs is not None and (
                len(mine) != len(theirs) or not np.allclose(mine, theirs, atol=0.05)):
            tumble = (f"; it turns over at {_times(mine)}" if len(mine) else
                      "; it never turns over") + f", the reference's at {_times(theirs)}"
        return (f"its orientation leaves the reference's: {np.degrees(apart[k]):.3g}° apart "
                f"at t = {t[k]:.2f} s, {np.degrees(apart[-1]):.3g}° at the end"
                f"{tumble}")
    gap = np.linalg.norm(x - xr, axis=1)
    if gap.max() > 1e-6 * (1 + np.abs(xr).max()):
        k = int(np.argmax(gap))
        return (f"its centre of mass is {gap[k] * 1e3:.3g} mm from the reference's at "
                f"t = {t[k]:.2f} s")
    return None


def step_runs(rng: np.random.Generator) -> list[Case]:
    handle = t_handle()
    q = _random_quat(rng)
    R = rot.matrix_from_quat(q)
    L_handle = R @ handle.inertia @ np.array([20.0, 0.1, 0.05])
    box = np.diag([0.3, 0.5, 0.7])  # spun about its axis of most inertia: stable
    mass = 1.5
    thrown = (np.zeros(3), np.array([1.0, 4.0, 0.5]), q, R @ box @ np.array([0.2, 0.3, 6.0]),
              mass, box, mass * np.array([0.0, -9.81, 0.0]), np.zeros(3), 0.005)
    twisted = _step_args(rng, 0.005, diagonal=False)
    return [
        Case("a T-handle spun about its bar: it must flip over, as the reference's does",
             (np.zeros(3), np.zeros(3), q, L_handle, handle.mass, handle.inertia, np.zeros(3),
              np.zeros(3), 0.005)),
        Case("a box thrown up, spinning about its axis of most inertia (gravity as the "
             "force)", thrown),
        Case("a body off its principal axes under a constant force and torque", twisted),
    ]


# --- the PD torque -----------------------------------------------------------------------------


def _rotvec(d: np.ndarray, shortest: bool = True, factor: float = 2.0) -> np.ndarray:
    """``factor`` atan2(|v|, w) v/|v| of quaternions (J, 4); ``shortest``: d ← -d where w < 0
    first (2 log d is then the rotation vector of the turn of at most π)."""
    if shortest:
        d = d * np.where(d[:, :1] < 0, -1.0, 1.0)
    v = d[:, 1:]
    n = np.linalg.norm(v, axis=1, keepdims=True)
    axis = np.divide(v, n, out=np.zeros_like(v), where=n > 1e-300)
    out: np.ndarray = factor * np.arctan2(n, d[:, :1]) * axis
    return out


def pd_formula(q: np.ndarray, q_bar: np.ndarray, omega: np.ndarray, kp: float, kd: float,
               limit: float, *, world: bool = False, shortest: bool = True,
               factor: float = 2.0, kd_sign: float = -1.0, clip: bool = True) -> np.ndarray:
    r"""τ = clip(k_p r - k_d ω, ±limit), r the rotation vector of q⁻¹ q̄; and the mistakes:
    ``world`` (q̄ q⁻¹), ``shortest=False``, ``factor=1`` (log q, half the angle),
    ``kd_sign=+1``, ``clip=False``."""
    inv = rot.quat_conjugate(q)
    d = rot.quat_mul(q_bar, inv) if world else rot.quat_mul(inv, q_bar)
    tau = kp * _rotvec(d, shortest, factor) + kd_sign * kd * omega
    out: np.ndarray = np.clip(tau, -limit, limit) if clip else tau
    return out


def pd_reference(q: np.ndarray, q_bar: np.ndarray, omega: np.ndarray, kp: float, kd: float,
                 limit: float) -> np.ndarray:
    """With the library's rotation vector (``rot.rotvec_from_quat``, the short way)."""
    r = rot.rotvec_from_quat(rot.quat_mul(rot.quat_conjugate(q), q_bar))
    out: np.ndarray = np.clip(kp * r - kd * omega, -limit, limit)
    return out


def _pd_args(rng: np.random.Generator, joints: int, *, flips: bool = True, spread: float = 1.2,
             limit: float | None = None, identity: bool = False) -> tuple[Any, ...]:
    q = np.tile([1.0, 0, 0, 0], (joints, 1)) if identity else np.array(
        [_random_quat(rng) for _ in range(joints)])
    turn = rot.quat_from_rotvec(rng.normal(0, spread, (joints, 3)))
    q_bar = rot.quat_mul(q, turn)
    if flips:
        sign = np.where(rng.random(joints) < 0.5, -1.0, 1.0)
        sign[0] = -1.0  # d = q⁻¹q̄ with w < 0 at least once
        q_bar = q_bar * sign[:, None]
    kp, kd = float(rng.uniform(50, 300)), float(rng.uniform(2, 20))
    omega = rng.normal(0, 2, (joints, 3))
    if limit is None:  # some components clipped, most not
        tau = np.abs(pd_reference(q, q_bar, omega, kp, kd, np.inf))
        limit = float(np.quantile(tau, 0.75))
    return q, q_bar, omega, kp, kd, limit


def pd_random(rng: np.random.Generator) -> list[Case]:
    return [Case(f"{j} ball joints, some targets stored as -q̄, some torques at the limit",
                 _pd_args(rng, j)) for j in (1, 3, 5, 8, 12)]


def pd_edges(rng: np.random.Generator) -> list[Case]:
    q, _, omega, kp, kd, _ = _pd_args(rng, 4)
    return [
        Case("at the target, still (no torque)", (q, q.copy(), np.zeros((4, 3)), kp, kd, 100.0)),
        Case("at the target, moving (damping only)", (q, q.copy(), omega, kp, kd, 1e6)),
        Case("a joint at its rest orientation (q = identity)", _pd_args(rng, 3, identity=True)),
        Case("limits never reached", _pd_args(rng, 5, limit=1e6)),
        Case("targets 2.5-3 rad away (the short way matters)", _pd_args(rng, 5, spread=1.7)),
    ]


def pd_hidden(rng: np.random.Generator) -> list[Case]:
    return [Case(f"hidden joints #{i + 1}", _pd_args(rng, int(rng.integers(2, 10))))
            for i in range(8)]


DRIVE_EPS = 1e-4  # rad and rad/s: the nudges the drive cases measure the torque law with
JOINT_INERTIA = np.diag([0.1, 0.15, 0.2])  # kg m²: the joint the grader drives (body frame)


def drive_args(rng: np.random.Generator, spread: float, stored_negated: bool) -> tuple[Any, ...]:
    """A drive case: one target q̄ (12 rows), the joint turned ±DRIVE_EPS off it about each
    axis of its own frame (rows 0-5), and turned DRIVE_EPS about (1, 1, 1)/√3 off it
    spinning ±DRIVE_EPS about each axis (rows 6-11; never exactly at the target, where
    q⁻¹(-q̄) = -1 has no axis and rounding picks one). The torques there are the torque law
    near the target: τ ≈ τ₀ + K_p r - K_d ω."""
    q_bar = rot.quat_from_rotvec(rng.normal(0, spread, 3))
    nudges = rot.quat_from_rotvec(np.vstack([-DRIVE_EPS * np.eye(3), DRIVE_EPS * np.eye(3)]))
    off = rot.quat_mul(q_bar, rot.quat_from_rotvec(-DRIVE_EPS * np.ones(3) / np.sqrt(3)))
    q = np.vstack([rot.quat_mul(q_bar, nudges), np.tile(off, (6, 1))])
    omega = np.vstack([np.zeros((6, 3)), DRIVE_EPS * np.eye(3), -DRIVE_EPS * np.eye(3)])
    target = np.tile(-q_bar if stored_negated else q_bar, (12, 1))
    return q, target, omega, float(rng.uniform(20, 200)), float(rng.uniform(0.5, 5.0)), 1e6


def is_drive_case(args: tuple[Any, ...]) -> bool:
    q, q_bar, omega = (np.asarray(a) for a in args[:3])
    return bool(q.shape == (12, 4) and np.all(q_bar == q_bar[0]) and np.all(omega[:6] == 0)
                and np.all(q[6:] == q[6])
                and np.array_equal(omega[6:], DRIVE_EPS * np.vstack([np.eye(3), -np.eye(3)])))


def drive_rates(got: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The closed loop of the joint JOINT_INERTIA driven by the torques ``got`` of a drive
    case: ``(τ₀, K_p, K_d, eigenvalues)`` of ṙ = -ω, I ω̇ = τ₀ + K_p r - K_d ω (small errors),
    by central differences."""
    tau0 = got[:6].mean(axis=0)
    Kp = (got[0:3] - got[3:6]).T / (2 * DRIVE_EPS)
    Kd = -(got[6:9] - got[9:12]).T / (2 * DRIVE_EPS)
    inv = np.linalg.inv(JOINT_INERTIA)
    A = np.block([[np.zeros((3, 3)), -np.eye(3)], [inv @ Kp, -inv @ Kd]])
    return tau0, Kp, Kd, np.linalg.eigvals(A)


def drive_verdict(got: np.ndarray) -> str | None:
    """None if the joint driven by these torques settles on its target, else what it does."""
    tau0, _, _, lam = drive_rates(got)
    if np.max(np.abs(tau0)) > 1e-6:
        return (f"at its target and still, the joint gets a torque of about {show(tau0)}: it "
                "is pushed away from where it should rest")
    worst = lam[np.argmax(lam.real)]
    if worst.real < -1e-3:
        return None
    if worst.real <= 1e-3:
        return ("a joint driven by your torques never settles: it swings about its target "
                "forever (no damping)")
    how = ("swings about its target ever wider" if abs(worst.imag) > 1e-9
           else "runs away from its target")
    return (f"a joint driven by your torques (inertia diag(0.1, 0.15, 0.2) kg m², a small "
            f"error to start) {how}: its error grows like e^({worst.real:.3g} t), it diverges")


def pd_drive(rng: np.random.Generator) -> list[Case]:
    return [
        Case("a joint near its target settles (target turned 0.5 rad from rest)",
             drive_args(rng, 0.3, False)),
        Case("the same, the target stored as -q̄", drive_args(rng, 0.3, True)),
        Case("a target turned far from rest (about 2.5 rad)", drive_args(rng, 1.5, False)),
        Case("a target turned far from rest, stored as -q̄", drive_args(rng, 1.5, True)),
    ]


DRIVE_H = 1 / 300  # s: the step of the grader's simulated joints
DRIVE_RUN = 270  # steps: 0.9 s (the reference is within 1° of its targets by 0.7 s)


def _carry_joints(args: tuple[Any, ...], tau: np.ndarray) -> tuple[Any, ...]:
    """Each joint one step on: JOINT_INERTIA turning under ``tau`` (Euler's equations in its
    own frame, I ω̇ = τ - ω × I ω), semi-implicit, q⁺ = q ⊗ exp(h ω⁺)."""
    q, q_bar, omega, *gains = args
    inv = np.linalg.inv(JOINT_INERTIA)
    omega = omega + DRIVE_H * (tau - np.cross(omega, omega @ JOINT_INERTIA)) @ inv
    q = rot.quat_mul(q, rot.quat_from_rotvec(DRIVE_H * omega))
    return (q / np.linalg.norm(q, axis=1, keepdims=True), q_bar, omega, *gains)


def drive_run_verdict(yours: Run, reference: Run, start: tuple[Any, ...]) -> str | None:
    """What joints driven by these torques did wrong, if anything: a torque past its limit,
    the long way round to a target, or still off target at the end."""
    limit = start[5]
    over = max(float(np.max(np.abs(a))) for a in yours.answers)
    if over > limit * (1 + 1e-9):
        return f"a torque reached {over:.4g} N m, past the limit ±{limit:g} N m"
    runs = [yours.states, reference.states]
    end = runs[0][-1]
    away = rot.quat_angle(start[0], start[1])
    off, spin = rot.quat_angle(end[0], end[1]), np.linalg.norm(end[2], axis=1)
    j = int(np.argmax(off + spin))
    if off[j] > 0.01 or spin[j] > 0.1:
        return (f"after {DRIVE_H * len(yours.answers):.2g} s joint {j} is {off[j]:.3g} rad "
                f"from its target, turning at {spin[j]:.3g} rad/s (it started {away[j]:.2f} rad "
                "away; the reference's joints have settled)")
    travel = [DRIVE_H * sum(np.linalg.norm(s[2], axis=1) for s in r[1:]) for r in runs]
    j = int(np.argmax(travel[0] - travel[1]))
    if travel[0][j] > travel[1][j] + 0.5:
        return (f"joint {j} turned through {travel[0][j]:.2f} rad on its way to a target "
                f"{away[j]:.2f} rad away (the reference's: {travel[1][j]:.2f} rad): it went "
                "the long way round, or wandered")
    return None


def pd_runs(rng: np.random.Generator) -> list[Case]:
    def far(stored_negated: bool) -> tuple[Any, ...]:
        q = np.array([_random_quat(rng) for _ in range(3)])
        axes = rng.normal(size=(3, 3))
        axes /= np.linalg.norm(axes, axis=1, keepdims=True)
        turn = rot.quat_from_rotvec(axes * np.array([[2.0], [2.5], [2.8]]))
        q_bar = rot.quat_mul(q, turn) * (-1.0 if stored_negated else 1.0)
        kp = float(rng.uniform(100, 200))
        return q, q_bar, np.zeros((3, 3)), kp, 2 * np.sqrt(kp * 0.2), 15.0
    return [
        Case("three joints driven 2-2.8 rad to their targets, torques at their limit",
             far(False)),
        Case("the same, the targets stored as -q̄", far(True)),
    ]


PD_RUN = Rollout(DRIVE_RUN, _carry_joints, drive_run_verdict, hint=ROLLOUT_HINT)


# --- the balance torque ------------------------------------------------------------------------


def chain_points(joint_angles: np.ndarray, lengths: np.ndarray, com_ratios: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Joint positions (n + 1, 2), the foot first, and link centres of mass (n, 2): link i
    points along (-sin φ_i, cos φ_i), φ_i = θ_0 + ... + θ_i from the vertical."""
    phi = np.cumsum(joint_angles)
    u = np.stack([-np.sin(phi), np.cos(phi)], axis=1)
    joints = np.vstack([np.zeros(2), np.cumsum(lengths[:, None] * u, axis=0)])
    coms = joints[:-1] + (com_ratios * lengths)[:, None] * u
    return joints, coms


def point_jacobian(joints: np.ndarray, p: np.ndarray, link: int) -> np.ndarray:
    """(2, n): ∂p/∂θ_j = ẑ × (p - joint_j) for the joints j <= ``link`` below p, else 0."""
    n = len(joints) - 1
    J = np.zeros((2, n))
    r = p - joints[: link + 1]
    J[0, : link + 1], J[1, : link + 1] = -r[:, 1], r[:, 0]
    return J


def com_jacobian(joint_angles: np.ndarray, lengths: np.ndarray, masses: np.ndarray,
                 com_ratios: np.ndarray, weighted: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The whole body's COM c (2,) and its Jacobian J_c (2, n), mass-weighted (or, with
    ``weighted=False``, the plain average of the links')."""
    joints, coms = chain_points(joint_angles, lengths, com_ratios)
    w = masses / masses.sum() if weighted else np.full(len(masses), 1 / len(masses))
    J = sum(wi * point_jacobian(joints, c, i) for i, (wi, c) in enumerate(zip(w, coms,
                                                                            strict=True)))
    return w @ coms, np.asarray(J)


def balance_formula(joint_angles: np.ndarray, lengths: np.ndarray, masses: np.ndarray,
                    com_ratios: np.ndarray, com_target: np.ndarray, com_velocity: np.ndarray,
                    kp: float, kd: float, *, point: str = "com", transpose: str = "T"
                    ) -> np.ndarray:
    """τ = J_cᵀ f, and the mistakes: ``point`` "tip" (the top joint's Jacobian), "top" (the
    top link's COM), "average" (the links' COM Jacobians unweighted); ``transpose`` "pinv"."""
    c, J = com_jacobian(joint_angles, lengths, masses, com_ratios)
    f = kp * (com_target - c) - kd * com_velocity
    joints, coms = chain_points(joint_angles, lengths, com_ratios)
    n = len(lengths)
    if point == "tip":
        J = point_jacobian(joints, joints[-1], n - 1)
    elif point == "top":
        J = point_jacobian(joints, coms[-1], n - 1)
    elif point == "average":
        J = com_jacobian(joint_angles, lengths, masses, com_ratios, weighted=False)[1]
    out: np.ndarray = np.linalg.pinv(J) @ f if transpose == "pinv" else J.T @ f
    return out


def balance_reference(*args: Any) -> np.ndarray:
    return balance_formula(*args)


def _balance_args(rng: np.random.Generator, n: int, lean: float = 0.15) -> tuple[Any, ...]:
    angles = rng.normal(0, lean, n)
    lengths = rng.uniform(0.3, 0.8, n)
    masses = rng.uniform(1.0, 20.0, n)
    ratios = rng.uniform(0.3, 0.7, n)
    c, _ = com_jacobian(angles, lengths, masses, ratios)
    target = np.array([rng.normal(0, 0.05), c[1]])
    return (angles, lengths, masses, ratios, target, rng.normal(0, 0.3, 2),
            float(rng.uniform(100, 1000)), float(rng.uniform(10, 100)))


def balance_random(rng: np.random.Generator) -> list[Case]:
    return [Case(f"a standing chain of {n} links", _balance_args(rng, n)) for n in (2, 3, 4, 5, 6)]


def balance_edges(rng: np.random.Generator) -> list[Case]:
    one = _balance_args(rng, 1)
    upright = list(_balance_args(rng, 3))
    upright[0] = np.zeros(3)
    still = list(_balance_args(rng, 4))
    still[5] = np.zeros(2)
    return [
        Case("one link (an inverted pendulum)", one),
        Case("standing straight up", tuple(upright)),
        Case("at rest (ċ = 0)", tuple(still)),
        Case("a deep bend (joint angles up to 1 rad)", _balance_args(rng, 4, lean=0.8)),
    ]


def balance_hidden(rng: np.random.Generator) -> list[Case]:
    return [Case(f"hidden chain #{i + 1}", _balance_args(rng, int(rng.integers(2, 8))))
            for i in range(6)]


def _not_transposed(*args: Any) -> np.ndarray:
    """J_c f: defined only where J_c is square (two links); elsewhere the product raises."""
    c, J = com_jacobian(*args[:4])
    if J.shape[1] != 2:
        raise ValueError("J f is undefined: J is (2, n)")
    out: np.ndarray = J @ (args[6] * (args[4] - c) - args[7] * args[5])
    return out


def _shape_error(error: dict[str, Any], *args: Any) -> str | None:
    if error.get("type") != "ValueError" or "matmul" not in str(error.get("message", "")):
        return None
    n = len(args[0])
    return (f"J_c is (2, {n}) and f is (2,): J_c @ f does not exist; the torques are "
            f"J_c.T @ f, shape ({n},)")


# --- the balance torque holding up a pushed chain ----------------------------------------------

#: a standing body as three links (shank, thigh, trunk with head): m, kg
STAND_LENGTHS, STAND_MASSES = np.array([0.45, 0.45, 0.6]), np.array([8.0, 16.0, 36.0])
STAND_RATIOS = np.array([0.55, 0.55, 0.4])
#: the grader's own joint PD holding the posture: too weak at the ankle (50 N m/rad against
#: gravity's M g h ≈ 500) for the chain to stand without the balance torque
POSTURE_KP, POSTURE_KD = np.array([50.0, 600.0, 400.0]), np.array([5.0, 60.0, 40.0])
GRAVITY = 9.81
STAND_H = 0.005  # s
STAND_RUN = 300  # steps: 1.5 s


def _mass_matrices(thetas: np.ndarray) -> np.ndarray:
    """M(θ) (B, n, n) of the standing chain at each row of ``thetas`` (B, n):
    Σ m_i J_iᵀJ_i + I_i w_iw_iᵀ, J_i the Jacobian of link i's centre of mass (column j:
    ẑ × (c_i - p_j) for the joints j <= i), w_i its angular one, slender links I = m l²/12."""
    phi = np.cumsum(thetas, axis=1)  # as chain_points, for every row at once
    bone = STAND_LENGTHS[:, None] * np.stack([-np.sin(phi), np.cos(phi)], axis=2)  # (B, n, 2)
    joints = np.cumsum(bone, axis=1) - bone  # the joint at the bottom of each link
    coms = joints + STAND_RATIOS[:, None] * bone
    r = coms[:, :, None, :] - joints[:, None, :, :]  # (B, i, j, 2)
    below = np.tril(np.ones((len(STAND_LENGTHS),) * 2))  # joint j moves link i when j <= i
    J = np.stack([-r[..., 1], r[..., 0]], axis=2) * below[None, :, None, :]  # (B, i, 2, j)
    spin = STAND_MASSES * STAND_LENGTHS**2 / 12
    out: np.ndarray = (np.einsum("i,biaj,biak->bjk", STAND_MASSES, J, J)
                       + np.einsum("i,ij,ik->jk", spin, below, below))
    return out


def _chain_acceleration(theta: np.ndarray, dtheta: np.ndarray, tau: np.ndarray) -> np.ndarray:
    r"""θ̈ from Lagrange's equations, M θ̈ = τ + Q_g - (Ṁ θ̇ - ½ ∂(θ̇ᵀMθ̇)/∂θ), the velocity
    terms from central differences ∂M/∂θ_k (the grader's plant, the same for every run)."""
    eps, n = 1e-6, len(theta)
    nudged = theta + eps * np.concatenate([np.eye(n), -np.eye(n)])
    M, *around = _mass_matrices(np.vstack([theta, nudged]))
    slopes = (np.asarray(around[:n]) - np.asarray(around[n:])) / (2 * eps)  # ∂M/∂θ_k
    Mdot = np.einsum("k,kij->ij", dtheta, slopes)
    bias = Mdot @ dtheta - 0.5 * np.einsum("i,kij,j->k", dtheta, slopes, dtheta)
    _, Jc = com_jacobian(theta, STAND_LENGTHS, STAND_MASSES, STAND_RATIOS)
    weight = STAND_MASSES.sum() * Jc.T @ np.array([0.0, -GRAVITY])
    out: np.ndarray = np.linalg.solve(M, tau + weight - bias)
    return out


#: a run's state: joint angles, their rates, the posture held, the call's other arguments
StandState = tuple[np.ndarray, np.ndarray, np.ndarray, tuple[Any, ...]]


def _stand_start(args: tuple[Any, ...]) -> StandState:
    """The pose of the call, pushed: the joint rates of least norm that give its ċ."""
    _, Jc = com_jacobian(args[0], *args[1:4])
    return args[0], np.linalg.pinv(Jc) @ args[5], args[0], args


def _stand_call(state: StandState) -> tuple[Any, ...]:
    theta, dtheta, _, args = state
    _, Jc = com_jacobian(theta, *args[1:4])
    return (theta, *args[1:5], Jc @ dtheta, *args[6:])


def _fallen(theta: np.ndarray, args: tuple[Any, ...]) -> bool:
    """Its centre of mass 0.3 m off the foot or below 60 % of its height: it has fallen."""
    c, _ = com_jacobian(theta, *args[1:4])
    return bool(abs(c[0]) > 0.3 or c[1] < 0.6 * args[4][1])


def _carry_stand(state: StandState, tau: Any) -> StandState:
    """One step of the chain under the balance torque and the grader's posture PD,
    semi-implicit; a chain that has fallen stays where it lies."""
    theta, dtheta, pose, args = state
    if _fallen(theta, args):
        return theta, np.zeros_like(dtheta), pose, args
    total = np.asarray(tau) - POSTURE_KP * (theta - pose) - POSTURE_KD * dtheta
    with np.errstate(all="ignore"):
        dtheta = dtheta + STAND_H * _chain_acceleration(theta, dtheta, total)
    if not np.all(np.isfinite(dtheta)):  # torques past anything a body could take
        return theta, np.zeros_like(dtheta), pose, args
    return theta + STAND_H * dtheta, dtheta, pose, args


def stand_verdict(yours: Run, reference: Run, start: tuple[Any, ...]) -> str | None:
    """Whether the pushed chain falls, and where its centre of mass ends up."""
    runs = [yours.states[1:], reference.states[1:]]
    coms = [np.array([com_jacobian(s[0], *start[1:4])[0] for s in r]) - start[4] for r in runs]
    t = STAND_H * np.arange(1, len(yours.answers) + 1)
    back = np.linalg.norm(coms[1], axis=1) > 0.02
    settled = t[np.flatnonzero(back)[-1] + 1] if back.any() else t[0]
    fell = [k for k, s in enumerate(runs[0]) if _fallen(s[0], start)]
    if fell:
        k = fell[0]
        return (f"the chain falls: by t = {t[k]:.2f} s its centre of mass is "
                f"{abs(coms[0][k][0]):.2f} m off the foot and {-coms[0][k][1]:.2f} m lower "
                f"(the reference's strays at most {np.abs(coms[1][:, 0]).max() * 100:.0f} cm "
                f"and is back within 2 cm by {settled:.2f} s)")
    off = float(np.linalg.norm(coms[0][-1]))
    if off > 0.02:
        return (f"the chain stands but its centre of mass is still {off * 100:.1f} cm from its "
                f"target after {t[-1]:g} s (the reference's is back within 2 cm by "
                f"{settled:.2f} s)")
    return None


STAND = Rollout(STAND_RUN, _carry_stand, stand_verdict, _stand_start, _stand_call,
                hint=ROLLOUT_HINT)


def stand_runs(rng: np.random.Generator) -> list[Case]:
    def pushed(pose: np.ndarray, push: float) -> tuple[Any, ...]:
        c, _ = com_jacobian(pose, STAND_LENGTHS, STAND_MASSES, STAND_RATIOS)
        pose = pose - np.array([np.arctan2(c[0], c[1]), 0.0, 0.0])  # its COM over the foot
        c, _ = com_jacobian(pose, STAND_LENGTHS, STAND_MASSES, STAND_RATIOS)
        return (pose, STAND_LENGTHS, STAND_MASSES, STAND_RATIOS, np.array([0.0, c[1]]),
                np.array([push, 0.0]), float(rng.uniform(1400, 1600)),
                float(rng.uniform(280, 320)))
    return [
        Case("a body standing straight, pushed forward (ċ = 0.6 m/s): it must not fall",
             pushed(np.zeros(3), 0.6)),
        Case("a body standing with bent knees, pushed backward (ċ = -0.5 m/s)",
             pushed(np.array([0.1, -0.3, 0.25]), -0.5)),
    ]


# --- the catalogue of known mistakes -----------------------------------------------------------

MISCONCEPTIONS = (
    Misconception(
        "omega_body_inertia", "rigid_body_step", "ω from the body-frame inertia (I₀⁻¹ L)",
        "Your orientation turned with ω = I₀⁻¹ L⁺. L is in the WORLD frame and I₀ in the BODY "
        "frame: rotate the inertia first, I = R I₀ Rᵀ, so ω = R I₀⁻¹ Rᵀ L⁺ (R from q at the "
        "start of the step). Only at R = I do the two agree.",
        wrong=_variant(omega="body")),
    Misconception(
        "inertia_rotated_wrong_way", "rigid_body_step", "the inertia rotated the wrong way "
        "(Rᵀ I₀ R)",
        "Your orientation turned with ω = Rᵀ I₀⁻¹ R L⁺: the inertia taken to the world as "
        "Rᵀ I₀ R. R maps body to world, so I = R I₀ Rᵀ and ω = R I₀⁻¹ Rᵀ L⁺ (into the body "
        "frame with Rᵀ, through I₀⁻¹, back with R).",
        wrong=_variant(omega="transposed")),
    Misconception(
        "not_renormalised", "rigid_body_step", "q⁺ not renormalised",
        "q + (h/2)[0, ω]⊗q is a little longer than 1 (by about h²|ω|²/8): divide it by its "
        "norm, q⁺ = q⁺/‖q⁺‖, every step, or the orientation stops being a rotation.",
        wrong=_variant(renormalise=False)),
    Misconception(
        "explicit", "rigid_body_step", "x moved with the old velocity (explicit Euler)",
        "Semi-implicit Euler updates the velocity first and moves with the NEW one: "
        "v⁺ = v + h f/m, then x⁺ = x + h v⁺. Yours is x⁺ = x + h v, explicit Euler's (it "
        "does not keep energy bounded).",
        symptom=_explicit),
    Misconception(
        "kd_sign", "pd_torque", "the damping with the wrong sign (+k_d ω)",
        "Damping opposes the motion: τ = k_p r - k_d ω. Yours adds k_d ω, which feeds the "
        "joint's velocity back into it and makes it oscillate ever more (it diverges).",
        wrong=lambda *a: pd_formula(*a, kd_sign=1.0)),
    Misconception(
        "limit_ignored", "pd_torque", "the torque limit ignored",
        "Each component of τ must be clipped to [-limit, limit]: np.clip(τ, -limit, limit). "
        "Yours returns the unclipped k_p r - k_d ω where a joint is far from its target.",
        wrong=lambda *a: pd_formula(*a, clip=False)),
    Misconception(
        "error_world_frame", "pd_torque", "the error q̄ q⁻¹ (the world frame)",
        "The error is the turn from q to q̄ in the joint's own frame, where ω and τ are: "
        "q⁻¹ q̄ (q times it is q̄). q̄ q⁻¹ is the same turn expressed in the parent's frame; the "
        "two agree only at q = identity (quaternion products do not commute).",
        wrong=lambda *a: pd_formula(*a, world=True)),
    Misconception(
        "no_shortest_path", "pd_torque", "no shortest path (q̄ and -q̄ treated differently)",
        "q̄ and -q̄ are the same target, but 2 log(d) of d = q⁻¹ q̄ with w < 0 is a turn of "
        "more than π, the long way round: flip d ← -d when its w < 0 before taking the "
        "rotation vector.",
        wrong=lambda *a: pd_formula(*a, shortest=False)),
    Misconception(
        "half_angle", "pd_torque", "half the angle (log d, not 2 log d)",
        "log d = (θ/2) u for d = (cos θ/2, sin θ/2 u): the rotation vector of the error is "
        "θ u = 2 log d. Yours drives the joint with half its error.",
        wrong=lambda *a: pd_formula(*a, factor=1.0)),
    Misconception(
        "tip_jacobian", "balance_torque", "Jᵀ of the chain's tip, not of the centre of mass",
        "The force f acts on the centre of mass c, so τ = J_cᵀ f with J_c = ∂c/∂θ. Yours uses "
        "the Jacobian of the top of the chain (the end effector), which weighs every joint by "
        "its lever arm to the tip, not to the body's mass.",
        wrong=lambda *a: balance_formula(*a, point="tip")),
    Misconception(
        "top_link_jacobian", "balance_torque", "Jᵀ of the top link's centre of mass only",
        "J_c is the Jacobian of the WHOLE body's centre of mass, c = Σ m_i c_i / M: "
        "J_c = Σ m_i J_{c_i} / M, every link's COM Jacobian weighted by its mass. Yours uses "
        "the top link's J_{c_n} alone.",
        wrong=lambda *a: balance_formula(*a, point="top")),
    Misconception(
        "unweighted_average", "balance_torque", "the links' COM Jacobians averaged without "
        "their masses",
        "c = Σ m_i c_i / M weights each link by its mass, so J_c = Σ m_i J_{c_i} / M. Yours "
        "averages the J_{c_i} equally (Σ J_{c_i} / n): right only when all links weigh the "
        "same.",
        wrong=lambda *a: balance_formula(*a, point="average")),
    Misconception(
        "not_transposed", "balance_torque", "J f instead of Jᵀ f",
        "τ = J_cᵀ f: J_c is (2, n), one column per joint, and each joint's torque is its "
        "column dotted with f. J_c @ f only exists for a square J_c (two links), and mixes the "
        "joints' columns there; write J_c.T @ f.",
        wrong=_not_transposed, explains=_shape_error),
    Misconception(
        "pseudo_inverse", "balance_torque", "J⁺ f (inverse kinematics) instead of Jᵀ f",
        "A force f at the COM is produced by the joint torques τ = J_cᵀ f (virtual work: "
        "τ·dθ = f·dc). Yours solves J_c dθ = f with the pseudo-inverse, which is inverse "
        "kinematics' velocity map, not a torque.",
        wrong=lambda *a: balance_formula(*a, transpose="pinv")),
)


# --- the assignment ----------------------------------------------------------------------------


class VectorsCheck(Check):
    """(J, 3) torques, one row per joint, named by row; the drive cases
    (:func:`is_drive_case`) are judged by what the torques achieve."""

    def judge(self, got: Any, expected: Any, args: tuple[Any, ...]) -> str | None:
        if is_drive_case(args):
            return drive_verdict(np.asarray(got, dtype=float))
        return self.compare(got, expected)

    def compare(self, got: np.ndarray, expected: np.ndarray) -> str | None:
        err = np.abs(np.subtract(got, expected))
        tol = self.atol + self.rtol * np.abs(expected)
        bad = np.flatnonzero(np.any(np.reshape(err > tol, (len(err), -1)), axis=1))
        if not bad.size:
            return None
        i = int(bad[0])
        digits = self.decimals(got[i], expected[i])
        more = f"; {bad.size} of {len(err)} rows are off" if bad.size > 1 else ""
        return (f"{self.noun} {i} is {show(got[i], digits)}, expected "
                f"{show(expected[i], digits)}{more}")


class UnitQuatCheck(QuatCheck):
    """q⁺: off the unit sphere by 1e-4 is a mistake here, so the norm is shown to the digit
    that differs (QuatCheck's |q| = 1.000 would hide it)."""

    def compare(self, got: np.ndarray, expected: np.ndarray,
                name: Any = None) -> str | None:
        norm = float(np.linalg.norm(got))
        if abs(norm - 1.0) > self.atol:
            return (f"is not a unit quaternion: |q| - 1 = {norm - 1.0:.2g}; rotations need "
                    "|q| = 1")
        return super().compare(got, expected, name)


_STEP_CHECK = TupleCheck((Check((3,), atol=1e-9, rtol=1e-9), Check((3,), atol=1e-9, rtol=1e-9),
                          UnitQuatCheck(atol=1e-9), Check((3,), atol=1e-9, rtol=1e-9)),
                         ("x", "v", "q", "L"))

_FUNCTIONS = (
    Function("rigid_body_step",
             ("x", "v", "q", "L", "mass", "inertia_body", "force", "torque", "h"),
             step_reference, _STEP_CHECK),
    Function("pd_torque", ("q", "q_bar", "omega", "kp", "kd", "limit"), pd_reference,
             VectorsCheck(None, atol=1e-7, rtol=1e-9, noun="joint")),
    Function("balance_torque",
             ("joint_angles", "lengths", "masses", "com_ratios", "com_target", "com_velocity",
              "kp", "kd"),
             balance_reference, Check(None, atol=1e-7, rtol=1e-9, noun="torques")),
)

ASSIGNMENT = Assignment(
    key="a6",
    title="Rigid bodies and joint control",
    template="a6_physics.py",
    functions=_FUNCTIONS,
    tests=(
        *random_edge_hidden("rigid_body_step", step_random, step_edges, step_hidden),
        Test("rigid_body_step: bodies simulated for 1.5 s", "rigid_body_step", 1.0,
             step_runs, rollout=Rollout(STEP_RUN, _carry_body, run_verdict, hint=ROLLOUT_HINT)),
        *random_edge_hidden("pd_torque", pd_random, pd_edges, pd_hidden),
        Test("pd_torque: a joint driven to its target", "pd_torque", 1.0, pd_drive),
        Test("pd_torque: joints driven from far for 0.9 s", "pd_torque", 1.0, pd_runs,
             rollout=PD_RUN),
        *random_edge_hidden("balance_torque", balance_random, balance_edges, balance_hidden),
        Test("balance_torque: a pushed body kept standing for 1.5 s", "balance_torque", 1.0,
             stand_runs, rollout=STAND),
    ),
    misconceptions=MISCONCEPTIONS,
)
