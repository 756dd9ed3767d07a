"""Issue 18, items 11-14: rotations, Motion and BVH give a right answer or a clear error for
every input. One regression test per fault (each failed before its fix); rotations are checked
against scipy and closed forms, q and -q count as equal."""

from __future__ import annotations

import inspect
import tracemalloc
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rotation_asserts import assert_quat_equal
from scipy.spatial.transform import Rotation
from test_bvh_errors import GOOD

import course.rotations as rot
from course.bvh import BVHError, format_bvh, load_bvh, parse_bvh
from course.motion import MIN_FRAME_TIME, Motion
from course.skeleton import Skeleton

unit_quats = st.tuples(*[st.floats(-1, 1)] * 4).filter(lambda q: np.linalg.norm(q) > 0.1).map(
    lambda q: np.array(q) / np.linalg.norm(q)
)
unit_vectors = st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1).map(
    lambda v: np.array(v) / np.linalg.norm(v)
)


# ------------------------------------------------------------ 11. rotations: huge, tiny, ±pi
def test_normalize_the_issues_huge_quaternion():
    """Item 11: |q|^2 overflowed, so q / |q| was zeros and the matrix the identity."""
    np.testing.assert_allclose(rot.quat_normalize([1e155, 1e155, 0, 0]), [0.5**0.5] * 2 + [0, 0])
    quarter_about_x = Rotation.from_rotvec([np.pi / 2, 0, 0]).as_matrix()
    np.testing.assert_allclose(rot.matrix_from_quat([1e155, 1e155, 0, 0]), quarter_about_x,
                               atol=1e-15)


@settings(max_examples=100, derandomize=True, deadline=None)
@given(unit_quats, st.integers(-11, 307), unit_vectors)
def test_scale_of_a_quaternion_or_direction_never_matters(q, exponent, v):
    """Item 11: any non-zero finite length, 1e-11 to 1e307, means the same rotation and the
    same direction (norms are taken after scaling by the largest component)."""
    s = 10.0**exponent
    assert_quat_equal(rot.quat_normalize(s * q), q, atol=1e-14)
    np.testing.assert_allclose(rot.matrix_from_quat(s * q), rot.matrix_from_quat(q), atol=1e-14)
    assert_quat_equal(rot.quat_from_axis_angle(s * v, 1.0), rot.quat_from_axis_angle(v, 1.0),
                      atol=1e-14)
    assert_quat_equal(rot.quat_between(s * v, [0, 0, 1]), rot.quat_between(v, [0, 0, 1]),
                      atol=1e-14)
    assert_quat_equal(rot.slerp(s * q, q, 0.5), q, atol=1e-7)
    if abs(exponent) <= 150:  # q^-1 = q* / |q|^2 itself under- or overflows beyond
        np.testing.assert_allclose(rot.quat_inverse(s * q) * s, rot.quat_conjugate(q),
                                   rtol=1e-14, atol=1e-15)


@settings(max_examples=100, derandomize=True, deadline=None)
@given(unit_vectors, st.floats(-300, -13))
def test_tiny_rotations_keep_their_axis_and_angle(axis, log_angle):
    """Item 11: a 3e-162 rad turn had an axis of length 0.71 and an angle 40 % off (|v|^2
    underflowed). Tiny turns now come back exactly, through every representation."""
    theta = 10.0**log_angle
    q = rot.quat_from_rotvec(theta * axis)
    np.testing.assert_allclose(q[1:], np.sin(theta / 2) * axis, rtol=1e-14, atol=1e-300)
    got_axis, got_angle = rot.axis_angle_from_quat(q)
    np.testing.assert_allclose(got_axis, axis, rtol=1e-12, atol=1e-15)
    assert got_angle == pytest.approx(theta, rel=1e-12)
    np.testing.assert_allclose(rot.rotvec_from_quat(q) / theta, axis, rtol=1e-12, atol=1e-15)
    R = rot.matrix_from_rotvec(theta * axis)  # R - I = theta [axis]x to first order
    np.testing.assert_allclose((R - np.eye(3)) / theta, rot.skew(axis), atol=1e-12)
    assert rot.quat_angle(q, [1, 0, 0, 0]) == pytest.approx(theta, rel=1e-9)


def test_rotation_vector_too_long_for_a_float_is_refused():
    with pytest.raises(ValueError, match="^rotvec: has a length beyond the largest float"):
        rot.quat_from_rotvec([1.5e308, 1.5e308, 0])


@st.composite
def near_half_turns(draw) -> np.ndarray:
    """Quaternions a rounding error away from the identity or a half turn about x, y or z,
    with perturbations of either sign: where angle wrapping rounds to the wrong end."""
    q = np.eye(4)[draw(st.integers(0, 3))]
    tiny = [draw(st.sampled_from([-1, 0, 1])) * 10.0 ** draw(st.floats(-20, -13))
            for _ in range(4)]
    return q + np.array(tiny)


@settings(max_examples=300, derandomize=True, deadline=None)
@given(near_half_turns(), st.sampled_from(rot.EULER_ORDERS), st.booleans())
def test_every_returned_angle_is_in_its_documented_range(q, order, degrees):
    """Item 11: euler_from_quat returned exactly +pi where [-pi, pi) is documented. Every
    angle-returning function is checked against its docstring's range."""
    half = 180.0 if degrees else np.pi
    angles = rot.euler_from_quat(q, order, degrees=degrees)
    assert -half <= angles[0] < half and -half <= angles[2] < half
    proper = order[0].lower() == order[2].lower()
    lo, hi = (0.0, half) if proper else (-half / 2, half / 2)
    assert lo <= angles[1] <= hi
    from_matrix = rot.euler_from_matrix(rot.matrix_from_quat(q), order, degrees=degrees)
    assert -half <= from_matrix[0] < half and -half <= from_matrix[2] < half
    np.testing.assert_allclose(
        rot.matrix_from_euler(angles, order, degrees=degrees), rot.matrix_from_quat(q),
        atol=1e-12,
    )
    _, angle = rot.axis_angle_from_quat(q, degrees=degrees)
    assert 0 <= angle <= half
    assert 0 <= np.linalg.norm(rot.rotvec_from_quat(q, degrees=degrees)) <= half
    assert 0 <= rot.quat_angle(q, [1, 0, 0, 0]) <= np.pi
    assert 0 <= rot.gimbal_lock_distance(angles, order, degrees=degrees) <= half / 2


def test_the_issues_plus_pi():
    q = [0.0, 0.0, 1.0, -1.6564358373827217e-15]  # a half turn about y, rounded
    angles = rot.euler_from_quat(q, "XYZ")
    assert angles[2] == -np.pi  # was +pi
    assert rot.euler_from_quat(q, "XYZ", degrees=True)[2] == -180.0


# Good arguments by parameter name, for calling every public rotation function.
_Q = np.array([0.9, 0.1, -0.3, 0.2])
GOOD_ARGS = {
    "q": _Q, "a": _Q, "b": _Q, "q0": _Q, "q1": _Q[::-1].copy(),
    "v": np.array([0.3, -1.0, 2.0]), "u": np.array([1.0, 0.5, 0.0]),
    "axis": np.array([0.0, 0.6, 0.8]), "angle": np.array(0.7),
    "rotvec": np.array([0.1, 0.2, 0.3]), "angles": np.array([0.1, 0.2, 0.3]),
    "R": rot.matrix_from_quat(_Q), "x0": np.array([1.0, 2.0]), "x1": np.array([3.0, 4.0]),
    "t": np.array(0.25), "tol": np.array(0.01), "order": "ZYX",
}
ARRAY_PARAMS = set(GOOD_ARGS) - {"order"}


def _public_calls() -> list[tuple[str, str]]:
    """(function, array parameter) for every public rotation function whose required
    parameters all have a good value above."""
    calls = []
    for name in rot.__all__:
        f = getattr(rot, name)
        if not inspect.isfunction(f):
            continue
        params = inspect.signature(f).parameters.values()
        required = {p.name for p in params if p.default is inspect.Parameter.empty}
        if required <= set(GOOD_ARGS):
            calls += [(name, p.name) for p in params if p.name in ARRAY_PARAMS]
    return calls


CALLS = _public_calls()


def test_the_non_real_input_check_covers_every_public_rotation_function():
    covered = {f for f, _ in CALLS}
    assert covered >= {
        "quat_mul", "quat_conjugate", "quat_inverse", "quat_normalize", "quat_canonical",
        "quat_rotate", "matrix_from_quat", "quat_from_matrix", "quat_from_axis_angle",
        "axis_angle_from_quat", "matrix_from_axis_angle", "axis_angle_from_matrix",
        "quat_from_rotvec", "rotvec_from_quat", "matrix_from_rotvec", "rotvec_from_matrix",
        "matrix_from_euler", "quat_from_euler", "euler_from_quat", "euler_from_matrix",
        "gimbal_lock_distance", "is_gimbal_lock", "lerp", "nlerp", "slerp", "quat_angle",
        "quat_between", "skew",
    }


def _non_real(x: np.ndarray) -> dict[str, object]:
    """``x`` as complex numbers, numeric strings, dates, time spans and objects."""
    ticks = np.round(x * 1000).astype(np.int64)
    return {
        "complex": x + 0.5j,
        "complex with zero imaginary parts": x.astype(complex),
        "numeric strings": x.astype(str),
        "datetime64": ticks.astype("datetime64[ms]"),
        "timedelta64": ticks.astype("timedelta64[ms]"),
        "objects": np.where(np.ones(x.shape, bool), None, x),
    }


@pytest.mark.parametrize(("function", "param"), CALLS)
def test_non_real_input_is_refused_by_name(function, param):
    """Item 11: complex input lost its imaginary part with only a warning; "1.5" and
    datetime64 were read as numbers. Each is a ValueError naming the argument, no warning."""
    f = getattr(rot, function)
    names = inspect.signature(f).parameters
    args = {k: v for k, v in GOOD_ARGS.items() if k in names}
    f(**args)  # the good call works
    for kind, bad in _non_real(args[param]).items():
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(ValueError, match=rf"^{param}: expected numbers, got") as caught:
                f(**(args | {param: bad}))
        assert "object" in kind or kind.split()[0] in str(caught.value) or "str" in kind


def test_big_ints_and_fractions_are_real_numbers():
    from fractions import Fraction

    np.testing.assert_allclose(rot.quat_normalize([2**70, 0, 0, Fraction(0)]), [1, 0, 0, 0])
    with pytest.raises(ValueError, match=r"^angles: expected numbers, got str at index \(1,\)"):
        rot.quat_from_euler(np.array([0.1, "x", 0.3], dtype=object), "XYZ")
    with pytest.raises(ValueError, match="^shape: expected a non-negative int"):
        rot.quat_identity("3")


# ------------------------------------------------------------------------------ 12. Motion
def _arm() -> Skeleton:
    return Skeleton(["Root", "Upper", "Upper_end"], [-1, 0, 1], [[0, 0, 0], [0, 2, 0], [1, 0, 0]])


def _motion_args(**changes) -> dict:
    rotations = np.tile([1.0, 0, 0, 0], (4, 3, 1))
    return {"skeleton": _arm(), "local_rotations": rotations, "root_positions": np.zeros((4, 3)),
            "frame_time": 0.1} | changes


@settings(max_examples=100, derandomize=True, deadline=None)
@given(st.integers(0, 3), st.integers(0, 2), st.floats(-0.5, 0.5), unit_quats)
def test_motion_refuses_zero_and_non_unit_rotations(frame, joint, log_scale, q):
    """Item 12: a zero or non-unit rotation was accepted and only saving failed, much later.
    Now it is refused at once with its frame and joint; float32 noise is accepted."""
    rotations = np.tile([1.0, 0, 0, 0], (4, 3, 1))
    rotations[frame, joint] = q * 10.0**log_scale
    names = _arm().names
    if abs(10.0**log_scale - 1) > 1e-6:
        with pytest.raises(ValueError, match=rf"^local_rotations: frame {frame}, joint "
                                             rf"'{names[joint]}' is not a unit quaternion"):
            Motion(**_motion_args(local_rotations=rotations))
    rotations[frame, joint] = q.astype(np.float32)  # float32 rounding: ~1e-7 off unit
    Motion(**_motion_args(local_rotations=rotations))
    rotations[frame, joint] = 0.0
    with pytest.raises(ValueError, match=rf"frame {frame}, joint '{names[joint]}' is the zero"):
        Motion(**_motion_args(local_rotations=rotations))


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"frame_time": "abc"}, r"^frame_time: expected a number of seconds, got str"),
        ({"frame_time": "0.1"}, r"^frame_time: expected a number of seconds, got str"),
        ({"frame_time": 0.1 + 0j}, r"^frame_time: expected a number of seconds, got complex"),
        ({"frame_time": None}, r"^frame_time: expected a number of seconds, got NoneType"),
        ({"frame_time": [0.1]}, r"^frame_time: expected a number of seconds, got list"),
        ({"frame_time": 5e-324}, r"^frame_time: must be a positive number of seconds, at least"),
        ({"frame_time": -0.1}, r"^frame_time: must be a positive number of seconds"),
        ({"skeleton": None}, r"^skeleton: expected a course.skeleton.Skeleton, got NoneType"),
        ({"skeleton": "arm"}, r"^skeleton: expected a course.skeleton.Skeleton, got str"),
        ({"root_positions": np.zeros((4, 3)).astype(str)}, r"^root_positions: expected numbers"),
        ({"local_rotations": np.tile([1 + 0j, 0, 0, 0], (4, 3, 1))},
         r"^local_rotations: expected numbers, got complex"),
        ({"translations": np.zeros((4, 3, 3)).astype("datetime64[s]")},
         r"^translations: expected numbers, got dates"),
    ],
)
def test_motion_errors_name_the_argument(changes, message):
    """Item 12: frame_time="abc" and Motion(None, ...) raised errors naming nothing."""
    with pytest.raises(ValueError, match=message):
        Motion(**_motion_args(**changes))


def test_motion_takes_numpy_seconds_and_owns_its_arrays():
    rotations = np.tile([1.0, 0, 0, 0], (4, 3, 1))
    motion = Motion(**_motion_args(local_rotations=rotations, frame_time=np.float32(0.25)))
    assert motion.frame_time == 0.25 and type(motion.frame_time) is float
    rotations[0, 0] = 0.0
    assert motion.local_rotations[0, 0, 0] == 1.0
    assert Motion(**_motion_args(frame_time=np.array(MIN_FRAME_TIME))).fps == pytest.approx(1e6)


# ------------------------------------------------------------ 13. BVH: bounded allocations
STATIC = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\n}\nMOTION\nFrames: %s\nFrame Time: 0.1\n"


@pytest.mark.parametrize("frames", ["10000000", str(10**12)])
def test_a_tiny_file_cannot_declare_millions_of_frames(frames):
    """Item 13: a 60-byte file without channels allocated 305 MiB (10**12 frames: MemoryError).
    Each frame of a skeleton without channels is an empty line, which the file must hold."""
    tracemalloc.start()
    try:
        with pytest.raises(BVHError, match=f"'Frames:' says {frames}, the file ends after 0"):
            parse_bvh(STATIC % frames)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 100_000


def test_a_frame_count_of_thousands_of_digits_is_a_bvh_error():
    """Item 13: past 4300 digits int() raised a plain ValueError without the line."""
    with pytest.raises(BVHError, match="frame count '9999.* is not a whole number below") as c:
        parse_bvh(STATIC % ("9" * 5000))
    assert c.value.line == 7
    assert parse_bvh(STATIC % ("0" * 30 + "1") + "\n").n_frames == 1


@settings(max_examples=60, derandomize=True, deadline=None)
@given(st.integers(0, 10**15), st.integers(0, 6), st.booleans())
def test_allocation_is_bounded_by_the_file(declared, lines, channels):
    """Item 13, as a property: whatever Frames: says, the reader allocates in proportion to
    the lines the file holds, and loads exactly the declared frames or refuses."""
    text = STATIC % declared
    if channels:
        text = text.replace("OFFSET 0 0 0\n", "OFFSET 0 0 0\nCHANNELS 1 Zrotation\n")
    text += ("5\n" if channels else "\n") * lines
    tracemalloc.start()
    try:
        try:
            motion = parse_bvh(text)
        except BVHError as error:
            assert declared > lines and error.line == text.count("\n")
        else:
            assert declared <= lines and motion.n_frames == declared
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 100_000


def test_frames_of_a_skeleton_without_channels_are_empty_lines():
    assert parse_bvh(STATIC % 2 + "\n\n\n").n_frames == 2  # a blank line to spare is fine
    with pytest.raises(BVHError, match="frame 1 has 2 values, expected 0") as caught:
        parse_bvh(STATIC % 2 + "\n1 2\n")
    assert caught.value.line == 10


# --------------------------------------------------------------- 14. BVH: ASCII, lines, saving
BAD_DIGITS = ["1_0", "\u0661\u0660", "\uff11\uff10", "\u0967", "1__0"]  # 10, Arabic-Indic, ...


@settings(max_examples=60, derandomize=True, deadline=None)
@given(st.integers(0, 29), st.integers(0, 8), st.sampled_from(BAD_DIGITS))
def test_a_bad_frame_token_is_reported_on_its_own_line(frame, column, token):
    """Item 14: '1_0' and non-ASCII digits were reported at the first frame line (line 188
    for a token on line 503), since Python's float() reads them and numpy does not."""
    head, rows = GOOD.split("Frames: 2\n")[0], ["1 2 3 10 20 30 40 50 60"] * 30
    values = rows[frame].split()
    values[column] = token
    rows[frame] = " ".join(values)
    text = head + "Frames: 30\nFrame Time: 0.5\n" + "\n".join(rows) + "\n"
    with pytest.raises(BVHError, match=f"frame {frame}: {token!r} is not a number") as caught:
        parse_bvh(text)
    assert caught.value.line == 19 + frame
    python_reads_it = token != "1__0"  # the message says why float() is not the rule
    assert ("ASCII" in caught.value.problem) == python_reads_it


@pytest.mark.parametrize("token", BAD_DIGITS)
@pytest.mark.parametrize(
    ("line", "old", "phrase"),
    [(8, "5", "OFFSET of joint 'Chest' is not three numbers"), (9, "3", "count"),
     (17, "2", "frame count"), (18, "0.5", "Frame Time")],
)
def test_header_numbers_are_ascii_only(token, line, old, phrase):
    """Item 14: those spellings were accepted in OFFSET, Frames: and Frame Time:."""
    lines = GOOD.splitlines()
    lines[line - 1] = lines[line - 1].replace(old, token, 1)
    with pytest.raises(BVHError, match=phrase) as caught:
        parse_bvh("\n".join(lines))
    assert caught.value.line == line


@pytest.mark.parametrize("separator", ["\x0b", "\x0c", "\x1c", "\x85", "\u2028", "\u2029"])
def test_only_newlines_end_lines(separator):
    """Item 14: line numbers followed str.splitlines, so \\x0b or \\u2028 shifted them. They
    are whitespace inside a line now; only \\n, \\r\\n and \\r end one."""
    text = GOOD.replace("OFFSET 0 0 0", f"OFFSET 0 0{separator}0").replace("x31", "x31")
    text = text.replace("4 5 6 11 21 31", "4 5 6 11 21 x31")  # an error on line 20
    for ending in ("\n", "\r\n", "\r"):
        with pytest.raises(BVHError, match="'x31' is not a number") as caught:
            parse_bvh(text.replace("\n", ending))
        assert caught.value.line == 20
    assert parse_bvh(GOOD.replace("OFFSET 0 0 0", f"OFFSET 0 0{separator}0")).n_frames == 2


def test_parse_bvh_strips_a_leading_byte_order_mark(tmp_path):
    """Item 14: load_bvh dropped a BOM, parse_bvh did not ('unknown keyword')."""
    with_bom = "\ufeff" + GOOD
    file = tmp_path / "bom.bvh"
    file.write_text(with_bom, encoding="utf-8")
    a, b = parse_bvh(with_bom), load_bvh(file)
    np.testing.assert_array_equal(a.local_rotations, b.local_rotations)
    assert a.skeleton.names == b.skeleton.names


@pytest.mark.parametrize("frame_time", ["5e-324", "1e-7", "0", "-0.5", "inf", "nan", "1e999"])
def test_frame_time_must_be_a_recording(frame_time):
    """Item 14: 'Frame Time: 5e-324' was accepted (infinite fps); non-positive, sub-microsecond
    and non-finite frame times are refused with their line."""
    with pytest.raises(BVHError, match="is not a positive number of seconds") as caught:
        parse_bvh(GOOD.replace("Frame Time: 0.5", f"Frame Time: {frame_time}"))
    assert caught.value.line == 18
    assert parse_bvh(GOOD.replace("Frame Time: 0.5", "Frame Time: 1e-6")).frame_time == 1e-6


def _deep_chain(depth: int) -> str:
    lines = ["HIERARCHY", "ROOT J0", "{", "OFFSET 0 0 0", "CHANNELS 1 Zrotation"]
    for j in range(1, depth):
        lines += [f"JOINT J{j}", "{", "OFFSET 0 1 0", "CHANNELS 1 Zrotation"]
    lines += ["}"] * depth + ["MOTION", "Frames: 1", "Frame Time: 0.1", "5 " * depth]
    return "\n".join(lines) + "\n"


def test_saved_size_is_linear_in_the_depth():
    """Item 14: an 8000-deep chain was saved in 160 MB (a tab per level on every line)."""
    sizes = {depth: len(format_bvh(parse_bvh(_deep_chain(depth)))) for depth in (300, 1200)}
    assert sizes[1200] / sizes[300] < 4.5  # quadratic growth made it 15
    again = parse_bvh(format_bvh(parse_bvh(_deep_chain(1200))))
    assert again.skeleton.depth("J1199") == 1199
    np.testing.assert_allclose(again.local_rotations[0, -1],
                               [np.cos(np.radians(2.5)), 0, 0, np.sin(np.radians(2.5))])


def test_ordinary_files_are_saved_as_before(shared_bvh_dir):
    """Item 14: every hierarchy line of a real clip is indented by its depth, one tab a level,
    as before the cap."""
    motion = load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")
    text = format_bvh(motion)
    depth = 0
    for line in text.split("MOTION")[0].splitlines()[1:]:
        body = line.lstrip("\t")
        if body == "}":
            depth -= 1
        assert line == "\t" * depth + body
        if body == "{":
            depth += 1
    assert depth == 0
