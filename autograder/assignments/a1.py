r"""Assignment a1, rotations: the spec the autograder checks ``assignments/a1_rotations.py`` by.

Six functions, each with three tests: random cases (1 point), hand-picked edge cases
(1 point), and hidden cases from the instructor's secret seed (2 points). Reference:
:mod:`course.rotations`. The catalogue lists the classic wrong answers, each written as a
function of the reference, so a failing test can say which mistake it looks like.
"""

from __future__ import annotations

import numpy as np

from course import rotations as ref

from ..checks import MatrixCheck, QuatCheck
from ..spec import Assignment, Case, Function, Misconception, random_edge_hidden

PI = np.pi
TAIT_BRYAN = ref.TAIT_BRYAN_ORDERS
INTRINSIC = ref.TAIT_BRYAN_ORDERS + ref.PROPER_EULER_ORDERS

# --- random inputs ---------------------------------------------------------------------------


def _quat(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=4)
    unit: np.ndarray = q / np.linalg.norm(q)
    return unit


def _axis(rng: np.random.Generator, unit: bool = True) -> np.ndarray:
    u = rng.normal(size=3)
    u /= np.linalg.norm(u)
    return u if unit else u * rng.uniform(0.3, 3.0)


def _near_half_turn(rng: np.random.Generator) -> np.ndarray:
    """A rotation within 1e-6 rad of 180 degrees: w ~ 0, where naive formulas break."""
    return ref.quat_from_axis_angle(_axis(rng), PI - rng.uniform(0, 1e-6))


def _deg(a: float) -> str:
    return f"{np.degrees(a):g}°"


def _e(*v: float) -> np.ndarray:
    return np.array(v, dtype=float)


X, Y, Z, IDENTITY = _e(1, 0, 0), _e(0, 1, 0), _e(0, 0, 1), _e(1, 0, 0, 0)

# --- cases per function ------------------------------------------------------------------------


def _mat(q: np.ndarray) -> np.ndarray:
    return ref.matrix_from_quat(q)


def quat_from_matrix_random(rng: np.random.Generator) -> list[Case]:
    return [Case(f"random rotation #{i + 1}", (_mat(_quat(rng)),)) for i in range(10)]


def quat_from_matrix_edges(rng: np.random.Generator) -> list[Case]:
    diag = _e(1, 1, 0) / np.sqrt(2)
    return [
        Case("identity", (np.eye(3),)),
        *(Case(f"180° about {n}", (_mat(ref.quat_from_axis_angle(a, PI)),))
          for n, a in (("x", X), ("y", Y), ("z", Z))),
        Case("180° about (1, 1, 0)", (_mat(ref.quat_from_axis_angle(diag, PI)),)),
        Case("179.9999° about a random axis (w ≈ 0)", (_mat(_near_half_turn(rng)),)),
        Case("90° about z", (_mat(ref.quat_from_axis_angle(Z, PI / 2)),)),
        Case("a tiny turn (1e-9 rad)", (_mat(ref.quat_from_axis_angle(_axis(rng), 1e-9)),)),
    ]


def quat_from_matrix_hidden(rng: np.random.Generator) -> list[Case]:
    return [Case(f"hidden rotation #{i + 1}",
                 (_mat(_near_half_turn(rng) if i % 4 == 3 else _quat(rng)),)) for i in range(24)]


def matrix_from_quat_random(rng: np.random.Generator) -> list[Case]:
    return [Case(f"random quaternion #{i + 1}", (_quat(rng),)) for i in range(10)]


def matrix_from_quat_edges(rng: np.random.Generator) -> list[Case]:
    return [
        Case("identity (1, 0, 0, 0)", (IDENTITY,)),
        Case("-identity (-1, 0, 0, 0), the same rotation", (-IDENTITY,)),
        Case("(0, 1, 0, 0): 180° about x", (_e(0, 1, 0, 0),)),
        Case("(0, 0, 1, 0): 180° about y", (_e(0, 0, 1, 0),)),
        Case("(0, 0, 0, 1): 180° about z", (_e(0, 0, 0, 1),)),
        Case("90° about x", (ref.quat_from_axis_angle(X, PI / 2),)),
        Case("a quaternion with w < 0", (-np.abs(_quat(rng)),)),
    ]


def matrix_from_quat_hidden(rng: np.random.Generator) -> list[Case]:
    return [Case(f"hidden quaternion #{i + 1}", (_quat(rng),)) for i in range(24)]


def axis_angle_random(rng: np.random.Generator) -> list[Case]:
    return [Case(f"random unit axis and angle #{i + 1}", (_axis(rng), rng.uniform(-PI, PI)))
            for i in range(10)]


def axis_angle_edges(rng: np.random.Generator) -> list[Case]:
    return [
        Case("angle 0", (_axis(rng), 0.0)),
        Case("90° about z", (Z, PI / 2)),
        Case("180° about x", (X, PI)),
        Case("-60° about y", (Y, -PI / 3)),
        Case("270° about a random axis", (_axis(rng), 1.5 * PI)),
        Case("360° (the identity rotation)", (_axis(rng), 2 * PI)),
        Case("axis of length 3 (normalise it!)", (3 * _axis(rng), 1.0)),
        Case("axis (0, 0.5, 0), 45°", (_e(0, 0.5, 0), PI / 4)),
    ]


def axis_angle_hidden(rng: np.random.Generator) -> list[Case]:
    return [Case(f"hidden axis and angle #{i + 1}", (_axis(rng, unit=False),
                                                     rng.uniform(-2 * PI, 2 * PI)))
            for i in range(24)]


def euler_random(rng: np.random.Generator) -> list[Case]:
    return [Case(f"random angles, order {o}", (rng.uniform(-PI, PI, 3), o))
            for o in TAIT_BRYAN for _ in range(2)]


def euler_edges(rng: np.random.Generator) -> list[Case]:
    a, c = rng.uniform(-PI, PI, 2)
    return [
        Case("zero angles, XYZ", (np.zeros(3), "XYZ")),
        Case("only the first angle, XYZ (30°, 0, 0)", (_e(PI / 6, 0, 0), "XYZ")),
        Case("only the last angle, ZYX (0, 0, 30°)", (_e(0, 0, PI / 6), "ZYX")),
        Case(f"gimbal lock, XYZ ({_deg(a)}, 90°, {_deg(c)})", (_e(a, PI / 2, c), "XYZ")),
        Case(f"gimbal lock, ZYX ({_deg(c)}, -90°, {_deg(a)})", (_e(c, -PI / 2, a), "ZYX")),
        Case("proper Euler order ZXZ", (rng.uniform(-PI, PI, 3), "ZXZ")),
        Case("proper Euler order YXY", (rng.uniform(-PI, PI, 3), "YXY")),
        Case("angles beyond 180°, YZX", (rng.uniform(PI, 2 * PI, 3), "YZX")),
    ]


def euler_hidden(rng: np.random.Generator) -> list[Case]:
    return [Case(f"hidden angles #{i + 1}, order {o}", (rng.uniform(-PI, PI, 3), o))
            for i, o in enumerate(rng.choice(INTRINSIC, 24))]


def mul_random(rng: np.random.Generator) -> list[Case]:
    return [Case(f"random pair #{i + 1}", (_quat(rng), _quat(rng))) for i in range(10)]


def mul_edges(rng: np.random.Generator) -> list[Case]:
    q = _quat(rng)
    i, j, k = _e(0, 1, 0, 0), _e(0, 0, 1, 0), _e(0, 0, 0, 1)
    return [
        Case("identity times q", (IDENTITY, q)),
        Case("q times identity", (q, IDENTITY)),
        Case("i j = k", (i, j)),
        Case("90° about z, then 90° about x (order matters)",
             (ref.quat_from_axis_angle(X, PI / 2), ref.quat_from_axis_angle(Z, PI / 2))),
        Case("k k = -1", (k, k)),
        Case("q times its conjugate = identity", (q, q * _e(1, -1, -1, -1))),
        Case("90° about x, then 90° about z", (ref.quat_from_axis_angle(Z, PI / 2),
                                               ref.quat_from_axis_angle(X, PI / 2))),
    ]


def mul_hidden(rng: np.random.Generator) -> list[Case]:
    return [Case(f"hidden pair #{i + 1}", (_quat(rng), _quat(rng))) for i in range(24)]


def _pair_short(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    q0, q1 = _quat(rng), _quat(rng)
    return q0, (q1 if q0 @ q1 >= 0 else -q1)


def slerp_random(rng: np.random.Generator) -> list[Case]:
    out = []
    for i in range(10):
        q0, q1 = _pair_short(rng)
        out.append(Case(f"random pair #{i + 1}, t = {(t := rng.uniform(0.05, 0.45)):.2f}",
                        (q0, q1, t)))
    return out


def slerp_edges(rng: np.random.Generator) -> list[Case]:
    q0, q1 = _pair_short(rng)
    near = ref.quat_mul(q0, ref.quat_from_axis_angle(_axis(rng), 2e-7))
    return [
        Case("t = 0 gives q0", (q0, q1, 0.0)),
        Case("t = 1 gives q1", (q0, q1, 1.0)),
        Case("q0 · q1 < 0: take the shortest path, t = 0.3", (q0, -q1, 0.3)),
        Case("q0 · q1 < 0: take the shortest path, t = 0.8", (-q0, q1, 0.8)),
        Case("q1 = -q0 (the same rotation), t = 0.4", (q0, -q0, 0.4)),
        Case("q0 = q1 (sin Ω = 0), t = 0.7", (q0, q0.copy(), 0.7)),
        Case("q0 ≈ q1 (2e-7 rad apart), t = 0.25", (q0, near, 0.25)),
        Case("identity to 120° about z, t = 0.25",
             (IDENTITY, ref.quat_from_axis_angle(Z, 2 * PI / 3), 0.25)),
    ]


def slerp_hidden(rng: np.random.Generator) -> list[Case]:
    return [Case(f"hidden pair #{i + 1}", (_quat(rng), _quat(rng), rng.uniform(0, 1)))
            for i in range(24)]


# --- the catalogue of known mistakes ---------------------------------------------------------


def _xyzw(q: np.ndarray) -> np.ndarray:  # a scalar-first quaternion written scalar-last
    return np.roll(q, -1)


def _wxyz(p: np.ndarray) -> np.ndarray:  # a scalar-last array read as the quaternion it meant
    return np.roll(p, 1)


def _conj(q: np.ndarray) -> np.ndarray:
    conj: np.ndarray = np.asarray(q) * _e(1, -1, -1, -1)
    return conj


def _trace_only(R: np.ndarray) -> np.ndarray:
    with np.errstate(all="ignore"):
        w = np.sqrt(1 + np.trace(R)) / 2
        q: np.ndarray = np.array([w, R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / _e(
            1, 4 * w, 4 * w, 4 * w)
        return q


def _slerp_long_way(q0: np.ndarray, q1: np.ndarray, t: float) -> np.ndarray:
    omega = np.arccos(np.clip(q0 @ q1, -1, 1))
    with np.errstate(all="ignore"):
        q: np.ndarray = (np.sin((1 - t) * omega) * q0 + np.sin(t * omega) * q1) / np.sin(omega)
        return q


def _elementary_flipped(angles: np.ndarray, order: str) -> np.ndarray:
    m = [ref.matrix_from_euler(_e(*np.eye(3)[n] * -angles[n]), order) for n in range(3)]
    return m[0] @ m[1] @ m[2]


MISCONCEPTIONS = (
    # quat_from_matrix
    Misconception(
        "conjugate", "quat_from_matrix", "the conjugate (inverse) quaternion",
        "The vector part comes from R - Rᵀ: x = (R₂₁ - R₁₂)/(4w), y = (R₀₂ - R₂₀)/(4w), "
        "z = (R₁₀ - R₀₁)/(4w); you took the differences the other way round, which gives "
        "q* = (w, -x, -y, -z), the inverse rotation.",
        lambda R: _conj(ref.quat_from_matrix(R))),
    Misconception(
        "trace_only", "quat_from_matrix", "w from the trace alone (breaks at 180°)",
        "w = ½√(1 + tr R) is 0 for a half turn, so x = (R₂₁ - R₁₂)/(4w) divides by zero; "
        "solve first for the largest of 4w² = 1 + tr R, 4x² = 1 + R₀₀ - R₁₁ - R₂₂, "
        "4y² = 1 - R₀₀ + R₁₁ - R₂₂, 4z² = 1 - R₀₀ - R₁₁ + R₂₂ (Shepperd's method).",
        _trace_only),
    # matrix_from_quat
    Misconception("xyzw", "matrix_from_quat", "the quaternion read as (x, y, z, w)",
                  "The input is scalar first, q = (w, x, y, z): w is q[0], not q[3].",
                  lambda q: ref.matrix_from_quat(_wxyz(q))),
    Misconception(
        "transposed", "matrix_from_quat", "the transposed matrix (the inverse rotation)",
        "You returned Rᵀ = R⁻¹: in R = [[1-2(y²+z²), 2(xy-wz), 2(xz+wy)], [2(xy+wz), "
        "1-2(x²+z²), 2(yz-wx)], [2(xz-wy), 2(yz+wx), 1-2(x²+y²)]] the terms with w change "
        "sign across the diagonal.",
        lambda q: ref.matrix_from_quat(q).T),
    # quat_from_axis_angle
    Misconception(
        "half_angle", "quat_from_axis_angle", "the full angle instead of the half angle",
        "A quaternion holds half the angle, q = (cos θ/2, sin θ/2·u); with cos θ and sin θ "
        "it turns by 2θ.",
        lambda axis, angle: ref.quat_from_axis_angle(axis, 2 * angle)),
    Misconception(
        "unnormalised_axis", "quat_from_axis_angle", "the axis not normalised",
        "Only a unit axis gives a unit quaternion: use u = axis / |axis| in "
        "q = (cos θ/2, sin θ/2·u).",
        lambda axis, angle: np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])),
    Misconception(
        "conjugate", "quat_from_axis_angle", "turning the wrong way (the conjugate)",
        "A right-handed turn by θ about u is q = (cos θ/2, +sin θ/2·u); your vector part has "
        "the opposite sign, which is the inverse rotation q*.",
        lambda axis, angle: _conj(ref.quat_from_axis_angle(axis, angle))),
    # matrix_from_euler
    Misconception(
        "extrinsic", "matrix_from_euler", "extrinsic instead of intrinsic",
        "Uppercase \"XYZ\" is intrinsic, about the moving axes: R = R_X(a) R_Y(b) R_Z(c); you "
        "multiplied in the extrinsic order R_Z(c) R_Y(b) R_X(a) (what \"xyz\" means).",
        lambda angles, order: ref.matrix_from_euler(angles, order.lower())),
    Misconception(
        "elementary_sign", "matrix_from_euler", "elementary rotations turning the wrong way",
        "R_X(θ) = [[1, 0, 0], [0, cos θ, -sin θ], [0, sin θ, cos θ]] (likewise R_Y, R_Z): the "
        "-sin θ is above the diagonal; with the signs swapped each factor turns by -θ.",
        _elementary_flipped),
    # quat_mul
    Misconception(
        "reversed", "quat_mul", "the product in the wrong order",
        "The product does not commute: a b = (w_a w_b - v_a·v_b, w_a v_b + w_b v_a + "
        "v_a × v_b); you computed b a, which flips the sign of v_a × v_b.",
        lambda a, b: ref.quat_mul(b, a)),
    Misconception("xyzw", "quat_mul", "quaternions read and written as (x, y, z, w)",
                  "The course stores the scalar first, q = (w, x, y, z); your product treats "
                  "the last entry as w.",
                  lambda a, b: _xyzw(ref.quat_mul(_wxyz(a), _wxyz(b)))),
    # slerp
    Misconception(
        "long_way", "slerp", "no shortest path",
        "q and -q are the same rotation: when q₀·q₁ < 0 use -q₁, or SLERP turns the long way "
        "round (more than 180°).",
        _slerp_long_way),
    Misconception(
        "nlerp", "slerp", "NLERP instead of SLERP",
        "Normalising (1-t) q₀ + t q₁ follows the right arc but not at constant speed; SLERP is "
        "sin((1-t)Ω)/sin Ω · q₀ + sin(tΩ)/sin Ω · q₁ with cos Ω = q₀·q₁.",
        ref.nlerp),
    Misconception(
        "lerp", "slerp", "LERP: not normalised",
        "(1-t) q₀ + t q₁ is not a unit quaternion; SLERP's weights sin((1-t)Ω)/sin Ω and "
        "sin(tΩ)/sin Ω keep |q| = 1.",
        lambda q0, q1, t: ref.lerp(q0, q1 if q0 @ q1 >= 0 else -q1, t)),
    Misconception(
        "t_reversed", "slerp", "t running backwards",
        "slerp(q₀, q₁, 0) is q₀ and slerp(q₀, q₁, 1) is q₁: the weight of q₀ is "
        "sin((1-t)Ω)/sin Ω.",
        lambda q0, q1, t: ref.slerp(q0, q1, 1 - t)),
)

# --- the assignment --------------------------------------------------------------------------

_FUNCTIONS = (
    ("quat_from_matrix", ("R",), ref.quat_from_matrix, QuatCheck(),
     quat_from_matrix_random, quat_from_matrix_edges, quat_from_matrix_hidden),
    ("matrix_from_quat", ("q",), ref.matrix_from_quat, MatrixCheck(),
     matrix_from_quat_random, matrix_from_quat_edges, matrix_from_quat_hidden),
    ("quat_from_axis_angle", ("axis", "angle"), ref.quat_from_axis_angle, QuatCheck(),
     axis_angle_random, axis_angle_edges, axis_angle_hidden),
    ("matrix_from_euler", ("angles", "order"), ref.matrix_from_euler, MatrixCheck(),
     euler_random, euler_edges, euler_hidden),
    ("quat_mul", ("a", "b"), ref.quat_mul, QuatCheck(), mul_random, mul_edges, mul_hidden),
    ("slerp", ("q0", "q1", "t"), ref.slerp, QuatCheck(), slerp_random, slerp_edges,
     slerp_hidden),
)

ASSIGNMENT = Assignment(
    key="a1",
    title="Rotations",
    template="a1_rotations.py",
    functions=tuple(Function(name, params, reference, check)
                    for name, params, reference, check, *_ in _FUNCTIONS),
    tests=tuple(test for name, *_, random, edges, hidden in _FUNCTIONS
                for test in random_edge_hidden(name, random, edges, hidden)),
    misconceptions=MISCONCEPTIONS,
)
