"""Notebook 03 · BVH: the clip's timing from its header, and a joint's rotation channels to
one quaternion."""

from __future__ import annotations

import numpy as np

from autograder.checks import Check, QuatCheck
from autograder.spec import Case, Function, Misconception

from ..motion import Motion
from ..rotations import quat_from_axis_angle, quat_from_euler, quat_identity, quat_mul
from ..skeleton import chain
from .spec import Exercise


def clip_timing(frame_time: float, n_frames: int) -> np.ndarray:
    r"""Reference of 03.timing: a :class:`~course.motion.Motion` of ``n_frames`` frames,
    ``frame_time`` apart, and its ``fps`` (:math:`1 / \Delta t`) and ``duration``
    (:math:`F\,\Delta t`)."""
    skeleton = chain([1.0])
    motion = Motion(skeleton, np.tile(quat_identity(), (n_frames, skeleton.n_joints, 1)),
                    np.zeros((n_frames, 3)), frame_time)
    return np.array([motion.fps, motion.duration])


def _timings(rng: np.random.Generator) -> list[Case]:
    cases = [Case("the CMU walk's header: Frame Time .0083333, Frames 524", (0.0083333, 524)),
             Case("a single frame at 120 fps", (0.0083333, 1)),
             Case("a 30 fps clip of 90 frames", (0.0333333, 90))]
    for k in (1, 2):
        fps = int(rng.choice([24, 25, 50, 60, 100]))
        cases.append(Case(f"a {fps} fps clip ({k})",
                          (round(1 / fps, 7), int(rng.integers(20, 2000)))))
    return cases


def channel_rotation(angles_deg: np.ndarray, order: str) -> np.ndarray:
    r"""Reference of 03.channels: intrinsic, in the listed order, degrees:
    ``"ZYX"`` is :math:`R_Z(\gamma) R_Y(\beta) R_X(\alpha)`."""
    return quat_from_euler(angles_deg, order, degrees=True)


def _reversed_product(angles_deg: np.ndarray, order: str) -> np.ndarray:
    """The elementary turns multiplied the other way round (extrinsic, in the listed order)."""
    q = np.array([1.0, 0.0, 0.0, 0.0])
    for axis, a in zip(order, np.radians(angles_deg), strict=True):
        q = quat_mul(quat_from_axis_angle(np.eye(3)["XYZ".index(axis)], a), q)
    return q


def _channels(rng: np.random.Generator) -> list[Case]:
    cases = [Case("one channel: 90° about Z", (np.array([90.0, 0.0, 0.0]), "ZYX"))]
    for k, order in enumerate(("ZYX", "ZXY", "XYZ"), start=1):
        cases.append(Case(f"CMU-like angles, order {order} ({k})",
                          (np.round(rng.uniform(-60, 60, 3), 1), order)))
    return cases


EXERCISES = (
    Exercise(
        "timing",
        Function("clip_timing", ("frame_time", "n_frames"), clip_timing,
                 Check((2,), atol=1e-3, noun="timing")),
        _timings,
        hint="The frame time is how long one frame lasts, in seconds. How many of them fit in "
             "one second? And how long do all the frames of the clip last, one after another?",
        formula="fps = 1 / frame_time; duration = n_frames · frame_time (seconds), as "
                "<code>walk.fps</code> and <code>walk.duration</code>.",
        mistakes=(
            Misconception("last_frame_time", "clip_timing",
                          "the time of the last frame as the duration",
                          "Frame k starts at k · frame_time, so the last one starts at "
                          "(n_frames − 1) · frame_time; it still lasts one frame time: the clip "
                          "lasts n_frames · frame_time.",
                          wrong=lambda dt, n: np.array([1 / dt, (n - 1) * dt])),
            Misconception("divided_by_frame_time", "clip_timing",
                          "the frame count divided by the frame time",
                          "n_frames / frame_time has units of frames² per second; the duration "
                          "is n_frames · frame_time = n_frames / fps.",
                          wrong=lambda dt, n: np.array([1 / dt, n / dt])),
        ),
    ),
    Exercise(
        "channels",
        Function("channel_rotation", ("angles_deg", "order"), channel_rotation, QuatCheck()),
        _channels,
        hint="Build one quaternion per channel (its axis, its angle — in which unit?), then "
             "multiply them in the order the channels are listed: intrinsic, so the first "
             "listed stands leftmost.",
        formula="order 'ZYX', angles (γ, β, α) in degrees: q = q_Z(γ) q_Y(β) q_X(α), with "
                "q_axis(θ) = <code>rot.quat_from_axis_angle(axis, np.radians(θ))</code>.",
        mistakes=(
            Misconception("extrinsic", "channel_rotation", "the product in the reverse order",
                          "BVH channels compose intrinsically, in the listed order: "
                          "'Zrotation Yrotation Xrotation' is q_Z q_Y q_X (the first channel "
                          "leftmost); q_X q_Y q_Z is the extrinsic reading.",
                          wrong=_reversed_product),
            Misconception("degrees_as_radians", "channel_rotation", "degrees used as radians",
                          "BVH angles are in degrees: convert them with np.radians before "
                          "building the rotations.",
                          wrong=lambda a, order: quat_from_euler(a, order)),
        ),
    ),
)
