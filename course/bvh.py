r"""Read and write BVH motion capture (Biovision Hierarchy).

A BVH file has two parts::

    HIERARCHY                                   MOTION
    ROOT Hips                                   Frames: 524
    {                                           Frame Time: .0083333
        OFFSET 0 0 0                            <one line per frame: every channel's value,
        CHANNELS 6 Xposition Yposition ...       joints in file order, channels in their
        JOINT LHipJoint { ... }                  declared order>
        End Site { OFFSET ... }
    }

Every joint becomes a joint of the :class:`~course.skeleton.Skeleton`, End Sites too (named
``"<Parent>_end"``, no channels), with the joint type its rotation channels allow (see
:func:`joint_type`: three make a ball joint, two a universal joint, one a hinge, none a fixed
joint), so ``skeleton.dof`` counts the rotation channels. Angles are in degrees in the file;
a joint's rotation channels compose *intrinsically* in file order, so ``Zrotation Yrotation
Xrotation`` is the Euler order ``"ZYX"``, :math:`R = R_Z(\alpha) R_Y(\beta) R_X(\gamma)`. A
position channel replaces that axis of the joint's OFFSET (for the root: its position).

The writer (:func:`save_bvh`, :func:`format_bvh`, :func:`format_bvh_channels`) is defined with
:class:`~course.motion.Motion`, whose :meth:`~course.motion.Motion.save` uses it, and is
exported here beside the reader.

The reader accepts what real exporters write (CRLF or mixed line endings, tabs, blank lines,
no final newline, ``.0083333``, leaf joints without End Site, ``Frame Time:`` spacing) and
refuses anything else with a :class:`BVHError` naming the file, the line and the problem.
"""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ._typing import Array
from .motion import (
    MIN_FRAME_TIME,
    POSITION_CHANNELS,
    ROTATION_CHANNELS,
    Motion,
    euler_order,
    format_bvh,
    format_bvh_channels,
    rotation_axes,
    save_bvh,
)
from .rotations import quat_from_euler, quat_identity
from .skeleton import Ball, Fixed, Hinge, JointType, Skeleton, Universal

__all__ = [
    "BVHError",
    "BVHWarning",
    "format_bvh",
    "format_bvh_channels",
    "joint_type",
    "load_bvh",
    "parse_bvh",
    "save_bvh",
]

_CHANNEL_NAMES = {c.upper(): c for c in POSITION_CHANNELS + ROTATION_CHANNELS}
_FRAMES = re.compile(r"\s*frames\s*:\s*(.*?)\s*$", re.IGNORECASE)
_FRAME_TIME = re.compile(r"\s*frame\s*time\s*:\s*(.*?)\s*$", re.IGNORECASE)
# Numbers as the format writes them, in ASCII, plus the inf/nan spellings numpy's reader takes
# (then refused as not finite). float() alone would also read "1_0" and Arabic-Indic or
# full-width digits.
_NUMBER = re.compile(
    r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:e[+-]?[0-9]+)?|inf(?:inity)?|nan)",
    re.IGNORECASE | re.ASCII,
)
# Whole numbers: ASCII digits, at most 18 of them after leading zeros (more than any file
# holds, and int() refuses strings past 4300 digits).
_COUNT = re.compile(r"0*[0-9]{1,18}")


class BVHError(ValueError):
    """A malformed BVH file.

    Attributes
    ----------
    path : str
        The file (or the ``source`` given to :func:`parse_bvh`).
    line : int or None
        1-based line number of the problem.
    problem : str
        What is wrong, without the location.
    """

    def __init__(self, problem: str, path: str, line: int | None = None) -> None:
        self.problem, self.path, self.line = problem, path, line
        where = path if line is None else f"{path}, line {line}"
        super().__init__(f"{where}: {problem}")

    def __reduce__(self) -> tuple[type[BVHError], tuple[str, str, int | None]]:
        # keep path and line across pickling (worker processes)
        return type(self), (self.problem, self.path, self.line)


class BVHWarning(UserWarning):
    """A BVH quirk the reader worked around (e.g. more frame lines than declared)."""


# -- reading -------------------------------------------------------------------------------


def load_bvh(path: str | os.PathLike[str]) -> Motion:
    """Read a BVH file.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    Motion
        One joint per ``ROOT``/``JOINT``/``End Site`` in file order (End Sites named
        ``"<Parent>_end"``, then ``"<Parent>_end2"``, ... if a joint has several), with
        ``channels`` as declared. ``local_rotations[t, j]`` is the product of the joint's
        rotation channels in file order (identity without any); ``root_positions`` are the
        root's position channels (an axis without a channel keeps the root's OFFSET);
        ``translations`` is set only if a non-root joint has position channels (see
        :class:`~course.motion.Motion`). ``name`` is the file stem, ``source`` the path.
        The skeleton's joint types follow the rotation channels (:func:`joint_type`).

    Raises
    ------
    BVHError
        If the file is malformed (the message names the file and line).
    OSError
        If the file cannot be read.

    Warns
    -----
    BVHWarning
        For a quirk the reader worked around (more frame lines than ``Frames:`` declares: the
        declared count is loaded); the warning points at the line that called ``load_bvh``.
    """
    path = Path(path)
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:  # joint names from old Windows exporters
        text = raw.decode("latin-1")
    motion, quirks = _parse(text, str(path), path.stem)
    _warn(quirks)
    return motion


def parse_bvh(text: str, source: str = "<string>", name: str = "") -> Motion:
    """Parse the text of a BVH file; see :func:`load_bvh`.

    Parameters
    ----------
    text : str
        The whole file.
    source : str
        Names the text in error messages and becomes ``Motion.source``.
    name : str
        ``Motion.name``.
    """
    motion, quirks = _parse(text, source, name)
    _warn(quirks)
    return motion


def _warn(quirks: Sequence[str]) -> None:
    # stacklevel 3: past this helper and the public function, at the line that called it.
    for quirk in quirks:
        warnings.warn(quirk, BVHWarning, stacklevel=3)


def _parse(text: str, source: str, name: str) -> tuple[Motion, list[str]]:
    """The motion, and the quirks worked around (warning messages, left to the caller so that
    the warning points at user code)."""
    quirks: list[str] = []
    lines = _lines(text)
    joints, motion_at = _parse_hierarchy(lines, source)
    n_frames, frame_time, data_at = _parse_motion_header(lines, motion_at, source)
    channels = tuple(j.channels or () for j in joints)
    n_channels = sum(len(c) for c in channels)
    values = _parse_frames(lines, data_at, n_frames, n_channels, source, quirks)
    offsets = np.array([j.offset for j in joints], dtype=np.float64)
    types = [joint_type(c) for c in channels]
    skeleton = Skeleton([j.name for j in joints], [j.parent for j in joints], offsets, types)
    rotations, root_positions, translations = _pose_from_channels(values, channels, offsets)
    motion = Motion(
        skeleton=skeleton,
        local_rotations=rotations,
        root_positions=root_positions,
        frame_time=frame_time,
        channels=channels,
        translations=translations,
        name=name,
        source=source,
    )
    return motion, quirks


def _lines(text: str) -> list[str]:
    r"""The lines of ``text`` without a leading byte order mark, ended by ``\n``, ``\r\n`` or
    ``\r`` (mixed too) and nothing else: ``str.splitlines`` also breaks at ``\v``, ``\f``,
    ``\x85``, ``\u2028`` ..., which would shift error line numbers from what an editor shows.
    A last line without a terminator is kept."""
    text = text.removeprefix("\ufeff")
    if "\r" in text:  # checked first: the replacements copy megabytes even when they find none
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    lines = text.split("\n")
    if lines[-1] == "":  # what follows the last terminator (or the empty text) is no line
        lines.pop()
    return lines


def _number(token: str) -> float | None:
    """The value of a number token as BVH writes it (ASCII), or None."""
    return float(token) if _NUMBER.fullmatch(token) else None


def _not_a_number(token: str) -> str:
    """Why ``token`` is refused, with a hint when Python's float() would have read it."""
    try:
        float(token)
    except ValueError:
        return f"{token!r} is not a number"
    return (f"{token!r} is not a number as BVH writes them (ASCII digits 0-9, with an optional "
            "sign, point and exponent)")


_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def joint_type(channels: Sequence[str]) -> JointType:
    """The joint type a BVH joint's rotation channels allow (position channels do not count).

    None: :class:`~course.skeleton.Fixed` (End Sites too); one, e.g. ``Xrotation``: a
    :class:`~course.skeleton.Hinge` about that axis; two, e.g. ``Zrotation Xrotation``: a
    :class:`~course.skeleton.Universal` joint turning about them in file order
    (:math:`R = R_Z R_X`); three: a :class:`~course.skeleton.Ball`. The axes are those of
    the parent's frame, where BVH rotation channels act.
    """
    axes = rotation_axes(channels)
    if not axes:
        return Fixed()
    if len(axes) == 1:
        return Hinge(_AXES[axes])
    if len(axes) == 2:
        return Universal((_AXES[axes[0]], _AXES[axes[1]]))
    return Ball()


@dataclass
class _Joint:
    name: str
    parent: int
    line: int
    end_site: bool = False
    offset: tuple[float, float, float] | None = None
    channels: tuple[str, ...] | None = None


#: Builds the error of a problem at a line index (of :func:`_parse_hierarchy`).
_Fail = Callable[[str, int], BVHError]


# One pass of a line-by-line state machine, each keyword a few lines with its own error.
def _parse_hierarchy(lines: Sequence[str], source: str) -> tuple[list[_Joint], int]:  # noqa: C901
    """The joints in file order and the index of the ``MOTION`` line."""

    def fail(problem: str, at: int) -> BVHError:
        return BVHError(problem, source, at + 1)

    joints: list[_Joint] = []
    names: set[str] = set()
    stack: list[int] = []  # joints whose '{' is open
    pending: int | None = None  # a joint waiting for its '{'
    seen_header = False

    def add_joint(name: str, parent: int, at: int, end_site: bool = False) -> int:
        if name in names:
            raise fail(f"duplicate joint name {name!r}", at)
        names.add(name)
        joints.append(_Joint(name, parent, at + 1, end_site, channels=() if end_site else None))
        return len(joints) - 1

    for at, line in enumerate(lines):
        tokens = line.split()
        k = 0
        while k < len(tokens):
            token, key = tokens[k], tokens[k].upper()
            if pending is not None:
                if token != "{":
                    joint = joints[pending]
                    raise fail(f"expected '{{' to open joint {joint.name!r}, found {token!r}", at)
                stack.append(pending)
                pending = None
                k += 1
            elif not seen_header:
                if key != "HIERARCHY":
                    raise fail(f"expected HIERARCHY at the start of the file, found {token!r}", at)
                seen_header = True
                k += 1
            elif key == "MOTION":
                if stack:
                    raise fail(
                        f"unbalanced braces: MOTION while joint {joints[stack[-1]].name!r} "
                        f"(line {joints[stack[-1]].line}) is still open; a '}}' is missing",
                        at,
                    )
                if not joints:
                    raise fail("MOTION before any ROOT joint", at)
                if len(tokens) > 1:
                    raise fail(f"unexpected {' '.join(tokens[1:])!r} after MOTION", at)
                return joints, at
            elif key == "}":
                if not stack:
                    raise fail("unbalanced braces: '}' without a matching '{'", at)
                joint = joints[stack.pop()]
                if joint.offset is None:
                    raise fail(f"joint {joint.name!r} has no OFFSET", at)
                if joint.channels is None:
                    joint.channels = ()
                k += 1
            elif key in ("ROOT", "JOINT"):
                if key == "ROOT" and joints:
                    raise fail("a second ROOT: only one skeleton per file is supported", at)
                if key == "JOINT" and not stack:
                    raise fail("JOINT outside any joint's braces", at)
                parent = stack[-1] if stack else -1
                if parent >= 0 and joints[parent].end_site:
                    raise fail("an End Site cannot have child joints", at)
                rest = tokens[k + 1 :]
                opens = bool(rest) and rest[-1] == "{"
                name = " ".join(rest[:-1] if opens else rest)
                if not name:
                    raise fail(f"{token} without a name", at)
                pending = add_joint(name, parent, at)
                k = len(tokens) - 1 if opens else len(tokens)
            elif key == "END":
                if k + 1 >= len(tokens) or tokens[k + 1].upper() != "SITE":
                    raise fail(f"unknown keyword {token!r} (expected 'End Site')", at)
                if not stack or joints[stack[-1]].end_site:
                    raise fail("End Site outside a joint's braces", at)
                parent_name = joints[stack[-1]].name
                name, n = f"{parent_name}_end", 2
                while name in names:  # a joint with several End Sites
                    name, n = f"{parent_name}_end{n}", n + 1
                pending = add_joint(name, stack[-1], at, end_site=True)
                k += 2
            elif key == "OFFSET":
                joint = _open_joint(joints, stack, token, fail, at)
                if joint.offset is not None:
                    raise fail(f"a second OFFSET for joint {joint.name!r}", at)
                joint.offset = _offset(tokens[k + 1 :], joint.name, fail, at)
                k = len(tokens)
            elif key == "CHANNELS":
                joint = _open_joint(joints, stack, token, fail, at)
                if joint.end_site:
                    raise fail("an End Site has no CHANNELS", at)
                if joint.channels is not None:
                    raise fail(f"a second CHANNELS for joint {joint.name!r}", at)
                joint.channels = _channels(tokens[k + 1 :], joint.name, fail, at)
                k = len(tokens)
            else:
                inside = f" in joint {joints[stack[-1]].name!r}" if stack else ""
                raise fail(f"unknown keyword {token!r}{inside}", at)

    last = max(len(lines) - 1, 0)
    if not seen_header:
        raise fail("empty file: expected HIERARCHY", last)
    if pending is not None or stack:
        joint = joints[pending if pending is not None else stack[-1]]
        raise fail(
            f"unbalanced braces: the file ends while joint {joint.name!r} "
            f"(line {joint.line}) is still open",
            last,
        )
    if not joints:
        raise fail("no ROOT joint", last)
    raise fail("missing MOTION section after the HIERARCHY", last)


def _open_joint(
    joints: list[_Joint], stack: list[int], keyword: str, fail: _Fail, at: int
) -> _Joint:
    if not stack:
        raise fail(f"{keyword} outside any joint's braces", at)
    return joints[stack[-1]]


def _offset(args: list[str], joint: str, fail: _Fail, at: int) -> tuple[float, float, float]:
    if len(args) != 3:
        raise fail(f"OFFSET of joint {joint!r} needs 3 numbers, found {len(args)}", at)
    bad = next((a for a in args if _number(a) is None), None)
    if bad is not None:
        raise fail(
            f"OFFSET of joint {joint!r} is not three numbers: {' '.join(args)!r} "
            f"({_not_a_number(bad)})", at
        )
    x, y, z = (float(a) for a in args)
    if not np.all(np.isfinite([x, y, z])):
        raise fail(f"OFFSET of joint {joint!r} is not finite: {' '.join(args)!r}", at)
    return x, y, z


def _channels(args: list[str], joint: str, fail: _Fail, at: int) -> tuple[str, ...]:
    if not args:
        raise fail(f"CHANNELS of joint {joint!r} needs a channel count", at)
    if not _COUNT.fullmatch(args[0]):
        raise fail(
            f"CHANNELS of joint {joint!r}: count {args[0][:40]!r} is not a whole number", at
        )
    count = int(args[0])
    names = args[1:]
    if count != len(names):
        raise fail(
            f"CHANNELS of joint {joint!r} declares {count} channels but names {len(names)}", at
        )
    channels = []
    for name in names:
        channel = _CHANNEL_NAMES.get(name.upper())
        if channel is None:
            raise fail(
                f"bad channel name {name!r} for joint {joint!r}; expected one of "
                + ", ".join(_CHANNEL_NAMES.values()),
                at,
            )
        if channel in channels:
            raise fail(f"channel {channel} repeated for joint {joint!r}", at)
        channels.append(channel)
    return tuple(channels)


def _parse_motion_header(
    lines: Sequence[str], motion_at: int, source: str
) -> tuple[int, float, int]:
    """``Frames:`` and ``Frame Time:`` after MOTION; returns them and the first data line."""

    def next_line(start: int, what: str) -> int:
        at = start
        while at < len(lines) and not lines[at].strip():
            at += 1
        if at == len(lines):
            raise BVHError(f"missing {what} line after MOTION", source, len(lines))
        return at

    at = next_line(motion_at + 1, "'Frames:'")
    match = _FRAMES.fullmatch(lines[at])
    if match is None:
        raise BVHError(f"expected 'Frames: <count>', found {lines[at].strip()!r}", source, at + 1)
    if not _COUNT.fullmatch(match[1]):
        raise BVHError(
            f"frame count {match[1][:40]!r} is not a whole number below 10**18", source, at + 1
        )
    n_frames = int(match[1])

    at = next_line(at + 1, "'Frame Time:'")
    match = _FRAME_TIME.fullmatch(lines[at])
    if match is None:
        raise BVHError(
            f"expected 'Frame Time: <seconds>', found {lines[at].strip()!r}", source, at + 1
        )
    frame_time = _number(match[1])
    if frame_time is None or not (np.isfinite(frame_time) and frame_time >= MIN_FRAME_TIME):
        raise BVHError(
            f"Frame Time {match[1]!r} is not a positive number of seconds (finite, at least "
            f"{MIN_FRAME_TIME:g}, written in ASCII digits)", source, at + 1
        )
    return n_frames, frame_time, at + 1


def _parse_frames(
    lines: Sequence[str], data_at: int, n_frames: int, n_channels: int, source: str,
    quirks: list[str],
) -> Array:
    """The motion block as an (F, C) array; a surplus of frame lines is noted in ``quirks``.

    The fast path hands the frame lines to numpy's C parser in one call; only when that fails
    are the lines split in Python to find the first bad one and report its line number.
    Frame lines are the non-blank lines, except for a skeleton without channels, whose frames
    are empty lines. Either way the file must hold every frame it declares, so what is
    allocated is bounded by the file's length, not by the ``Frames:`` it claims.
    """
    tail = lines[data_at:]
    if n_channels:
        numbered = [i for i, line in enumerate(tail) if line and not line.isspace()]
    else:
        numbered = list(range(len(tail)))
    if len(numbered) < n_frames:
        raise BVHError(
            f"fewer frame lines than declared: 'Frames:' says {n_frames}, "
            f"the file ends after {len(numbered)}"
            + ("" if n_channels else " (without channels, each frame is an empty line)"),
            source,
            len(lines),
        )
    surplus = sum(1 for i in numbered[n_frames:] if tail[i] and not tail[i].isspace())
    if surplus:
        quirks.append(
            f"{source}: more frame lines than declared: Frames: says {n_frames}, the file has "
            f"{n_frames + surplus}; loading the first {n_frames}"
        )
    rows = [tail[i] for i in numbered[:n_frames]]
    line_numbers = [data_at + 1 + i for i in numbered[:n_frames]]  # 1-based
    if n_frames == 0:
        return np.zeros((0, n_channels))
    if not n_channels:
        values = None if any(row and not row.isspace() for row in rows) else np.zeros((n_frames, 0))
    else:
        try:
            values = np.loadtxt(rows, dtype=np.float64, comments=None, ndmin=2)
        except ValueError:
            values = None
    if values is None or values.shape != (n_frames, n_channels):
        raise _frame_error(rows, line_numbers, n_channels, source)
    finite = np.isfinite(values)
    if not finite.all():
        f, c = (int(i) for i in np.argwhere(~finite)[0])
        token = rows[f].split()[c]
        raise BVHError(f"frame {f}: {token!r} is not a finite number", source, line_numbers[f])
    return values


def _frame_error(
    rows: Sequence[str], line_numbers: Sequence[int], n_channels: int, source: str
) -> BVHError:
    """The error for the first frame line numpy could not read."""
    for f, row in enumerate(rows):
        tokens = row.split()
        if len(tokens) != n_channels:
            return BVHError(
                f"frame {f} has {len(tokens)} values, expected {n_channels} "
                "(the number of channels in the HIERARCHY)",
                source,
                line_numbers[f],
            )
        for token in tokens:
            if _number(token) is None:
                return BVHError(f"frame {f}: {_not_a_number(token)}", source, line_numbers[f])
    return BVHError("the frame lines could not be read as numbers", source, line_numbers[0])


def _pose_from_channels(
    values: Array, channels: Sequence[tuple[str, ...]], offsets: Array
) -> tuple[Array, Array, Array | None]:
    """Local rotations (F, J, 4), root positions (F, 3) and, if any non-root joint has position
    channels, per-frame bones (F, J, 3) from the channel values (F, C)."""
    n_frames, n_joints = values.shape[0], len(channels)
    # One extra zero column stands in for the axes a joint has no rotation channel for.
    padded = np.concatenate([values, np.zeros((n_frames, 1))], axis=1)
    zero_column = values.shape[1]
    animated_bones = any(c in POSITION_CHANNELS for joint in channels[1:] for c in joint)
    # A position channel replaces its axis of the OFFSET; per-frame bones of every joint only
    # when a non-root joint has one, else just the root's row (its position).
    bones = np.repeat(offsets[None, : n_joints if animated_bones else 1], n_frames, axis=0)
    groups: dict[str, tuple[list[int], list[list[int]]]] = {}  # Euler order -> joints, columns
    column = 0
    for j, joint_channels in enumerate(channels):
        rotation_columns = []
        for channel in joint_channels:
            if channel in POSITION_CHANNELS:
                bones[:, j, "XYZ".index(channel[0])] = values[:, column]
            else:
                rotation_columns.append(column)
            column += 1
        order = euler_order(joint_channels)
        if order is not None:
            joints, columns = groups.setdefault(order, ([], []))
            joints.append(j)
            columns.append(rotation_columns + [zero_column] * (3 - len(rotation_columns)))

    rotations = quat_identity((n_frames, n_joints))
    for order, (joints, columns) in groups.items():
        angles = padded[:, np.array(columns)]  # (F, G, 3), in the joint's channel order
        rotations[:, joints] = quat_from_euler(angles, order, degrees=True)
    root_positions = bones[:, 0].copy()
    return rotations, root_positions, bones if animated_bones else None
