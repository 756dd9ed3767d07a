"""Notebook 15 · walking: the capture point of the linear inverted pendulum, SIMBICON's
balance feedback on the swing hip, and the ZMP of contact forces."""

from __future__ import annotations

import numpy as np

from autograder.checks import Check
from autograder.spec import Case, Function, Misconception

from .spec import Exercise

G = 9.81  # m/s², the course's (course.physics.lip.G)


def capture_point(com: np.ndarray, com_velocity: np.ndarray, ground_height: float) -> np.ndarray:
    r"""Reference of 15.capture_point: the capture point :math:`\xi = c + \dot c/\omega_0` on
    the ground (its ``(x, z)``, y up), :math:`\omega_0 = \sqrt{g/h}` with :math:`h` the COM's
    height above the ground under the foot, ``com[1] - ground_height``."""
    c, v = np.asarray(com, dtype=float), np.asarray(com_velocity, dtype=float)
    omega0 = np.sqrt(G / (c[1] - float(ground_height)))
    return np.asarray(c[[0, 2]] + v[[0, 2]] / omega0, dtype=float)


def _forward(heading: float) -> np.ndarray:
    """The walking direction at ``heading`` (radians about +y, positive to the left): +z at 0."""
    return np.array([np.sin(heading), 0.0, np.cos(heading)])


def swing_hip_target(hip0: float, c_d: float, c_v: float, com: np.ndarray,
                     com_velocity: np.ndarray, stance_ankle: np.ndarray,
                     heading: float) -> float:
    r"""Reference of 15.swing_hip_target: SIMBICON's sagittal feedback
    :math:`\theta_d = \theta_{d0} + c_d\,d + c_v\,v`, with :math:`d` the COM's horizontal
    offset from the stance ankle and :math:`v` its velocity, both along the walking
    direction :math:`(\sin\psi, 0, \cos\psi)` of the heading :math:`\psi` (world frame, y
    up)."""
    f = _forward(float(heading))
    d = float(np.dot(np.asarray(com, dtype=float) - np.asarray(stance_ankle, dtype=float), f))
    v = float(np.dot(np.asarray(com_velocity, dtype=float), f))
    return float(hip0 + c_d * d + c_v * v)


def zmp_from_forces(positions: np.ndarray, forces: np.ndarray,
                    ground_height: float) -> np.ndarray:
    r"""Reference of 15.zmp_from_forces: the point :math:`p` of the ground plane
    :math:`y = p_y` about which the contact forces have no horizontal moment,
    :math:`p_x = \sum_i [x_i f_{i,y} - (y_i - p_y) f_{i,x}] / \sum_i f_{i,y}` and
    :math:`p_z` alike (:func:`course.physics.zmp.zmp_from_forces`)."""
    r, f = np.asarray(positions, dtype=float), np.asarray(forces, dtype=float)
    py = float(ground_height)
    arm = r[:, 1] - py
    fy = f[:, 1].sum()
    px = (r[:, 0] * f[:, 1] - arm * f[:, 0]).sum() / fy
    pz = (r[:, 2] * f[:, 1] - arm * f[:, 2]).sum() / fy
    return np.array([px, py, pz])


# -- mistakes ---------------------------------------------------------------------------------


def _capture_wrong_height(com: np.ndarray, v: np.ndarray, ground: float) -> np.ndarray:
    c, v = np.asarray(com, dtype=float), np.asarray(v, dtype=float)
    return np.asarray(c[[0, 2]] + v[[0, 2]] / np.sqrt(G / c[1]), dtype=float)


def _capture_times_omega(com: np.ndarray, v: np.ndarray, ground: float) -> np.ndarray:
    c, v = np.asarray(com, dtype=float), np.asarray(v, dtype=float)
    return np.asarray(c[[0, 2]] + v[[0, 2]] * np.sqrt(G / (c[1] - ground)), dtype=float)


def _capture_no_sqrt(com: np.ndarray, v: np.ndarray, ground: float) -> np.ndarray:
    c, v = np.asarray(com, dtype=float), np.asarray(v, dtype=float)
    return np.asarray(c[[0, 2]] + v[[0, 2]] / (G / (c[1] - ground)), dtype=float)


def _hip_signs(h0: float, cd: float, cv: float, c: np.ndarray, v: np.ndarray, a: np.ndarray,
               psi: float) -> float:
    return 2.0 * h0 - swing_hip_target(h0, cd, cv, c, v, a, psi)


def _hip_from_origin(h0: float, cd: float, cv: float, c: np.ndarray, v: np.ndarray,
                     a: np.ndarray, psi: float) -> float:
    return swing_hip_target(h0, cd, cv, c, v, np.zeros(3), psi)


def _hip_world_z(h0: float, cd: float, cv: float, c: np.ndarray, v: np.ndarray, a: np.ndarray,
                 psi: float) -> float:
    return swing_hip_target(h0, cd, cv, c, v, a, 0.0)


def _zmp_moment_sign(r: np.ndarray, f: np.ndarray, ground: float) -> np.ndarray:
    r, f = np.asarray(r, dtype=float), np.asarray(f, dtype=float)
    arm = r[:, 1] - float(ground)
    fy = f[:, 1].sum()
    return np.array([(r[:, 0] * f[:, 1] + arm * f[:, 0]).sum() / fy, float(ground),
                     (r[:, 2] * f[:, 1] + arm * f[:, 2]).sum() / fy])


def _zmp_vertical_only(r: np.ndarray, f: np.ndarray, ground: float) -> np.ndarray:
    r, f = np.asarray(r, dtype=float), np.asarray(f, dtype=float)
    fy = f[:, 1].sum()
    return np.array([(r[:, 0] * f[:, 1]).sum() / fy, float(ground),
                     (r[:, 2] * f[:, 1]).sum() / fy])


def _zmp_unweighted(r: np.ndarray, f: np.ndarray, ground: float) -> np.ndarray:
    r = np.asarray(r, dtype=float)
    return np.array([r[:, 0].mean(), float(ground), r[:, 2].mean()])


# -- cases ------------------------------------------------------------------------------------


def _capture_cases(rng: np.random.Generator) -> list[Case]:
    cases = [Case("at rest: the capture point is under the COM",
                  (np.array([0.1, 0.8, 0.3]), np.zeros(3), 0.0)),
             Case("walking forward at 1 m/s, COM 0.981 m above flat ground",
                  (np.array([0.0, 0.981, 0.0]), np.array([0.0, 0.0, 1.0]), 0.0)),
             Case("standing on a 0.5 m platform, pushed sideways",
                  (np.array([0.2, 1.3, -0.1]), np.array([0.6, 0.05, 0.0]), 0.5))]
    for k in (1, 2):
        ground = float(np.round(rng.uniform(-0.3, 0.6), 2))
        com = np.round([rng.uniform(-1, 1), ground + rng.uniform(0.6, 1.0),
                        rng.uniform(-1, 1)], 2)
        cases.append(Case(f"a random state ({k})",
                          (com, np.round(rng.normal(scale=0.8, size=3), 2), ground)))
    return cases


def _hip_cases(rng: np.random.Generator) -> list[Case]:
    cases = [Case("the COM over the stance ankle, at rest: no feedback",
                  (0.35, 0.8, 0.3, np.array([0.2, 0.7, 1.0]), np.zeros(3),
                   np.array([0.2, 0.0, 1.0]), 0.0)),
             Case("COM 10 cm ahead of the stance ankle, 0.5 m/s forward, heading 0",
                  (0.3, 0.8, 0.3, np.array([0.1, 0.7, 2.1]), np.array([0.0, 0.0, 0.5]),
                   np.array([0.1, 0.0, 2.0]), 0.0)),
             Case("walking along +x (heading π/2), the COM behind the ankle",
                  (0.3, 0.7, 0.2, np.array([3.0, 0.7, 1.0]), np.array([0.4, 0.0, 0.1]),
                   np.array([3.05, 0.0, 0.9]), float(np.pi / 2)))]
    for k in (1, 2):
        ankle = np.round([rng.uniform(-2, 2), 0.0, rng.uniform(-2, 2)], 2)
        com = np.round(ankle + [rng.uniform(-0.2, 0.2), 0.7, rng.uniform(-0.2, 0.2)], 2)
        cases.append(Case(f"a random state ({k})",
                          (float(np.round(rng.uniform(0.2, 0.5), 2)),
                           float(np.round(rng.uniform(0.3, 1.2), 2)),
                           float(np.round(rng.uniform(0.1, 0.6), 2)), com,
                           np.round(rng.normal(scale=0.5, size=3), 2), ankle,
                           float(np.round(rng.uniform(-np.pi, np.pi), 2)))))
    return cases


def _zmp_cases(rng: np.random.Generator) -> list[Case]:
    feet = np.array([[-0.1, 0.0, 0.0], [0.1, 0.0, 0.0], [-0.1, 0.0, 0.2], [0.1, 0.0, 0.2]])
    cases = [Case("four contacts on flat ground, equal vertical forces",
                  (feet, np.tile([0.0, 100.0, 0.0], (4, 1)), 0.0)),
             Case("on the ground, more weight on the toes, some friction",
                  (feet, np.array([[5.0, 50.0, 2.0], [5.0, 50.0, 2.0], [-3.0, 150.0, 8.0],
                                   [-3.0, 150.0, 8.0]]), 0.0)),
             Case("two contacts 5 cm above the ZMP's plane, pushed forward",
                  (np.array([[0.0, 0.05, 0.0], [0.0, 0.05, 0.3]]),
                   np.array([[0.0, 200.0, 40.0], [10.0, 200.0, 40.0]]), 0.0))]
    for k in (1, 2):
        n = int(rng.integers(3, 6))
        ground = float(np.round(rng.uniform(-0.2, 0.2), 2))
        r = np.round(np.column_stack([rng.uniform(-0.3, 0.3, n),
                                      ground + rng.uniform(0.0, 0.1, n),
                                      rng.uniform(-0.3, 0.3, n)]), 2)
        f = np.round(np.column_stack([rng.normal(scale=30, size=n), rng.uniform(50, 300, n),
                                      rng.normal(scale=30, size=n)]), 1)
        cases.append(Case(f"random contacts ({k})", (r, f, ground)))
    return cases


EXERCISES = (
    Exercise(
        "capture_point",
        Function("capture_point", ("com", "com_velocity", "ground_height"), capture_point,
                 Check((2,), atol=1e-6, noun="capture point")),
        _capture_cases,
        hint="The pendulum's natural frequency ω₀ = √(g/h) needs the COM's height above the "
             "ground the foot stands on, not its y. Then move the COM's ground position by "
             "its velocity over ω₀ (a length: m/s over 1/s).",
        formula="h = com[1] − ground_height; ω₀ = √(9.81 / h); "
                "ξ = com[[0, 2]] + com_velocity[[0, 2]] / ω₀.",
        mistakes=(
            Misconception("omega_wrong_height", "capture_point",
                          "ω₀ from the COM's y, not its height above the ground",
                          "ω₀ = √(g/h) with h the pendulum's length: the COM's height above "
                          "the ground under the foot, com[1] − ground_height. The COM's y "
                          "is that only on a floor at y = 0.",
                          wrong=_capture_wrong_height),
            Misconception("times_omega", "capture_point", "the velocity times ω₀, not over it",
                          "ξ − c must be a length: ċ (m/s) divided by ω₀ (1/s). ċ ω₀ is an "
                          "acceleration.", wrong=_capture_times_omega),
            Misconception("omega_not_rooted", "capture_point", "ω₀ = g/h without the root",
                          "The LIP is c̈ = (g/h)(c − p), so ω₀² = g/h and ω₀ = √(g/h).",
                          wrong=_capture_no_sqrt),
        ),
    ),
    Exercise(
        "swing_hip_target",
        Function("swing_hip_target",
                 ("hip0", "c_d", "c_v", "com", "com_velocity", "stance_ankle", "heading"),
                 swing_hip_target, Check((), atol=1e-6, noun="swing hip target")),
        _hip_cases,
        hint="d is how far the COM is ahead of the stance ankle and v how fast it moves, both "
             "measured along the walking direction in the world (not the pelvis's frame, not "
             "the world's z axis). A COM too far ahead or too fast must swing the leg further "
             "forward: the feedback adds.",
        formula="f = (sin ψ, 0, cos ψ); d = (com − stance_ankle) · f; v = com_velocity · f; "
                "θ_d = hip0 + c_d d + c_v v.",
        mistakes=(
            Misconception("feedback_signs", "swing_hip_target",
                          "the c_d and c_v terms subtracted",
                          "A COM ahead of the stance foot, or moving forward, needs the swing "
                          "foot further forward to catch it: θ_d = θ_d0 + c_d d + c_v v. "
                          "Subtracting them steps back when falling forward.",
                          wrong=_hip_signs),
            Misconception("d_from_origin", "swing_hip_target",
                          "d measured from the world origin, not the stance ankle",
                          "d is the COM's offset from the stance ankle, the pendulum's pivot; "
                          "the COM's own position grows with every step walked.",
                          wrong=_hip_from_origin),
            Misconception("heading_ignored", "swing_hip_target",
                          "d and v along the world's z axis, not the walking direction",
                          "The feedback is in the world frame but along the heading: "
                          "f = (sin ψ, 0, cos ψ). Along z it only holds for ψ = 0.",
                          wrong=_hip_world_z),
        ),
    ),
    Exercise(
        "zmp_from_forces",
        Function("zmp_from_forces", ("positions", "forces", "ground_height"), zmp_from_forces,
                 Check((3,), atol=1e-6, noun="ZMP")),
        _zmp_cases,
        hint="Take the moment of every force about a point p on the ground plane and ask for "
             "its horizontal part to vanish. A contact above the plane adds the moment of its "
             "horizontal force, arm (y_i − p_y): which sign does it get?",
        formula="arm = positions[:, 1] − ground_height; F = Σ f_y; "
                "p_x = Σ (x f_y − arm f_x) / F; p_z = Σ (z f_y − arm f_z) / F; "
                "p = (p_x, ground_height, p_z).",
        mistakes=(
            Misconception("moment_sign", "zmp_from_forces",
                          "the horizontal forces' moment with the wrong sign",
                          "The moment about p of f at r is (r − p) × f. Its x part with r − p = "
                          "(x − p_x, y − p_y, z − p_z) gives (y − p_y) f_z − (z − p_z) f_y = 0 "
                          "for p_z: p_z = Σ [z f_y − (y − p_y) f_z] / Σ f_y, a minus.",
                          wrong=_zmp_moment_sign),
            Misconception("vertical_only", "zmp_from_forces",
                          "the horizontal forces left out for contacts above the plane",
                          "Σ p_i f_y / Σ f_y is the ZMP only when every contact is on the "
                          "plane; above it a horizontal force has a lever arm y_i − p_y.",
                          wrong=_zmp_vertical_only),
            Misconception("unweighted_mean", "zmp_from_forces",
                          "the mean of the contact points, not weighted by the forces",
                          "The ZMP is where the forces' resultant acts: each point weighs by "
                          "its vertical force.", wrong=_zmp_unweighted),
        ),
    ),
)
