r"""Assignment a2, forward kinematics: the spec ``assignments/a2_forward_kinematics.py`` is
checked by.

Three functions and a bonus: ``parse_bvh_hierarchy(text)`` (the hierarchy section of a BVH
file, sent as a string), ``forward_kinematics`` (:math:`Q_i = Q_{p(i)} R_i`,
:math:`p_i = p_{p(i)} + Q_{p(i)} l_i`), ``local_from_global`` (:math:`R_i = Q_{p(i)}^{-1} Q_i`)
and, for bonus points, ``pose_from_frame`` (one MOTION line to the root position and local
rotations: channel order, degrees).

The scored cases are the same on every machine: the wave clip shipped with the package, three
sample files generated here in the style of the BVH edge cases real readers trip over (the
root's rotation channels before its position, mixed rotation orders; leaves with CHANNELS but
no End Site; CRLF line endings), and generated hierarchies and poses. The real clips a machine
has locally (the CMU walk and the edge-case files of the shared data folder) add unscored
tests, reported as such. Reference: :mod:`course.bvh` and :mod:`course.fk`.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from typing import Any

import numpy as np

from course import rotations as rot
from course.bvh import parse_bvh
from course.fk import forward_kinematics as ref_fk
from course.fk import local_from_global as ref_local
from course.motion import Motion, is_end_site

from ..checks import IndexCheck, PointsCheck, QuatCheck, StringsCheck, TupleCheck
from ..spec import Assignment, Case, Function, Misconception, Picture, Test

# --- hierarchies: sample files, real ones, generated ones -------------------------------------

EMPTY_MOTION = "MOTION\nFrames: 0\nFrame Time: 0.01\n"


def hierarchy_of(text: str) -> str:
    """The hierarchy section of a BVH file: everything before the ``MOTION`` line (line
    endings kept as they are, CRLF included)."""
    at = text.find("MOTION")
    return text if at < 0 else text[:at]


def parse_reference(text: str) -> tuple[list[str], np.ndarray, np.ndarray]:
    motion = parse_bvh(text if "MOTION" in text else text + EMPTY_MOTION, source="hierarchy")
    sk = motion.skeleton
    return list(sk.names), np.asarray(sk.parents, dtype=np.int64), np.array(sk.offsets)


@cache
def sample_files() -> tuple[tuple[str, str], ...]:
    """``(label, file text)`` of the files every machine has: the packaged wave clip and three
    generated in the style of the BVH edge cases (see the module's docstring), with motion."""
    from importlib.resources import files

    wave = (files("course.data") / "samples" / "wave.bvh").read_text(encoding="utf-8")
    rng = np.random.default_rng(105)  # fixed: these files are the same everywhere
    styles: tuple[tuple[str, dict[str, Any]], ...] = (
        ("the root's rotation channels before its position, mixed orders",
         {"n": 5, "rotation_first": True, "newline": "\n"}),
        ("leaves with CHANNELS but no End Site, tabs", {"n": 7, "end_sites": False,
                                                        "indent": "\t", "newline": "\n"}),
        ("CRLF line endings", {"n": 20, "newline": "\r\n"}),
    )
    out = [("the packaged wave clip", wave)]
    for label, style in styles:
        text = random_hierarchy(rng, **style)
        out.append((f"sample file: {label}", with_motion(rng, text, frames=12)))
    return tuple(out)


@cache
def local_clips() -> tuple[tuple[str, str], ...]:
    """``(label, file text)`` of the real clips this machine has locally (none offline): the
    CMU walk and the edge-case files of the shared data folder. Only unscored tests use them,
    so scores never depend on the machine."""
    from course import data

    found = []
    try:
        found.append(("the CMU walk (12_01)", data.path("cmu_12_01_walk", download=False)))
    except Exception:  # offline and no mirror
        pass
    edge = data.mirror_dir() / "edge_cases"
    found += [(f"edge case {p.name}", p) for p in sorted(edge.glob("*.bvh"))]
    return tuple((label, p.read_bytes().decode("utf-8-sig")) for label, p in found)


@cache
def clip_motion(label: str) -> Motion:
    return parse_bvh(dict(sample_files() + local_clips())[label], source=label)


NAMES = ("Hips", "Spine", "Chest", "Neck", "Head", "Shoulder", "Arm", "ForeArm", "Hand",
         "Finger", "UpLeg", "Leg", "Foot", "Toe", "Tail", "Wing", "Ear", "Jaw")
ORDERS = ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX")


def _number(rng: np.random.Generator, x: float) -> str:
    """``x`` written as exporters do: fixed decimals, short, or in exponent form."""
    return str(rng.choice([f"{x:.6f}", f"{x:g}", f"{x:.4e}", f"{x:.2f}"]))


def random_parents(rng: np.random.Generator, n: int) -> np.ndarray:
    """A random tree of ``n`` joints, parents before children, bushy or chain-like."""
    parents = [-1]
    for j in range(1, n):
        parents.append(j - 1 if rng.random() < 0.55 else int(rng.integers(0, j)))
    return np.array(parents, dtype=np.int64)


def random_hierarchy(rng: np.random.Generator, n: int, *, rotation_first: bool | None = None,
                     end_sites: bool | None = None, indent: str | None = None,
                     newline: str | None = None) -> str:
    """The hierarchy text of a random tree of ``n`` joints: random names, offsets with every
    number format, random rotation orders, the root's rotation channels sometimes before
    its position channels, leaves with or without an End Site, tabs or spaces, LF or CRLF
    (each keyword fixes one of these choices instead of drawing it)."""
    parents = random_parents(rng, n)
    children = [[c for c in range(n) if parents[c] == j] for j in range(n)]
    used: set[str] = set()

    def name() -> str:
        while True:
            side = rng.choice(["", "Left", "Right", "L_", "R_"])
            s = f"{side}{rng.choice(NAMES)}{rng.choice(['', str(rng.integers(1, 9))])}"
            if s not in used:
                used.add(s)
                return s

    indent = indent or rng.choice(["\t", "  ", "    "])
    out: list[str] = ["HIERARCHY"]

    def offset(depth: int) -> str:
        v = rng.normal(0, 5, 3) * (rng.random(3) < 0.8)
        return f"{indent * depth}OFFSET " + " ".join(_number(rng, float(x)) for x in v)

    def joint(j: int, depth: int) -> None:
        pad = indent * depth
        out.append(f"{pad}{'ROOT' if j == 0 else 'JOINT'} {name()}")
        out.append(f"{pad}{{")
        out.append(offset(depth + 1))
        rotation = [f"{a}rotation" for a in rng.choice(ORDERS)]
        if j == 0:
            position = ["Xposition", "Yposition", "Zposition"]
            first = rng.random() < 0.3 if rotation_first is None else rotation_first
            chans = rotation + position if first else position + rotation
        else:
            chans = rotation
        out.append(f"{pad}{indent}CHANNELS {len(chans)} {' '.join(chans)}")
        for c in children[j]:
            joint(c, depth + 1)
        if not children[j] and (rng.random() < 0.7 if end_sites is None else end_sites):
            out.extend([f"{pad}{indent}End Site", f"{pad}{indent}{{", offset(depth + 2),
                        f"{pad}{indent}}}"])
        out.append(f"{pad}}}")

    joint(0, 0)
    newline = newline or ("\r\n" if rng.random() < 0.3 else "\n")
    return newline.join(out) + newline


def with_motion(rng: np.random.Generator, text: str, frames: int) -> str:
    """A hierarchy with a MOTION section of ``frames`` random frames, in its line endings."""
    newline = "\r\n" if "\r\n" in text else "\n"
    lines = [" ".join(f"{v:.4f}" for v in _random_frame(rng, text)) for _ in range(frames)]
    return text + newline.join(["MOTION", f"Frames: {frames}", "Frame Time: 0.0333333", *lines,
                                ""])


# --- cases per function ------------------------------------------------------------------------


def parse_samples(rng: np.random.Generator) -> list[Case]:
    return [Case(label, (hierarchy_of(text),)) for label, text in sample_files()]


def parse_local(rng: np.random.Generator) -> list[Case]:
    return [Case(label, (hierarchy_of(text),)) for label, text in local_clips()]


def parse_generated(rng: np.random.Generator) -> list[Case]:
    return [Case(f"generated hierarchy #{i + 1} ({n} joints)", (random_hierarchy(rng, n),))
            for i, n in enumerate((1, 2, 4, 7, 12, 20))]


def parse_hidden(rng: np.random.Generator) -> list[Case]:
    return [Case(f"hidden hierarchy #{i + 1}", (random_hierarchy(rng, int(rng.integers(2, 28))),))
            for i in range(12)]


def _quats(rng: np.random.Generator, n: int, spread: float = np.pi) -> np.ndarray:
    axes = rng.normal(size=(n, 3))
    q = rot.quat_from_axis_angle(axes / np.linalg.norm(axes, axis=-1, keepdims=True),
                                 rng.uniform(-spread, spread, n))
    signed: np.ndarray = q * rng.choice([-1.0, 1.0], (n, 1))  # q and -q are one rotation
    return signed


def _random_pose(
    rng: np.random.Generator, n: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    parents = random_parents(rng, n)
    offsets = rng.normal(0, 3, (n, 3))
    return parents, offsets, _quats(rng, n), rng.normal(0, 10, 3)


def _clip_frames(rng: np.random.Generator, per_clip: int,
                 clips: Callable[[], tuple[tuple[str, str], ...]] = sample_files) -> list[Case]:
    out: list[Case] = []
    for label, _ in clips():
        m = clip_motion(label)
        frames = np.unique(np.r_[0, rng.integers(0, m.n_frames, per_clip - 1)])
        sk = m.skeleton
        out += [Case(f"{label}, frame {f}", (np.asarray(sk.parents, dtype=np.int64),
                                             np.array(sk.offsets), m.local_rotations[f].copy(),
                                             m.root_positions[f].copy())) for f in frames]
    return out


def fk_samples(rng: np.random.Generator) -> list[Case]:
    return _clip_frames(rng, 3)


def fk_local(rng: np.random.Generator) -> list[Case]:
    return _clip_frames(rng, 3, local_clips)


def fk_random(rng: np.random.Generator) -> list[Case]:
    chain = np.arange(-1, 5, dtype=np.int64)
    ones = np.tile([1.0, 0, 0, 0], (6, 1))
    straight = np.tile([0.0, 1.0, 0.0], (6, 1))
    turn = rot.quat_from_axis_angle(np.array([0.0, 1.0, 0.0]), np.pi / 2)
    spin = ones.copy()
    spin[0] = turn
    return [
        *(Case(f"random tree and pose #{i + 1} ({n} joints)", _random_pose(rng, n))
          for i, n in enumerate((3, 8, 15))),
        Case("one joint: p_0 is the root position", (np.array([-1], dtype=np.int64),
                                                     np.zeros((1, 3)), _quats(rng, 1),
                                                     np.array([1.0, 2.0, 3.0]))),
        Case("identity rotations: the rest pose, p_i = p_parent + l_i",
             (chain, straight, ones, np.zeros(3))),
        Case("only the root turns (90° about y): the whole chain swings",
             (chain, rng.normal(0, 1, (6, 3)), spin, np.array([0.0, 1.0, 0.0]))),
        Case("rotations with w < 0", (chain, rng.normal(0, 1, (6, 3)),
                                      -np.abs(_quats(rng, 6)), np.zeros(3))),
    ]


def fk_hidden(rng: np.random.Generator) -> list[Case]:
    return [*_clip_frames(rng, 2),
            *(Case(f"hidden tree and pose #{i + 1}", _random_pose(rng, int(rng.integers(2, 30))))
              for i in range(10))]


def _orientation_case(label: str, parents: np.ndarray, offsets: np.ndarray, quats: np.ndarray,
                      root: np.ndarray) -> Case:
    _, Q = ref_fk(parents, offsets, rot.quat_normalize(quats), root)
    return Case(label, (np.asarray(parents, dtype=np.int64), np.array(Q)))


def local_random(rng: np.random.Generator) -> list[Case]:
    return [_orientation_case(c.label.replace("frame", "orientations of frame"), *c.args)
            for c in _clip_frames(rng, 2)[:4]] + [
        _orientation_case(f"orientations of a random pose #{i + 1}", *_random_pose(rng, n))
        for i, n in enumerate((4, 9, 16))]


def local_edges(rng: np.random.Generator) -> list[Case]:
    chain = np.arange(-1, 4, dtype=np.int64)
    q = _quats(rng, 1)[0]
    return [
        Case("one joint: R_0 = Q_0", (np.array([-1], dtype=np.int64), _quats(rng, 1))),
        Case("all joints turned alike: only the root rotates, R_i = identity below it",
             (chain, np.tile(q, (5, 1)))),
        Case("orientations given with w < 0", (chain, -np.abs(_quats(rng, 5)))),
        Case("a bushy tree (several children per joint)",
             (np.array([-1, 0, 0, 0, 1, 1, 2], dtype=np.int64), _quats(rng, 7))),
    ]


def local_hidden(rng: np.random.Generator) -> list[Case]:
    return [_orientation_case(f"hidden pose #{i + 1}", *_random_pose(rng, int(rng.integers(2, 30))))
            for i in range(10)]


def pose_reference(text: str, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    line = " ".join(repr(float(v)) for v in frame)
    m = parse_bvh(f"{hierarchy_of(text)}MOTION\nFrames: 1\nFrame Time: 0.01\n{line}\n",
                  source="frame")
    return m.root_positions[0].copy(), m.local_rotations[0].copy()


def _random_frame(rng: np.random.Generator, text: str) -> np.ndarray:
    channels = parse_bvh(hierarchy_of(text) + EMPTY_MOTION).channels
    assert channels is not None  # parse_bvh records every joint's channels
    chans = [c for cs in channels for c in cs]
    return np.array([rng.normal(0, 20) if c.endswith("position") else rng.uniform(-180, 180)
                     for c in chans])


def pose_visible(rng: np.random.Generator) -> list[Case]:
    out = []
    for label, text in sample_files():
        m = parse_bvh(text, source=label)
        f = int(rng.integers(1, m.n_frames))
        line = _motion_line(text, f)
        out.append(Case(f"{label}, frame {f}", (hierarchy_of(text), line)))
    for i, n in enumerate((3, 6, 10)):
        text = random_hierarchy(rng, n)
        out.append(Case(f"generated hierarchy #{i + 1}, random angles", (text,
                                                                         _random_frame(rng, text))))
    return out


def _motion_line(text: str, frame: int) -> np.ndarray:
    lines = text[text.find("MOTION"):].splitlines()
    data = [ln for ln in lines[3:] if ln.strip()]
    return np.array([float(v) for v in data[frame].split()])


def pose_hidden(rng: np.random.Generator) -> list[Case]:
    out = []
    for i in range(8):
        text = random_hierarchy(rng, int(rng.integers(2, 16)))
        out.append(Case(f"hidden hierarchy #{i + 1}", (text, _random_frame(rng, text))))
    return out


# --- the catalogue of known mistakes -----------------------------------------------------------


def _fk_variant(parents: np.ndarray, offsets: np.ndarray, quats: np.ndarray, root: np.ndarray,
                *, compose_reversed: bool = False, own: bool = False,
                no_parent_position: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Forward kinematics with one of the classic slips, joint by joint."""
    quats = rot.quat_normalize(np.asarray(quats, dtype=float))
    n = len(parents)
    P, Q = np.zeros((n, 3)), np.zeros((n, 4))
    P[0], Q[0] = root, quats[0]
    for i in range(1, n):
        p = parents[i]
        Q[i] = rot.quat_mul(quats[i], Q[p]) if compose_reversed else rot.quat_mul(Q[p], quats[i])
        lever = rot.quat_rotate(Q[i] if own else Q[p], offsets[i])
        P[i] = lever if no_parent_position else P[p] + lever
    return P, Q


def _without_end_sites(text: str) -> tuple[list[str], np.ndarray, np.ndarray]:
    names, parents, offsets = parse_reference(text)
    sk = parse_bvh(hierarchy_of(text) + EMPTY_MOTION).skeleton
    keep = [j for j in range(sk.n_joints) if not is_end_site(sk, j)]
    index = {j: k for k, j in enumerate(keep)}
    return ([names[j] for j in keep], np.array([index.get(int(parents[j]), -1) for j in keep]),
            offsets[keep])


def _accumulated_offsets(text: str) -> tuple[list[str], np.ndarray, np.ndarray]:
    names, parents, offsets = parse_reference(text)
    rest = np.array(offsets)
    for j in range(1, len(parents)):
        rest[j] += rest[parents[j]]
    return names, parents, rest


def _euler_variant(text: str, frame: np.ndarray, *, always_xyz: bool = False,
                   by_name: bool = True, degrees: bool = True
                   ) -> tuple[np.ndarray, np.ndarray]:
    """``pose_from_frame`` with one slip: every joint composed as R_X R_Y R_Z whatever its
    CHANNELS order (``always_xyz``; each angle about the axis its channel names, or with
    ``by_name=False`` the three values in file order taken as x, y, z), or the angles left
    in degrees (``degrees=False``)."""
    motion = parse_bvh(hierarchy_of(text) + EMPTY_MOTION)
    assert motion.channels is not None  # parse_bvh records every joint's channels
    root, quats = pose_reference(text, frame)
    k = 0
    for j, chans in enumerate(motion.channels):
        values = frame[k:k + len(chans)]
        k += len(chans)
        axes = [(c[0].upper(), v) for c, v in zip(chans, values, strict=True)
                if c.endswith("rotation")]
        if len(axes) != 3:
            continue
        if always_xyz and by_name:
            axes = sorted(axes)
        order = "XYZ" if always_xyz else "".join(a for a, _ in axes)
        quats[j] = rot.quat_from_euler(np.array([v for _, v in axes]), order,
                                       degrees=degrees)
    return root, quats


MISCONCEPTIONS = (
    Misconception(
        "end_sites_dropped", "parse_bvh_hierarchy", "End Sites dropped",
        "Every `End Site { OFFSET ... }` is a joint too, the tip of a bone with no channels: add "
        "it as \"<Parent>_end\" with its parent and offset, or the hands, feet and head lose "
        "their last bone.",
        wrong=_without_end_sites),
    Misconception(
        "offsets_accumulated", "parse_bvh_hierarchy", "offsets added up along the tree",
        "OFFSET is the bone l_i in the parent's frame, relative to the parent; you returned "
        "rest-pose positions (the sum of offsets from the root), which forward kinematics adds "
        "up a second time in p_i = p_parent + Q_parent l_i.",
        wrong=_accumulated_offsets),
    Misconception(
        "reversed_product", "forward_kinematics", "Q_i = R_i Q_parent (the product reversed)",
        "A joint's orientation is its parent's followed by its own local rotation, "
        "Q_i = Q_parent R_i: the local rotation acts in the parent's frame, so it multiplies on "
        "the right.",
        wrong=lambda parents, offsets, quats, root: _fk_variant(
            parents, offsets, quats, root, compose_reversed=True)),
    Misconception(
        "own_orientation", "forward_kinematics", "the bone rotated by the joint's own orientation",
        "The bone l_i hangs from the parent, so the parent's orientation turns it: "
        "p_i = p_parent + Q_parent l_i, not Q_i l_i (a joint's own rotation moves its children).",
        wrong=lambda parents, offsets, quats, root: _fk_variant(
            parents, offsets, quats, root, own=True)),
    Misconception(
        "no_parent_position", "forward_kinematics", "positions not accumulated from the parent",
        "Each position is the parent's plus the turned bone, p_i = p_parent + Q_parent l_i; "
        "without p_parent every joint sits one bone away from the origin.",
        wrong=lambda parents, offsets, quats, root: _fk_variant(
            parents, offsets, quats, root, no_parent_position=True)),
    Misconception(
        "reversed_product", "local_from_global", "R_i = Q_i Q_parent⁻¹ (the product reversed)",
        "From Q_i = Q_parent R_i, the local rotation is R_i = Q_parent⁻¹ Q_i: the inverse "
        "multiplies on the left.",
        wrong=lambda parents, Q: np.array(
            [Q[0], *(rot.quat_mul(Q[i], rot.quat_inverse(Q[p]))
                     for i, p in enumerate(parents) if p >= 0)])),
    Misconception(
        "channel_order_ignored", "pose_from_frame", "channel order ignored (always XYZ)",
        "A joint's rotation is the product of its channels in the order the CHANNELS line lists "
        "them: \"Zrotation Yrotation Xrotation\" is R = R_Z(z) R_Y(y) R_X(x), intrinsic "
        "\"ZYX\"; you turned each angle about its own axis but always multiplied R_X R_Y R_Z.",
        wrong=lambda text, frame: _euler_variant(text, frame, always_xyz=True)),
    Misconception(
        "channel_axes_positional", "pose_from_frame", "the angles read as x, y, z in file order",
        "Each rotation channel names its axis: \"Zrotation Yrotation Xrotation\" gives the "
        "first value to z, R = R_Z(z) R_Y(y) R_X(x); you read the three values as x, y, z, "
        "whatever the CHANNELS line says.",
        wrong=lambda text, frame: _euler_variant(text, frame, always_xyz=True, by_name=False)),
    Misconception(
        "degrees", "pose_from_frame", "angles left in degrees",
        "BVH stores rotation channels in degrees: convert them (θ·π/180) before building "
        "R = R_Z(z) R_Y(y) R_X(x).",
        wrong=lambda text, frame: _euler_variant(text, frame, degrees=False)),
)

# --- pictures of a failing case ----------------------------------------------------------------


def _tree(parents: Any) -> np.ndarray | None:  # a student's answer: anything
    """``parents`` as integers if they describe a tree listed parents first, else None."""
    p = np.asarray(parents)
    if p.ndim != 1 or not len(p) or p[0] != -1 or np.any(p[1:] < 0) or np.any(
            p[1:] >= np.arange(1, len(p))) or np.any(p != np.round(p)):
        return None
    return p.astype(np.int64)


def _posed(parents: Any, offsets: Any, quats: Any, root: Any) -> np.ndarray | None:
    """Joint positions p_i = p_parent + Q_parent l_i, or None if the tree is not one."""
    tree = _tree(parents)
    q = np.asarray(quats, dtype=float)
    if tree is None or q.shape != (len(tree), 4) or np.any(np.linalg.norm(q, axis=1) < 1e-9):
        return None
    return np.array(ref_fk(tree, np.asarray(offsets, float), rot.quat_normalize(q), root)[0])


# got: the student's answer (anything); expected: the reference's; args: the case's.
def parse_picture(got: Any, expected: Any, args: tuple[Any, ...]) -> Picture | None:
    """The rest pose of your hierarchy (offsets added up along the parents) and the expected."""
    mine = _posed(got[1], got[2], np.tile([1.0, 0, 0, 0], (len(got[1]), 1)), np.zeros(3))
    if mine is None:
        return None
    rest = _posed(expected[1], expected[2], np.tile([1.0, 0, 0, 0], (len(expected[1]), 1)),
                  np.zeros(3))
    if rest is None:  # the reference's own tree: never, but then there is nothing to draw
        return None
    return Picture("the rest pose of your hierarchy (offsets added along the parents) and the "
                   "expected one", np.asarray(got[1], np.int64), mine, rest,
                   expected_parents=np.asarray(expected[1], np.int64))


def fk_picture(got: Any, expected: Any, args: tuple[Any, ...]) -> Picture:
    return Picture("your forward kinematics and the expected pose", args[0], got[0], expected[0])


def local_picture(got: Any, expected: Any, args: tuple[Any, ...]) -> Picture | None:
    """The pose your local rotations give a skeleton of unit bones along y."""
    parents = args[0]
    bones = np.tile([0.0, 1.0, 0.0], (len(parents), 1))
    mine = _posed(parents, bones, got, np.zeros(3))
    want = _posed(parents, bones, expected, np.zeros(3))
    if mine is None or want is None:
        return None
    return Picture("the pose your local rotations give (every bone 1 long, along y at rest) and "
                   "the expected one", parents, mine, want)


def pose_picture(got: Any, expected: Any, args: tuple[Any, ...]) -> Picture | None:
    _, parents, offsets = parse_reference(args[0])
    mine = _posed(parents, offsets, got[1], got[0])
    want = _posed(parents, offsets, expected[1], expected[0])
    if mine is None or want is None:
        return None
    return Picture("the pose your frame gives the file's skeleton, and the expected one",
                   parents, mine, want)


# --- the assignment ----------------------------------------------------------------------------

POSITIONS = PointsCheck(atol=1e-6)
ORIENTATIONS = QuatCheck(atol=1e-6, shape=None)

_FUNCTIONS = (
    Function("parse_bvh_hierarchy", ("text",), parse_reference,
             TupleCheck((StringsCheck("name"), IndexCheck(noun="parent"),
                         PointsCheck(row="offset")), ("names", "parents", "offsets")),
             parse_picture),
    Function("forward_kinematics", ("parents", "offsets", "local_quats", "root_position"),
             lambda parents, offsets, quats, root: tuple(
                 np.array(a) for a in ref_fk(parents, offsets, rot.quat_normalize(quats), root)),
             TupleCheck((POSITIONS, ORIENTATIONS), ("positions", "orientations")), fk_picture),
    Function("local_from_global", ("parents", "orientations"),
             lambda parents, Q: np.array(ref_local(parents, Q)), ORIENTATIONS, local_picture),
    Function("pose_from_frame", ("text", "frame"), pose_reference,
             TupleCheck((PointsCheck(atol=1e-6, row="coordinate", shape=(3,)), ORIENTATIONS),
                        ("root_position", "local_quats")), pose_picture),
)

ASSIGNMENT = Assignment(
    key="a2",
    title="Forward kinematics",
    template="a2_forward_kinematics.py",
    functions=_FUNCTIONS,
    tests=(
        Test("parse_bvh_hierarchy: sample files", "parse_bvh_hierarchy", 1.0, parse_samples),
        Test("parse_bvh_hierarchy: generated hierarchies", "parse_bvh_hierarchy", 1.0,
             parse_generated),
        Test("parse_bvh_hierarchy: hidden hierarchies", "parse_bvh_hierarchy", 2.0,
             parse_hidden, hidden=True),
        Test("forward_kinematics: sample motions", "forward_kinematics", 1.0, fk_samples),
        Test("forward_kinematics: random poses and edge cases", "forward_kinematics", 1.0,
             fk_random),
        Test("forward_kinematics: hidden poses", "forward_kinematics", 2.0, fk_hidden,
             hidden=True),
        Test("local_from_global: round trips", "local_from_global", 1.0, local_random),
        Test("local_from_global: edge cases", "local_from_global", 1.0, local_edges),
        Test("local_from_global: hidden poses", "local_from_global", 1.0, local_hidden,
             hidden=True),
        Test("pose_from_frame (bonus): sample and generated frames", "pose_from_frame", 1.0,
             pose_visible, bonus=True),
        Test("pose_from_frame (bonus): hidden frames", "pose_from_frame", 1.0, pose_hidden,
             hidden=True, bonus=True),
        Test("parse_bvh_hierarchy: real clips on this machine (unscored)",
             "parse_bvh_hierarchy", 0.0, parse_local),
        Test("forward_kinematics: real clips on this machine (unscored)", "forward_kinematics",
             0.0, fk_local),
    ),
    misconceptions=MISCONCEPTIONS,
)
