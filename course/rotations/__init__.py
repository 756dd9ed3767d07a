"""Rotation representations and conversions (numpy only, batched over leading dimensions)."""

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

__all__ = [
    "matrix_from_quat",
    "quat_canonical",
    "quat_conjugate",
    "quat_identity",
    "quat_inverse",
    "quat_mul",
    "quat_normalize",
    "quat_from_matrix",
    "quat_rotate",
]
