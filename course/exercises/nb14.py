"""Notebook 14 · a simulated character: the PD torque of one ball joint, the largest stable
gain of explicit PD, and a Jacobian-transpose torque that holds a centre of mass."""

from __future__ import annotations

import numpy as np

from autograder.checks import Check
from autograder.spec import Case, Function, Misconception

from ..rotations import quat_conjugate, quat_mul, rotvec_from_quat
from ._cases import unit_quat, vector
from .spec import Exercise


def pd_torque(q: np.ndarray, q_bar: np.ndarray, omega: np.ndarray, kp: float,
              kd: float) -> np.ndarray:
    r"""Reference of 14.pd_torque: the PD torque of one ball joint in its own frame,
    :math:`\tau = k_p \log(q^{-1}\bar q) - k_d\,\omega`, the rotation vector of the shorter of
    the two turns (:math:`q^{-1}\bar q` and its negative are the same rotation)."""
    error = rotvec_from_quat(quat_mul(quat_conjugate(q), q_bar))
    return np.asarray(kp * error - kd * np.asarray(omega, dtype=float), dtype=float)


def kp_max(inertia: float, h: float, kd: float) -> float:
    r"""Reference of 14.kp_max: the largest stable :math:`k_p` of explicit PD on a joint of
    inertia :math:`I` (``inertia``) stepped by semi-implicit Euler with step :math:`h`.

    With :math:`a = h k_d / I`, :math:`b = h^2 k_p / I`, one step of the error
    :math:`(\dot x, x)` is :math:`\dot x^+ = (1-a)\dot x - (b/h) x`, :math:`x^+ = x + h\dot x^+`,
    whose characteristic polynomial is :math:`\lambda^2 - (2-a-b)\lambda + (1-a)`. Both roots
    are inside the unit circle while :math:`b > 0`, :math:`0 < a < 2` and
    :math:`p(-1) = 4 - 2a - b > 0`, so :math:`k_p < (4I - 2hk_d)/h^2` (:math:`k_d = 0`:
    :math:`\omega h < 2`, notebook 12's bound)."""
    return float((4.0 * inertia - 2.0 * h * kd) / h**2)


def leg_torque(theta: np.ndarray, lengths: np.ndarray, c_bar: np.ndarray,
               kp: float) -> np.ndarray:
    r"""Reference of 14.leg_torque: a planar two-link leg, ankle at the origin, joint angles
    :math:`\theta_1` (ankle, from the x axis) and :math:`\theta_2` (knee, relative), its mass
    lumped at the hip :math:`c = l_1 (\cos\theta_1, \sin\theta_1) + l_2(\cos(\theta_1+\theta_2),
    \sin(\theta_1+\theta_2))`. The virtual force :math:`f = k_p(\bar c - c)` becomes the
    torques :math:`\tau = J^\top f`, :math:`J = \partial c/\partial\theta` (2 x 2)."""
    t1, t2 = float(theta[0]), float(theta[1])
    l1, l2 = float(lengths[0]), float(lengths[1])
    c = np.array([l1 * np.cos(t1) + l2 * np.cos(t1 + t2), l1 * np.sin(t1) + l2 * np.sin(t1 + t2)])
    J = np.array([[-l1 * np.sin(t1) - l2 * np.sin(t1 + t2), -l2 * np.sin(t1 + t2)],
                  [l1 * np.cos(t1) + l2 * np.cos(t1 + t2), l2 * np.cos(t1 + t2)]])
    f = kp * (np.asarray(c_bar, dtype=float) - c)
    return np.asarray(J.T @ f, dtype=float)


# -- mistakes ---------------------------------------------------------------------------------


def _log_no_shortest(q: np.ndarray) -> np.ndarray:
    """The rotation vector 2 arccos(w) u, without choosing the sign of q first."""
    w = float(np.clip(q[0], -1.0, 1.0))
    v = np.asarray(q[1:], dtype=float)
    s = float(np.linalg.norm(v))
    return np.zeros(3) if s < 1e-12 else 2.0 * np.arccos(w) * v / s


def _leg(theta: np.ndarray, lengths: np.ndarray, relative: bool = True
         ) -> tuple[np.ndarray, np.ndarray]:
    t1, t2 = float(theta[0]), float(theta[1])
    l1, l2 = float(lengths[0]), float(lengths[1])
    a2 = t1 + t2 if relative else t2
    c = np.array([l1 * np.cos(t1) + l2 * np.cos(a2), l1 * np.sin(t1) + l2 * np.sin(a2)])
    J = np.array([[-l1 * np.sin(t1) - l2 * np.sin(a2), -l2 * np.sin(a2)],
                  [l1 * np.cos(t1) + l2 * np.cos(a2), l2 * np.cos(a2)]])
    return c, J


# -- cases ------------------------------------------------------------------------------------


def _pd_cases(rng: np.random.Generator) -> list[Case]:
    half = np.array([np.cos(np.pi / 8), 0.0, np.sin(np.pi / 8), 0.0])  # 45° about y
    cases = [Case("at rest, target 45° about y, kp = 100", (np.array([1.0, 0, 0, 0]), half,
                                                           np.zeros(3), 100.0, 10.0)),
             Case("the target given as −q̄ (the same rotation)",
                  (np.array([1.0, 0, 0, 0]), -half, np.array([0.0, 1.0, 0.0]), 50.0, 5.0))]
    for k in (1, 2):
        q, q_bar = unit_quat(rng), unit_quat(rng)
        if k == 2:
            q_bar = -q_bar if quat_mul(quat_conjugate(q), q_bar)[0] > 0 else q_bar
        cases.append(Case(f"a random joint ({k})", (q, q_bar, vector(rng),
                                                    float(np.round(rng.uniform(10, 500))),
                                                    float(np.round(rng.uniform(1, 20), 1)))))
    return cases


def _kp_cases(rng: np.random.Generator) -> list[Case]:
    cases = [Case("a hand: I = 0.01 kg m², h = 1/600 s, no damping", (0.01, 1 / 600, 0.0)),
             Case("a thigh: I = 0.5 kg m², h = 1/120 s, kd = 10", (0.5, 1 / 120, 10.0))]
    for k in (1, 2):
        inertia = float(np.round(rng.uniform(0.01, 2.0), 3))
        h = float(rng.choice([1 / 1000, 1 / 600, 1 / 240, 1 / 60]))
        kd = float(np.round(rng.uniform(0.0, 1.5 * inertia / h), 1))
        cases.append(Case(f"a random joint ({k})", (inertia, h, kd)))
    return cases


def _leg_cases(rng: np.random.Generator) -> list[Case]:
    cases = [Case("straight up, target 5 cm forward",
                  (np.array([np.pi / 2, 0.0]), np.array([0.5, 0.5]), np.array([0.05, 1.0]),
                   1000.0)),
             Case("knee bent, target where the hip is: no torque",
                  (np.array([1.2, 0.6]), np.array([0.45, 0.5]),
                   _leg(np.array([1.2, 0.6]), np.array([0.45, 0.5]))[0], 800.0))]
    for k in (1, 2):
        theta = np.round([rng.uniform(0.9, 2.2), rng.uniform(-1.2, 1.2)], 2)
        lengths = np.round(rng.uniform(0.3, 0.6, size=2), 2)
        c_bar = np.round(_leg(theta, lengths)[0] + rng.normal(scale=0.1, size=2), 3)
        cases.append(Case(f"a random leg ({k})", (theta, lengths, c_bar,
                                                  float(np.round(rng.uniform(100, 2000))))))
    return cases


EXERCISES = (
    Exercise(
        "pd_torque",
        Function("pd_torque", ("q", "q_bar", "omega", "kp", "kd"), pd_torque,
                 Check((3,), atol=1e-6, noun="torque")),
        _pd_cases,
        hint="The error is the turn that takes the joint from where it is, q, to where it "
             "should be, q̄, seen from the joint's own frame; q and −q are the same rotation, "
             "so take the shorter way round. Damping opposes the angular velocity.",
        formula="e = quat_mul(quat_conjugate(q), q_bar); if e[0] < 0: e = −e; "
                "τ = kp · rotvec_from_quat(e) − kd · ω.",
        mistakes=(
            Misconception("world_frame_error", "pd_torque",
                          "the error taken as q̄ q⁻¹ (the parent's frame)",
                          "q̄ q⁻¹ is the turn seen from the parent's frame; the torque acts "
                          "in the joint's frame, where the turn from q to q̄ is q⁻¹ q̄.",
                          wrong=lambda q, qb, w, kp, kd: kp * rotvec_from_quat(
                              quat_mul(qb, quat_conjugate(q))) - kd * w),
            Misconception("damping_sign", "pd_torque", "the damping added, not subtracted",
                          "+kd ω pushes the joint the way it already turns and feeds energy "
                          "in; damping is τ = … − kd ω.",
                          wrong=lambda q, qb, w, kp, kd: kp * rotvec_from_quat(
                              quat_mul(quat_conjugate(q), qb)) + kd * w),
            Misconception("long_way_round", "pd_torque",
                          "the long way round when q⁻¹ q̄ has w < 0",
                          "q and −q are the same rotation; 2 arccos(w) with w < 0 is an angle "
                          "over π, the long way round. Flip the sign of q⁻¹ q̄ first when its w "
                          "is negative.",
                          wrong=lambda q, qb, w, kp, kd: kp * _log_no_shortest(
                              quat_mul(quat_conjugate(q), qb)) - kd * w),
        ),
    ),
    Exercise(
        "kp_max",
        Function("kp_max", ("inertia", "h", "kd"), kp_max, Check((), rtol=1e-9, noun="gain")),
        _kp_cases,
        hint="Write one step of ẋ⁺ = ẋ + h(−kp x − kd ẋ)/I, x⁺ = x + h ẋ⁺ as a 2 x 2 matrix; "
             "its eigenvalues must stay inside the unit circle. Which of λ = 1 and λ = −1 does "
             "a too-stiff spring cross?",
        formula="p(λ) = λ² − (2 − a − b) λ + (1 − a), a = h kd / I, b = h² kp / I; "
                "p(−1) = 4 − 2a − b > 0 gives kp_max = (4 I − 2 h kd) / h².",
        mistakes=(
            Misconception("no_damping_term", "kp_max", "the damping's share left out",
                          "Explicit damping also sits in the step: p(−1) = 4 − 2a − b, so the "
                          "bound is (4I − 2 h kd)/h², lower than 4I/h² when kd > 0.",
                          wrong=lambda i, h, kd: 4.0 * i / h**2),
            Misconception("omega_not_squared", "kp_max", "ω_max = 2/h taken as kp itself",
                          "ω = √(kp/I), so ω h < 2 means kp < I (2/h)², the square of the "
                          "frequency times the inertia.",
                          wrong=lambda i, h, kd: i * 2.0 / h - 2.0 * kd / h),
            Misconception("inertia_inverted", "kp_max", "the inertia divided, not multiplied",
                          "A heavier joint tolerates a stiffer spring: ω² = kp / I, so "
                          "kp_max grows with I.",
                          wrong=lambda i, h, kd: (4.0 / i - 2.0 * h * kd) / h**2),
        ),
    ),
    Exercise(
        "leg_torque",
        Function("leg_torque", ("theta", "lengths", "c_bar", "kp"), leg_torque,
                 Check((2,), atol=1e-6, noun="torque")),
        _leg_cases,
        hint="Find the hip c from θ (the knee angle is relative to the shin), the virtual "
             "force pulling c to c̄, and the Jacobian ∂c/∂θ; by virtual work the torques are "
             "the force through the Jacobian's transpose.",
        formula="c = l₁(cos θ₁, sin θ₁) + l₂(cos(θ₁+θ₂), sin(θ₁+θ₂)); f = kp (c̄ − c); "
                "J = [[−l₁ sin θ₁ − l₂ sin(θ₁+θ₂), −l₂ sin(θ₁+θ₂)], [l₁ cos θ₁ + l₂ cos(θ₁+θ₂), "
                "l₂ cos(θ₁+θ₂)]]; τ = J.T @ f.",
        mistakes=(
            Misconception("jacobian_not_transposed", "leg_torque", "J f instead of Jᵀ f",
                          "J maps joint velocities to the COM's velocity; forces go the other "
                          "way, by virtual work f · δc = f · J δθ = (Jᵀ f) · δθ: τ = Jᵀ f.",
                          wrong=lambda t, ls, cb, kp: _leg(t, ls)[1] @ (
                              kp * (np.asarray(cb) - _leg(t, ls)[0]))),
            Misconception("force_reversed", "leg_torque", "the force pointing away from c̄",
                          "The virtual spring pulls the COM towards its target: f = kp (c̄ − c).",
                          wrong=lambda t, ls, cb, kp: -leg_torque(t, ls, cb, kp)),
            Misconception("absolute_knee", "leg_torque", "the knee angle taken as absolute",
                          "θ₂ is the knee's angle relative to the shin: the thigh points along "
                          "θ₁ + θ₂, in c and in both columns of J.",
                          wrong=lambda t, ls, cb, kp: _leg(t, ls, False)[1].T @ (
                              kp * (np.asarray(cb) - _leg(t, ls, False)[0]))),
        ),
    ),
)
