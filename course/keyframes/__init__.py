r"""Keyframe animation 关键帧动画: curves through keys, rotation splines, clips rebuilt and blended.

One module per step of the lecture:

* :mod:`.curves`: position keys 关键帧 on a time line and the interpolation 插值 family,
  :func:`linear`, :func:`polynomial` (Runge), :func:`cubic` (natural/clamped spline 样条),
  :func:`hermite`, :func:`catmull_rom`, :func:`bezier` (de Casteljau), with velocities;
* :mod:`.rotations`: rotation keys, :func:`slerp_keys` per segment and :func:`squad`;
* :mod:`.motion`: keyframing a :class:`~course.motion.Motion` every k frames and the error;
* :mod:`.blend`: aligning, cross-fading and concatenating two clips, and their foot
  contacts (foot sliding itself: :mod:`course.foot_sliding`).
"""

from ..data.registry import CMU_CM_PER_UNIT
from .blend import aligned, concatenate, concatenated_contacts, facing_yaw, smoothstep
from .curves import (
    KNOTS,
    bezier,
    catmull_rom,
    check_times,
    continuity_jumps,
    cubic,
    cubic_tangents,
    hermite,
    linear,
    newton_coefficients,
    polynomial,
)
from .motion import joint_position_error, key_frames, keyframed
from .rotations import (
    angular_velocity,
    angular_velocity_jump,
    quat_exp,
    quat_log,
    same_hemisphere,
    slerp_keys,
    squad,
    squad_controls,
)

__all__ = [
    "CMU_CM_PER_UNIT",
    "KNOTS",
    "aligned",
    "angular_velocity",
    "angular_velocity_jump",
    "bezier",
    "catmull_rom",
    "check_times",
    "continuity_jumps",
    "concatenate",
    "concatenated_contacts",
    "cubic",
    "cubic_tangents",
    "facing_yaw",
    "hermite",
    "joint_position_error",
    "key_frames",
    "keyframed",
    "linear",
    "newton_coefficients",
    "polynomial",
    "quat_exp",
    "quat_log",
    "same_hemisphere",
    "slerp_keys",
    "smoothstep",
    "squad",
    "squad_controls",
]
