"""Rotation representations and conversions (numpy only, batched over leading dimensions).

Conventions (``docs/conventions.md``): quaternions ``(w, x, y, z)``, Hamilton product, active
rotations; Euler order strings as in scipy (``"XYZ"`` intrinsic, ``"xyz"`` extrinsic); radians
unless ``degrees=True``. Names are ``<target>_from_<source>``. One module per topic:
:mod:`.quaternion`, :mod:`.axis_angle` (and rotation vectors), :mod:`.euler`,
:mod:`.interpolation`, :mod:`.vectors`.
"""

from .axis_angle import (
    DEFAULT_AXIS,
    axis_angle_from_matrix,
    axis_angle_from_quat,
    matrix_from_axis_angle,
    matrix_from_rotvec,
    quat_from_axis_angle,
    quat_from_rotvec,
    rotvec_from_matrix,
    rotvec_from_quat,
)
from .euler import (
    EULER_ORDERS,
    GIMBAL_LOCK_TOL,
    PROPER_EULER_ORDERS,
    TAIT_BRYAN_ORDERS,
    euler_from_matrix,
    euler_from_quat,
    gimbal_lock_distance,
    is_gimbal_lock,
    matrix_from_euler,
    quat_from_euler,
)
from .interpolation import lerp, nlerp, quat_angle, slerp
from .quaternion import (
    matrix_from_quat,
    quat_canonical,
    quat_conjugate,
    quat_from_matrix,
    quat_identity,
    quat_inverse,
    quat_mul,
    quat_normalize,
    quat_rotate,
)
from .swing_twist import clamp_swing_twist, swing_angle, swing_twist, twist_angle
from .vectors import quat_between, skew

__all__ = [
    "DEFAULT_AXIS",
    "EULER_ORDERS",
    "GIMBAL_LOCK_TOL",
    "PROPER_EULER_ORDERS",
    "TAIT_BRYAN_ORDERS",
    "axis_angle_from_matrix",
    "axis_angle_from_quat",
    "clamp_swing_twist",
    "euler_from_matrix",
    "euler_from_quat",
    "gimbal_lock_distance",
    "is_gimbal_lock",
    "lerp",
    "matrix_from_axis_angle",
    "matrix_from_euler",
    "matrix_from_quat",
    "matrix_from_rotvec",
    "nlerp",
    "quat_angle",
    "quat_between",
    "quat_canonical",
    "quat_conjugate",
    "quat_from_axis_angle",
    "quat_from_euler",
    "quat_from_matrix",
    "quat_from_rotvec",
    "quat_identity",
    "quat_inverse",
    "quat_mul",
    "quat_normalize",
    "quat_rotate",
    "rotvec_from_matrix",
    "rotvec_from_quat",
    "skew",
    "slerp",
    "swing_angle",
    "swing_twist",
    "twist_angle",
]
