r"""A motion clip: a skeleton and, per frame, its root position and local joint rotations.

Frame :math:`t` of a :class:`Motion` is the pose of the lecture's forward kinematics,

.. math::
    Q_0 = R_0(t),\quad p_0 = \text{root\_positions}[t],\qquad
    Q_i = Q_{p(i)} R_i(t),\quad p_i = p_{p(i)} + Q_{p(i)}\, l_i(t),

where :math:`R_i(t)` = ``local_rotations[t, i]`` and the bone :math:`l_i(t)` is the joint's
OFFSET, or ``translations[t, i]`` when the clip animates bone vectors too (BVH position
channels on non-root joints).

``channels`` records how each joint was animated in its BVH file (``("Zrotation",
"Yrotation", "Xrotation")``, ...), so that saving writes the channels back in the same order.
The BVH writer (:func:`save_bvh`, :func:`format_bvh`) lives here, beside what it writes, so
that :meth:`Motion.save` needs no module above this one; :mod:`course.bvh` reads the files and
exports the writer too.
"""

from __future__ import annotations

import numbers
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ._typing import Array
from ._validate import as_array
from .rotations import euler_from_quat
from .skeleton import Skeleton

POSITION_CHANNELS = ("Xposition", "Yposition", "Zposition")
ROTATION_CHANNELS = ("Xrotation", "Yrotation", "Zrotation")

#: Seconds. The shortest frame time accepted (a million frames per second): anything shorter
#: is a garbled value, not a recording (5e-324 s would be infinite frames per second).
MIN_FRAME_TIME = 1e-6
#: How far the norm of a local rotation may be from 1: float32 data is ~1e-7 off, while a
#: rotation that was never normalised (or never filled in) is far off.
UNIT_TOL = 1e-6
# Tabs of indentation stop growing at this depth, so a deep chain is saved in linear size
# (real skeletons are less than 20 deep and are written as they always were).
_MAX_INDENT = 32
# Components a rotation channel set cannot express are tolerated up to this (degrees).
_DROPPED_ANGLE_TOL = 1e-6


def rotation_axes(channels: Sequence[str]) -> str:
    """The axes of a joint's rotation channels in file order: ``("Zrotation", "Xrotation")``
    -> ``"ZX"``."""
    return "".join(c[0] for c in channels if c in ROTATION_CHANNELS)


def euler_order(channels: Sequence[str]) -> str | None:
    """The intrinsic Euler order a joint's rotation channels spell, padded to three axes.

    BVH rotation channels compose intrinsically in file order, so ``Zrotation Yrotation
    Xrotation`` is ``"ZYX"`` (:math:`R = R_Z R_Y R_X`). A joint with fewer than three rotation
    channels gets the missing axes appended (their angles are zero, so they change nothing):
    ``"ZX"`` -> ``"ZXY"``. ``None`` when the joint has no rotation channel.
    """
    axes = rotation_axes(channels)
    if not axes:
        return None
    return axes + "".join(a for a in "XYZ" if a not in axes)


def default_channels(skeleton: Skeleton, order: str = "ZYX") -> tuple[tuple[str, ...], ...]:
    """Channels for a motion built in code: the root positions and rotations, every other joint
    rotations in ``order``; End Sites (leaves named ``"<Parent>_end"``) none."""
    rotations = tuple(f"{axis}rotation" for axis in order)
    channels = []
    for j in range(skeleton.n_joints):
        parent = int(skeleton.parents[j])
        if parent < 0:
            channels.append(POSITION_CHANNELS + rotations)
        elif is_end_site(skeleton, j):
            channels.append(())
        else:
            channels.append(rotations)
    return tuple(channels)


def is_end_site(skeleton: Skeleton, j: int) -> bool:
    """Whether joint ``j`` is a BVH End Site: a leaf named after its parent with ``_end``."""
    parent = int(skeleton.parents[j])
    return (
        parent >= 0
        and not skeleton.children(j)
        and skeleton.names[j].startswith(f"{skeleton.names[parent]}_end")
    )


@dataclass(eq=False)
class Motion:
    """A motion clip (one skeleton, ``F`` frames).

    Parameters
    ----------
    skeleton : Skeleton
        ``J`` joints, parent before child; End Sites are joints named ``"<Parent>_end"``.
    local_rotations : array_like, shape (F, J, 4)
        :math:`R_i(t)`, unit quaternions (w, x, y, z) relative to the parent joint (norms
        within :data:`UNIT_TOL` of 1).
    root_positions : array_like, shape (F, 3)
        :math:`p_0(t)`, the root joint's position.
    frame_time : float
        Seconds between frames (BVH ``Frame Time``), at least :data:`MIN_FRAME_TIME`.
    channels : sequence of tuple of str, optional
        Per joint, its BVH channel names in file order. Default (empty, or None):
        :func:`default_channels`.
    translations : array_like, shape (F, J, 3), optional
        Per-frame bones :math:`l_i(t)` for clips with position channels on non-root joints;
        rows of joints without position channels equal their offsets (the root's row, unused
        by forward kinematics, is its position). ``None`` (the usual case) means the bones
        are the skeleton's constant offsets.
    name : str
        A short name for display (the file stem when loaded).
    source : str, optional
        Where the motion came from (the file path when loaded).

    Raises
    ------
    ValueError
        Naming the argument, if ``skeleton`` is not a :class:`~course.skeleton.Skeleton`, an
        array is not real numbers of the right shape (NaN and infinity refused), a rotation
        is not a unit quaternion (with its frame and joint), or ``frame_time`` is not a
        number of seconds of at least :data:`MIN_FRAME_TIME`.
    """

    skeleton: Skeleton
    local_rotations: Array
    root_positions: Array
    frame_time: float
    channels: tuple[tuple[str, ...], ...] = ()
    translations: Array | None = None
    name: str = ""
    source: str | None = field(default=None)

    def __post_init__(self) -> None:
        if not isinstance(self.skeleton, Skeleton):
            raise ValueError(
                f"skeleton: expected a course.skeleton.Skeleton, got {type(self.skeleton).__name__}"
            )
        n_joints = self.skeleton.n_joints
        self.local_rotations = _float_array(self.local_rotations, "local_rotations", (n_joints, 4))
        _check_unit(self.local_rotations, self.skeleton.names)
        n_frames = self.local_rotations.shape[0]
        self.root_positions = _float_array(self.root_positions, "root_positions", (3,))
        if self.root_positions.shape[0] != n_frames:
            raise ValueError(
                f"root_positions: has {self.root_positions.shape[0]} frames, "
                f"local_rotations has {n_frames}"
            )
        if self.translations is not None:
            self.translations = _float_array(self.translations, "translations", (n_joints, 3))
            if self.translations.shape[0] != n_frames:
                raise ValueError(
                    f"translations: has {self.translations.shape[0]} frames, "
                    f"local_rotations has {n_frames}"
                )
        self.frame_time = _seconds(self.frame_time)
        if not self.channels:  # None too, as callers may pass
            self.channels = default_channels(self.skeleton)
        self.channels = _checked_channels(self.channels, self.skeleton)

    # -- size and timing --------------------------------------------------------------------

    @property
    def n_frames(self) -> int:
        """Number of frames ``F``."""
        return int(self.local_rotations.shape[0])

    @property
    def n_joints(self) -> int:
        """Number of joints ``J`` (End Sites included)."""
        return self.skeleton.n_joints

    @property
    def fps(self) -> float:
        """Frames per second, ``1 / frame_time``."""
        return 1.0 / self.frame_time

    @property
    def duration(self) -> float:
        """Length of the clip in seconds, ``n_frames * frame_time``."""
        return self.n_frames * self.frame_time

    @property
    def times(self) -> Array:
        """Time of each frame in seconds, shape (F,)."""
        return np.arange(self.n_frames, dtype=np.float64) * self.frame_time

    @property
    def euler_orders(self) -> tuple[str | None, ...]:
        """Per joint, the intrinsic Euler order of its rotation channels (:func:`euler_order`)."""
        return tuple(euler_order(c) for c in self.channels)

    def __len__(self) -> int:
        return self.n_frames

    # -- frames -----------------------------------------------------------------------------

    def __getitem__(self, index: int | slice) -> Motion:
        """``motion[i]``: a one-frame motion; ``motion[a:b:s]``: frames a..b-1 every s-th
        (the frame time becomes ``|s| * frame_time``). Arrays are copied."""
        if isinstance(index, slice):
            frames = index
            step = abs(index.step) if index.step is not None else 1
        elif isinstance(index, (int, np.integer)):
            i = int(index)
            if not -self.n_frames <= i < self.n_frames:
                raise IndexError(f"frame {i} is out of range for {self.n_frames} frames")
            i %= self.n_frames
            frames, step = slice(i, i + 1), 1
        else:
            raise TypeError(f"index: expected an int or a slice, got {type(index).__name__}")
        if step == 0:
            raise ValueError("index: slice step cannot be zero")
        return Motion(
            skeleton=self.skeleton,
            local_rotations=self.local_rotations[frames].copy(),
            root_positions=self.root_positions[frames].copy(),
            frame_time=self.frame_time * step,
            channels=self.channels,
            translations=None if self.translations is None else self.translations[frames].copy(),
            name=self.name,
            source=self.source,
        )

    # -- kinematics -------------------------------------------------------------------------

    def forward_kinematics(self) -> tuple[Array, Array]:
        r"""Global joint positions and orientations of every frame.

        :math:`Q_i = Q_{p(i)} R_i`, :math:`p_i = p_{p(i)} + Q_{p(i)} l_i`.

        Returns
        -------
        positions : ndarray, shape (F, J, 3)
        orientations : ndarray, shape (F, J, 4)
        """
        if self.translations is None:
            return self.skeleton.forward_kinematics(self.local_rotations, self.root_positions)
        from .fk import forward_kinematics

        return forward_kinematics(
            self.skeleton.parents,
            self.translations,
            self.local_rotations,
            self.root_positions,
            names=self.skeleton.names,
        )

    def save(self, path: str | os.PathLike[str], orders: str | Mapping[str, str] | None = None,
             *, digits: int = 12) -> None:
        """Write the clip as a BVH file (:func:`save_bvh`, which documents ``orders`` and
        ``digits``)."""
        save_bvh(self, path, orders, digits=digits)

    def __repr__(self) -> str:
        label = f"{self.name!r}, " if self.name else ""
        return (
            f"Motion({label}{self.n_frames} frames at {self.fps:.4g} fps, "
            f"{self.n_joints} joints, {self.duration:.3f} s)"
        )


def _float_array(x: ArrayLike, name: str, last: tuple[int, ...]) -> Array:
    """``x`` as a finite float array of shape (F,) + ``last``, a copy the motion owns."""
    a = as_array(x, name)
    if a.ndim != 1 + len(last) or a.shape[1:] != last:
        want = "(F, " + ", ".join(map(str, last)) + ")"
        raise ValueError(f"{name}: expected shape {want}, got {a.shape}")
    return a.copy() if a is x or a.base is not None else a  # a view of the caller's data


def _check_unit(rotations: Array, names: Sequence[str]) -> None:
    """Refuse local rotations (F, J, 4) that are not unit quaternions, by frame and joint:
    they would be taken as rotations until saving or FK failed far from the cause."""
    squared = np.einsum("...i,...i->...", rotations, rotations)  # cheaper than the norms
    off = (squared < (1.0 - UNIT_TOL) ** 2) | (squared > (1.0 + UNIT_TOL) ** 2)
    if np.any(off):
        f, j = (int(i) for i in np.argwhere(off)[0])
        norm = float(np.linalg.norm(rotations[f, j]))
        what = (
            "the zero quaternion, which is no rotation" if norm < 1e-12
            else f"not a unit quaternion (norm {norm:.9g})"
        )
        raise ValueError(
            f"local_rotations: frame {f}, joint {names[j]!r} is {what}; rotations are unit "
            "quaternions (normalise with course.rotations.quat_normalize)"
        )


def _seconds(frame_time: object) -> float:
    """``frame_time`` as a float of seconds, at least :data:`MIN_FRAME_TIME`."""
    if isinstance(frame_time, np.ndarray) and frame_time.ndim == 0:
        frame_time = frame_time[()]
    if not isinstance(frame_time, numbers.Real) or isinstance(frame_time, (bool, np.bool_)):
        raise ValueError(
            f"frame_time: expected a number of seconds, got {type(frame_time).__name__} "
            f"{frame_time!r}"
        )
    seconds = float(frame_time)
    if not (np.isfinite(seconds) and seconds >= MIN_FRAME_TIME):
        raise ValueError(
            f"frame_time: must be a positive number of seconds, at least {MIN_FRAME_TIME:g}, "
            f"got {seconds}"
        )
    return seconds


def _checked_channels(
    channels: Sequence[Sequence[str]], skeleton: Skeleton
) -> tuple[tuple[str, ...], ...]:
    """Per-joint channel tuples, each a valid set of distinct BVH channel names."""
    if isinstance(channels, str) or len(channels) != skeleton.n_joints:
        raise ValueError(
            f"channels: expected one tuple of channel names per joint ({skeleton.n_joints})"
        )
    checked = []
    for j, joint in enumerate(channels):
        joint = tuple(joint)
        for c in joint:
            if c not in POSITION_CHANNELS and c not in ROTATION_CHANNELS:
                raise ValueError(
                    f"channels: joint {skeleton.names[j]!r} has unknown channel {c!r}; "
                    f"expected some of {', '.join(POSITION_CHANNELS + ROTATION_CHANNELS)}"
                )
        if len(set(joint)) != len(joint):
            raise ValueError(f"channels: joint {skeleton.names[j]!r} repeats a channel: {joint}")
        checked.append(joint)
    return tuple(checked)


# -- as a BVH file ---------------------------------------------------------------------------


def save_bvh(
    motion: Motion,
    path: str | os.PathLike[str],
    orders: str | Mapping[str, str] | None = None,
    *,
    digits: int = 12,
) -> None:
    """Write ``motion`` as a BVH file (LF line endings, tabs); see :func:`format_bvh`."""
    Path(path).write_text(format_bvh(motion, orders, digits=digits), encoding="utf-8", newline="\n")


def format_bvh(
    motion: Motion, orders: str | Mapping[str, str] | None = None, *, digits: int = 12
) -> str:
    """The text of a BVH file holding ``motion``.

    Parameters
    ----------
    motion : Motion
    orders : str or mapping of joint name to str, optional
        Intrinsic Euler orders for the rotation channels (``"ZYX"`` writes ``Zrotation
        Yrotation Xrotation``): one order for every joint that has rotation channels, or a
        mapping for some joints. Default: each joint's channels as in ``motion.channels``.
    digits : int
        Significant digits per value; the default 12 keeps forward kinematics within 1e-9 of
        the motion for clip-sized numbers.

    Raises
    ------
    ValueError
        If ``orders`` is not an intrinsic Tait-Bryan order (or names an unknown joint), or the
        motion holds something its channels cannot carry (a rotation of a joint without
        rotation channels, a bone that differs from its OFFSET without position channels).

    Notes
    -----
    Joints are written depth first; for a skeleton not already in that order, the file (and a
    motion loaded from it) lists the joints in a different order, with the same names.
    """
    if not isinstance(digits, int) or not 1 <= digits <= 17:
        raise ValueError(f"digits: expected an integer from 1 to 17, got {digits!r}")
    channels = _channels_with_orders(motion, orders)
    columns = [_joint_values(motion, j, c) for j, c in enumerate(channels)]
    order = _depth_first(motion.skeleton)
    values = np.concatenate([columns[j] for j in order], axis=1)
    return format_bvh_channels(
        motion.skeleton, channels, values, motion.frame_time, fmt=f"%.{digits}g", order=order
    )


def format_bvh_channels(
    skeleton: Skeleton,
    channels: Sequence[Sequence[str]],
    values: Array,
    frame_time: float,
    *,
    fmt: str = "%.12g",
    order: Sequence[int] | None = None,
) -> str:
    """The text of a BVH file from raw channel values (degrees and file units).

    Parameters
    ----------
    skeleton : Skeleton
        One root; leaves named ``"<Parent>_end"`` without channels are written as End Sites.
    channels : sequence of tuple of str
        Per joint, its channel names.
    values : array_like, shape (F, C)
        Channel values per frame, joints in depth-first order (``order``).
    frame_time : float
        Seconds per frame.
    fmt : str
        printf format of a number (offsets and channel values).
    order : sequence of int, optional
        The depth-first joint order of the file (computed when not given).
    """
    order = list(_depth_first(skeleton) if order is None else order)
    values = np.asarray(values, dtype=np.float64)
    n_channels = sum(len(channels[j]) for j in order)
    if values.ndim != 2 or values.shape[1] != n_channels:
        raise ValueError(f"values: expected shape (F, {n_channels}), got {values.shape}")
    depth: dict[int, int] = {}
    lines = ["HIERARCHY"]
    open_blocks: list[int] = []
    for j in order:
        parent = int(skeleton.parents[j])
        while open_blocks and open_blocks[-1] != parent:  # close finished subtrees
            lines.append("\t" * depth[open_blocks.pop()] + "}")
        depth[j] = min(depth[parent] + 1, _MAX_INDENT) if parent >= 0 else 0
        tab = "\t" * depth[j]
        end_site = is_end_site(skeleton, j) and not channels[j]
        head = "ROOT " if parent < 0 else "End Site" if end_site else "JOINT "
        lines.append(tab + head + ("" if end_site else skeleton.names[j]))
        lines.append(tab + "{")
        lines.append(tab + "\tOFFSET " + " ".join(fmt % v for v in skeleton.offsets[j]))
        if not end_site:
            lines.append(tab + f"\tCHANNELS {len(channels[j])} " + " ".join(channels[j]))
        open_blocks.append(j)
    while open_blocks:
        lines.append("\t" * depth[open_blocks.pop()] + "}")
    lines += ["MOTION", f"Frames: {values.shape[0]}", f"Frame Time: {float(frame_time)!r}"]
    row = " ".join([fmt] * n_channels)
    lines.extend(row % tuple(frame) for frame in values.tolist())
    return "\n".join(lines) + "\n"


def _depth_first(skeleton: Skeleton) -> list[int]:
    """Joint indices in depth-first (BVH file) order from the root, joint 0; children in index
    order."""
    order, todo = [], [0]
    while todo:
        j = todo.pop()
        order.append(j)
        todo.extend(reversed(skeleton.children(j)))
    return order


def _channels_with_orders(
    motion: Motion, orders: str | Mapping[str, str] | None
) -> tuple[tuple[str, ...], ...]:
    """``motion.channels`` with the rotation channels of the joints in ``orders`` replaced."""
    names = motion.skeleton.names
    if orders is None:
        return motion.channels
    if isinstance(orders, str):
        wanted = {names[j]: orders for j, c in enumerate(motion.channels) if rotation_axes(c)}
    elif isinstance(orders, Mapping):
        wanted = dict(orders)
        unknown = sorted(set(wanted) - set(names))
        if unknown:
            raise ValueError(f"orders: no joint named {', '.join(map(repr, unknown))}")
    else:
        raise ValueError(f"orders: expected a string or a mapping, got {type(orders).__name__}")
    for name, order in wanted.items():
        if not isinstance(order, str) or len(order) != 3 or set(order) != set("XYZ"):
            hint = (
                " (BVH rotation channels are intrinsic: use uppercase, e.g. 'ZYX' for extrinsic"
                " 'xyz')"
                if isinstance(order, str) and set(order) == set("xyz")
                else ""
            )
            raise ValueError(
                f"orders: {order!r} for joint {name!r} is not an intrinsic order of the three "
                f"axes X, Y, Z{hint}"
            )
    channels = []
    for name, joint_channels in zip(names, motion.channels, strict=True):
        if name not in wanted:
            channels.append(joint_channels)
            continue
        rotations = tuple(f"{axis}rotation" for axis in wanted[name])
        kept = [c for c in joint_channels if c in POSITION_CHANNELS]
        # The rotations go where they were (before or after the positions).
        first = next((i for i, c in enumerate(joint_channels) if c in ROTATION_CHANNELS), None)
        at = len(kept) if first is None else first
        channels.append(tuple(kept[:at]) + rotations + tuple(kept[at:]))
    return tuple(channels)


def _joint_values(motion: Motion, j: int, channels: tuple[str, ...]) -> Array:
    """Joint ``j``'s channel values (F, len(channels)): degrees and file units."""
    name = motion.skeleton.names[j]
    rotation = motion.local_rotations[:, j]
    order = euler_order(channels)
    if order is None:
        if np.any(1.0 - np.abs(rotation[:, 0]) > 1e-12):
            raise ValueError(
                f"motion: joint {name!r} rotates but has no rotation channels; give it some "
                "with orders={" + repr(name) + ": 'ZYX'}"
            )
        angles = np.zeros((motion.n_frames, 3))
    else:
        angles = euler_from_quat(rotation, order, degrees=True)
        n_axes = len(rotation_axes(channels))
        if n_axes < 3:
            # Every rotation has a second Tait-Bryan triple, (a + 180, 180 - b, c + 180); a
            # joint with two channels turned more than 90 degrees about its second axis needs
            # that one, where the padded third angle is 0 instead of 180.
            other = _wrap_degrees(angles + [180.0, 0.0, 180.0])
            other[:, 1] = _wrap_degrees(180.0 - angles[:, 1])
            flip = np.abs(angles[:, n_axes:]).max(axis=1) > np.abs(other[:, n_axes:]).max(axis=1)
            angles[flip] = other[flip]
        dropped = np.abs(angles[:, n_axes:])
        if dropped.size and dropped.max() > _DROPPED_ANGLE_TOL:
            raise ValueError(
                f"motion: joint {name!r} rotates about axes its channels {channels} do not "
                f"have ({dropped.max():.3g} degrees); pass orders to write all three"
            )
    if j == 0:
        bones = motion.root_positions
    elif motion.translations is not None:
        bones = motion.translations[:, j]
    else:
        bones = np.broadcast_to(motion.skeleton.offsets[j], (motion.n_frames, 3))
    offset = motion.skeleton.offsets[j]
    for axis in range(3):
        if f"{'XYZ'[axis]}position" not in channels and not np.allclose(
            bones[:, axis], offset[axis], rtol=1e-12, atol=1e-9
        ):
            what = "root position" if j == 0 else "bone (translations)"
            raise ValueError(
                f"motion: the {what} of joint {name!r} moves along {'XYZ'[axis]} but the joint "
                f"has no {'XYZ'[axis]}position channel"
            )
    columns = []
    axes = order or ""
    for channel in channels:
        axis = "XYZ".index(channel[0])
        if channel in POSITION_CHANNELS:
            columns.append(bones[:, axis])
        else:
            columns.append(angles[:, axes.index(channel[0])])
    return np.stack(columns, axis=1) if columns else np.zeros((motion.n_frames, 0))


def _wrap_degrees(angles: Array) -> Array:
    """Angles wrapped into [-180, 180)."""
    return (np.asarray(angles) + 180.0) % 360.0 - 180.0
