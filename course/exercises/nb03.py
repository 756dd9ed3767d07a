"""Notebook 03 · BVH: a joint's rotation channels to one quaternion."""

from __future__ import annotations

import numpy as np

from autograder.checks import QuatCheck
from autograder.spec import Case, Function, Misconception

from ..rotations import quat_from_axis_angle, quat_from_euler, quat_mul
from .check import Exercise


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
