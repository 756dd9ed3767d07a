r"""The zero-moment point 零力矩点 (ZMP) and the support polygon 支撑多边形 (lecture 11).

The ZMP is the point :math:`p` on the ground about which the ground's reaction has no
horizontal moment; on flat ground it is the centre of pressure. A body is dynamically
balanced (its feet do not start to roll over an edge) while :math:`p` is inside the support
polygon, the convex hull of its contacts with the ground. Three ways to get it:

1. **From contact forces** (:func:`zmp_from_forces`): point forces :math:`f_i` at
   :math:`r_i`, the ground at height :math:`p_y`,

   .. math::

       p_x = \frac{\sum_i x_i f_{i,y} - (y_i - p_y) f_{i,x}}{\sum_i f_{i,y}}, \qquad
       p_z = \frac{\sum_i z_i f_{i,y} - (y_i - p_y) f_{i,z}}{\sum_i f_{i,y}},

   which for contacts on the ground (:math:`y_i = p_y`) is the lecture's
   :math:`p = \sum_i p_i f_{i,y} / \sum_i f_{i,y}`. From a MuJoCo state:
   :func:`zmp_from_mujoco` (contacts with the world body, ``mj_contactForce``).
2. **From the centre of mass** (:func:`zmp_from_com`): Newton and Euler for the whole body,
   ground reaction :math:`F = M(\ddot c + g\hat y)`, and its moment about :math:`p` equal to
   :math:`(c - p)\times F + \dot H` with :math:`\dot H` the rate of angular momentum about the
   COM:

   .. math::

       p_x = c_x - (c_y - p_y)\frac{\ddot c_x}{\ddot c_y + g} + \frac{\dot H_z}{M(\ddot c_y + g)},
       \qquad
       p_z = c_z - (c_y - p_y)\frac{\ddot c_z}{\ddot c_y + g} - \frac{\dot H_x}{M(\ddot c_y + g)}.

   Without :math:`\dot H` it is the lecture's single-mass (cart-table) formula; the signs of
   the :math:`\dot H` terms are those of y up (x right, z forward).
3. **From a kinematic clip** (:func:`zmp_from_motion`): the multi-body version of 2, with the
   package's mass model (:func:`segment_masses`: the bodies of the MuJoCo character
   :func:`~course.physics.model.build_model` makes of the skeleton) placed by the package's
   forward kinematics, accelerations by central second differences of the segment COMs, and
   :math:`\dot H` summed over the segments (their COMs' motion about the whole-body COM and,
   optionally, each segment's spin :math:`\tfrac{d}{dt}(I_k\omega_k)`).

The support polygon of a clip (:func:`support_polygons`): per frame, the foot joints in
contact (:func:`course.foot_sliding.foot_contacts`: low *and* slow), projected on the ground,
their convex hull in x–z (:func:`convex_hull`), widened by a foot radius; the ZMP is inside when
its signed distance (:func:`polygon_distance`) is at most the radius. :func:`clip_zmp` puts it
together for a character and a clip.

Conventions: y up, ground plane x–z, gravity ``(0, -g, 0)`` with ``g = 9.81`` m/s²; points
are ``(..., 3)`` arrays, polygon vertices and ground-plane points ``(..., 2)`` arrays of
``(x, z)``. A ZMP that does not exist (no vertical support: no contact force, or the COM
falling at ``g`` or faster) is NaN, not an error, so a whole clip can be computed at once.
``docs/walking.md`` says which formula and why, with the figures measured on the CMU walk.
MuJoCo is imported only by :func:`zmp_from_mujoco` and :func:`mujoco_ground_contacts`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array, BoolArray
from .._validate import as_array, as_positive
from ..motion import Motion
from ..rotations import matrix_from_quat
from ..rotations._kernels import rotvec_from_matrix
from .lip import G
from .model import Y_TO_Z_MATRIX, Character, import_mujoco

# -- the ZMP from forces and from the COM ----------------------------------------------------


def _ground(height: ArrayLike | None, name: str = "ground_height") -> Array | None:
    return None if height is None else as_array(height, name)


def zmp_from_forces(positions: ArrayLike, forces: ArrayLike, *,
                    ground_height: ArrayLike | None = None) -> Array:
    r"""The ZMP (centre of pressure) of point contact forces on flat ground.

    .. math::

        p_x = \frac{\sum_i x_i f_{i,y} - (y_i - p_y) f_{i,x}}{\sum_i f_{i,y}}, \quad
        p_z = \frac{\sum_i z_i f_{i,y} - (y_i - p_y) f_{i,z}}{\sum_i f_{i,y}}, \quad
        p_y = \text{ground height}:

    the point of the ground plane about which the forces' moment has no horizontal part. For
    points on the ground it is the lecture's :math:`\sum_i p_i f_{i,y} / \sum_i f_{i,y}`.

    Parameters
    ----------
    positions : array_like, shape (..., k, 3)
        Contact points :math:`r_i`, y up.
    forces : array_like, shape (..., k, 3)
        The force the ground exerts on the body at each point (its y part is the push up,
        positive), broadcast with ``positions``.
    ground_height : array_like, shape (...), optional
        :math:`p_y`. Default: the force-weighted mean height of the points,
        :math:`\sum_i y_i f_{i,y} / \sum_i f_{i,y}` (their height, for points on flat ground).

    Returns
    -------
    ndarray, shape (..., 3)
        The ZMP; NaN where the total vertical force is not positive (no support: airborne or
        pulled down).
    """
    r = as_array(positions, "positions", (3,))
    f = as_array(forces, "forces", (3,))
    if r.ndim < 2 or f.ndim < 2:
        raise ValueError(f"positions, forces: expected shape (..., k, 3), got {r.shape} and "
                         f"{f.shape}")
    try:
        r, f = np.broadcast_arrays(r, f)
    except ValueError:
        raise ValueError(f"zmp_from_forces: positions {r.shape} and forces {f.shape} do not "
                         "broadcast together") from None
    fy = f[..., 1].sum(axis=-1)
    ok = fy > 0
    safe = np.where(ok, fy, 1.0)
    h = _ground(ground_height)
    py = (r[..., 1] * f[..., 1]).sum(axis=-1) / safe if h is None else np.broadcast_to(
        h, fy.shape)
    arm = r[..., 1] - py[..., None]
    px = (r[..., 0] * f[..., 1] - arm * f[..., 0]).sum(axis=-1) / safe
    pz = (r[..., 2] * f[..., 1] - arm * f[..., 2]).sum(axis=-1) / safe
    out: Array = np.where(ok[..., None], np.stack([px, py * np.ones_like(px), pz], -1), np.nan)
    return out


def zmp_from_com(com: ArrayLike, com_acceleration: ArrayLike, *, ground_height: ArrayLike = 0.0,
                 g: float = G, mass: ArrayLike | None = None,
                 angular_momentum_rate: ArrayLike | None = None) -> Array:
    r"""The ZMP of a body from its centre of mass (and, optionally, its angular momentum).

    .. math::

        p_x = c_x - (c_y - p_y)\frac{\ddot c_x}{\ddot c_y + g}
              + \frac{\dot H_z}{M(\ddot c_y + g)}, \qquad
        p_z = c_z - (c_y - p_y)\frac{\ddot c_z}{\ddot c_y + g}
              - \frac{\dot H_x}{M(\ddot c_y + g)},

    with :math:`p_y` the ground height. Without ``angular_momentum_rate`` it is the lecture's
    single-mass formula (a COM accelerating forwards puts the ZMP *behind* it). At rest
    (:math:`\ddot c = 0, \dot H = 0`) the ZMP is the COM's projection on the ground.

    Parameters
    ----------
    com : array_like, shape (..., 3)
        :math:`c`, y up.
    com_acceleration : array_like, shape (..., 3)
        :math:`\ddot c`, in the units of ``com`` per second squared.
    ground_height : array_like, shape (...)
        :math:`p_y`.
    g : float
        Gravity's magnitude in the same units (9.81 for meters).
    mass : array_like, shape (...), optional
        :math:`M` (kg); needed with ``angular_momentum_rate``.
    angular_momentum_rate : array_like, shape (..., 3), optional
        :math:`\dot H`, the rate of the angular momentum about the COM (N m with meters),
        y-up world axes.

    Returns
    -------
    ndarray, shape (..., 3)
        NaN where :math:`\ddot c_y + g \le 0` (the COM falls at ``g`` or faster: nothing
        pushes up).
    """
    c = as_array(com, "com", (3,))
    a = as_array(com_acceleration, "com_acceleration", (3,))
    h = as_array(ground_height, "ground_height")
    g = as_positive(g, "g")
    try:
        shape = np.broadcast_shapes(c.shape[:-1], a.shape[:-1], h.shape)
    except ValueError:
        raise ValueError(f"zmp_from_com: com {c.shape}, com_acceleration {a.shape} and "
                         f"ground_height {h.shape} do not broadcast together") from None
    support = a[..., 1] + g
    ok = support > 0
    s = np.where(ok, support, 1.0)
    height = c[..., 1] - h
    px = c[..., 0] - height * a[..., 0] / s
    pz = c[..., 2] - height * a[..., 2] / s
    if angular_momentum_rate is not None:
        if mass is None:
            raise ValueError("mass: needed with angular_momentum_rate (the H-dot terms are "
                             "divided by M (c̈_y + g))")
        hdot = as_array(angular_momentum_rate, "angular_momentum_rate", (3,))
        m = as_array(mass, "mass")
        if not np.all(m > 0):
            raise ValueError(f"mass: must be positive, got {mass!r}")
        px = px + hdot[..., 2] / (m * s)
        pz = pz - hdot[..., 0] / (m * s)
    p = np.stack(np.broadcast_arrays(px, np.broadcast_to(h, shape), pz), -1)
    out: Array = np.where(ok[..., None], p, np.nan)
    return out


def _multibody(r: Array, a: Array, m: Array, spin: Array | None) -> tuple[Array, Array, Array]:
    """COM, COM acceleration and the rate of angular momentum about the COM of point masses
    ``m`` (B,) at ``r`` with accelerations ``a`` (..., B, 3), plus ``spin`` (..., 3)."""
    total = m.sum()
    c = np.einsum("b,...bi->...i", m, r) / total
    cdd = np.einsum("b,...bi->...i", m, a) / total
    rho = r - c[..., None, :]
    hdot = np.einsum("b,...bi->...i", m, np.cross(rho, a))  # sum m rho x a (sum m rho = 0)
    if spin is not None:
        hdot = hdot + spin
    return c, cdd, hdot


def zmp_from_points(positions: ArrayLike, accelerations: ArrayLike, masses: ArrayLike, *,
                    ground_height: ArrayLike = 0.0, g: float = G) -> Array:
    r"""The ZMP of point masses: :func:`zmp_from_com` with the system's COM, COM acceleration
    and :math:`\dot H = \sum_k m_k (r_k - c)\times \ddot r_k`.

    Equivalently :math:`p_x = \frac{\sum_k m_k[(\ddot y_k + g) x_k - (y_k - p_y)\ddot x_k]}
    {\sum_k m_k(\ddot y_k + g)}` and the same for :math:`p_z` (Kajita's multi-body formula,
    segments as point masses).

    Parameters
    ----------
    positions, accelerations : array_like, shape (..., B, 3)
        Each mass's position and acceleration (units of length, and per second squared).
    masses : array_like, shape (B,)
        Kilograms (positive).
    ground_height : array_like, shape (...)
    g : float
        Gravity's magnitude in the units of ``positions`` per second squared.

    Returns
    -------
    ndarray, shape (..., 3)
    """
    r = as_array(positions, "positions", (3,))
    a = as_array(accelerations, "accelerations", (3,))
    m = as_array(masses, "masses")
    if m.ndim != 1 or not np.all(m > 0) or r.ndim < 2 or r.shape[-2] != m.shape[0]:
        raise ValueError(f"masses: expected B positive masses, one per point of positions "
                         f"{r.shape}, got shape {m.shape}")
    try:
        r, a = np.broadcast_arrays(r, a)
    except ValueError:
        raise ValueError(f"zmp_from_points: positions {r.shape} and accelerations {a.shape} "
                         "do not broadcast together") from None
    c, cdd, hdot = _multibody(r, a, m, None)
    return zmp_from_com(c, cdd, ground_height=ground_height, g=g, mass=m.sum(),
                        angular_momentum_rate=hdot)


# -- the mass model and the kinematic ZMP ----------------------------------------------------


@dataclass(frozen=True, eq=False)
class SegmentMasses:
    """Rigid segments attached to a skeleton's joints: the mass model of a clip.

    Made by :func:`segment_masses` from the bodies of a MuJoCo character, so the kinematic
    ZMP of a clip and the simulated character share one mass model.

    Attributes
    ----------
    joints : tuple of int, length B
        The skeleton joint each segment moves with (its frame is the joint's global frame).
    masses : ndarray, shape (B,)
        Kilograms.
    com : ndarray, shape (B, 3)
        Each segment's COM in its joint's frame, y up, skeleton units.
    inertia : ndarray, shape (B, 3, 3)
        Each segment's inertia tensor about its COM, in its joint's frame (y up), kg m².
    scale : float
        Meters per skeleton unit.
    """

    joints: tuple[int, ...]
    masses: Array
    com: Array
    inertia: Array
    scale: float

    @property
    def total_mass(self) -> float:
        """Kilograms."""
        return float(self.masses.sum())


def segment_masses(character: Character) -> SegmentMasses:
    """The mass model of ``character``'s skeleton: one segment per MuJoCo body.

    Each body of :func:`~course.physics.model.build_model` (a sphere at the joint and a
    capsule per bone to each child, ``density`` times volume) gives its mass, COM
    (``body_ipos``) and principal inertia (``body_inertia`` in the frame ``body_iquat``),
    turned from MuJoCo's z-up body frame to the joint's y-up frame (the two agree at rest,
    :mod:`course.physics.model`). Reads the compiled model only: MuJoCo is not called.
    """
    model = character.model
    joints = character.simulated_joints
    bodies = np.array([character.bodies[j] for j in joints])
    C = Y_TO_Z_MATRIX  # v_z = C v_y
    com = model.body_ipos[bodies] @ C / character.scale  # C^T v_z, row-wise
    R = matrix_from_quat(np.asarray(model.body_iquat[bodies], dtype=float))  # z-up
    I_z = R @ (np.asarray(model.body_inertia[bodies], dtype=float)[:, :, None]
               * np.swapaxes(R, -1, -2))
    inertia = C.T @ I_z @ C
    return SegmentMasses(tuple(joints), np.asarray(model.body_mass[bodies], dtype=float),
                         np.asarray(com, dtype=float), np.asarray(inertia, dtype=float),
                         character.scale)


def segment_positions(motion: Motion, masses: SegmentMasses) -> tuple[Array, Array]:
    """Each segment's COM and orientation in every frame, by the package's FK.

    Returns
    -------
    com : ndarray, shape (F, B, 3)
        World COM of each segment, y up, skeleton units: :math:`p_j + Q_j\\,\\bar c_k`.
    rotation : ndarray, shape (F, B, 3, 3)
        Each segment's world orientation :math:`Q_j` as a matrix.
    """
    if max(masses.joints, default=-1) >= motion.n_joints:
        raise ValueError(f"masses: made for a skeleton with more joints than the motion's "
                         f"{motion.n_joints}")
    positions, orientations = motion.forward_kinematics()
    js = list(masses.joints)
    R = matrix_from_quat(orientations[:, js])
    com: Array = positions[:, js] + np.einsum("fbij,bj->fbi", R, masses.com)
    return com, R


@dataclass(frozen=True, eq=False)
class KinematicZMP:
    """What :func:`zmp_from_motion` returns; frame by frame, NaN where not defined.

    Attributes
    ----------
    zmp : ndarray, shape (F, 3)
        The multi-body ZMP, y up, skeleton units, on the ground (``zmp[:, 1]`` is
        ``ground_height``). NaN in the first and last ``stride`` frames (no central
        difference) and where nothing pushes up.
    zmp_com : ndarray, shape (F, 3)
        The single-mass ZMP (the lecture's formula, :math:`\\dot H` left out), for comparison.
    com : ndarray, shape (F, 3)
        Whole-body COM, skeleton units.
    com_acceleration : ndarray, shape (F, 3)
        m/s² (meters, whatever the skeleton's unit).
    angular_momentum_rate : ndarray, shape (F, 3)
        :math:`\\dot H` about the COM, N m (kg m²/s²), y-up world axes; with or without the
        segments' spin as asked.
    ground_height : float
        Skeleton units.
    stride : int
        Frames between the samples of the central differences.
    """

    zmp: Array
    zmp_com: Array
    com: Array
    com_acceleration: Array
    angular_momentum_rate: Array
    ground_height: float
    stride: int


def _second_difference(x: Array, s: int, dt: float) -> Array:
    """``(x[i+s] - 2 x[i] + x[i-s]) / (s dt)^2`` along axis 0, NaN where it does not exist."""
    out = np.full_like(x, np.nan)
    out[s:-s] = (x[2 * s:] - 2.0 * x[s:-s] + x[: -2 * s]) / (s * dt) ** 2
    return out


def _spin_rate(R: Array, inertia: Array, s: int, dt: float) -> Array:
    r""":math:`\sum_k \frac{d}{dt}(I_k\omega_k)` by central differences (F, 3), NaN at the ends.

    Between samples ``i`` and ``i + s``: :math:`\omega = \log(R_{i+s}R_i^T)/(s\,\Delta t)`
    (world frame), :math:`I = \tfrac12(I_i + I_{i+s})` with :math:`I_i = R_i \bar I R_i^T`;
    then the difference of those angular momenta over the two intervals around ``i``.
    """
    I_w = R @ inertia @ np.swapaxes(R, -1, -2)  # (F, B, 3, 3)
    omega = rotvec_from_matrix(R[s:] @ np.swapaxes(R[:-s], -1, -2)) / (s * dt)
    L = np.einsum("fbij,fbj->fi", 0.5 * (I_w[s:] + I_w[:-s]), omega)  # (F - s, 3)
    out = np.full((R.shape[0], 3), np.nan)
    out[s:-s] = (L[s:] - L[:-s]) / (s * dt)
    return out


#: The default time between the samples of :func:`zmp_from_motion`'s differences: 1/20 s.
DIFFERENCE_SPACING = 0.05


def default_stride(frame_time: float) -> int:
    """Frames nearest :data:`DIFFERENCE_SPACING` seconds (at least 1): 6 at 120 fps, 3 at 60."""
    return max(1, round(DIFFERENCE_SPACING / as_positive(frame_time, "frame_time")))


def zmp_from_motion(motion: Motion, masses: SegmentMasses, *, ground_height: float | None = None,
                    stride: int | None = None, spin: bool = True, g: float = G) -> KinematicZMP:
    r"""The ZMP of a captured clip from kinematics alone, frame by frame.

    The segments of ``masses`` are placed by forward kinematics (:func:`segment_positions`);
    their COM accelerations are central second differences,
    :math:`\ddot r_i = (r_{i+s} - 2 r_i + r_{i-s}) / (s\,\Delta t)^2` with ``s = stride``;
    the rate of angular momentum about the whole-body COM is
    :math:`\dot H = \sum_k m_k (r_k - c)\times\ddot r_k` plus, with ``spin``, each segment's
    :math:`\tfrac{d}{dt}(I_k\omega_k)` (the angular velocity over each interval of ``s``
    frames from the relative rotation, :math:`\omega = \log(R_{i+s}R_i^T)/(s\,\Delta t)`,
    times the inertia averaged over it, differenced across frame ``i``); then
    :func:`zmp_from_com`. Computed in meters (``masses.scale``), returned in
    skeleton units.

    Parameters
    ----------
    motion : Motion
        ``F`` frames, at least ``2 stride + 1``. Drop a converter's T-pose frame first (the
        CMU clips' frame 0): its jump to the first real frame is a huge acceleration.
    masses : SegmentMasses
        The mass model (:func:`segment_masses` of a character built from this skeleton).
    ground_height : float, optional
        Skeleton units; default the lowest any joint gets in the clip (a walk's toe tips).
    stride : int, optional
        Samples ``stride`` frames apart for the differences (1: consecutive frames); default
        :func:`default_stride`, the frames nearest 1/20 s. A second difference amplifies
        noise of amplitude :math:`\epsilon` to :math:`4\epsilon/(s\Delta t)^2`: on the CMU
        walk at 120 fps, consecutive frames give a COM acceleration with a 3-5 m/s² standard
        deviation (mostly noise), 1/20 s gives 0.7-1.4 m/s², and it keeps 97% of a 2 Hz
        (step frequency) component and 81% of 5 Hz (gain :math:`(2 - 2\cos\omega h) /
        (\omega h)^2`, :math:`h = s\Delta t`).
    spin : bool
        Include the segments' own rotational inertia in :math:`\dot H` (else point masses).
    g : float
        Gravity, m/s².

    Returns
    -------
    KinematicZMP
    """
    if not isinstance(motion, Motion):
        raise ValueError(f"motion: expected a course.motion.Motion, got {type(motion).__name__}")
    if not isinstance(masses, SegmentMasses):
        raise ValueError(f"masses: expected a SegmentMasses (segment_masses(character)), got "
                         f"{type(masses).__name__}")
    if stride is None:
        stride = default_stride(motion.frame_time)
    if isinstance(stride, bool) or not isinstance(stride, int | np.integer) or stride < 1:
        raise ValueError(f"stride: a whole number of frames, at least 1, got {stride!r}")
    s = int(stride)
    if motion.n_frames < 2 * s + 1:
        raise ValueError(f"motion: {motion.n_frames} frames; central differences with stride "
                         f"{s} need at least {2 * s + 1}")
    g = as_positive(g, "g")
    scale = masses.scale
    com_k, R = segment_positions(motion, masses)
    if ground_height is None:
        ground = float(motion.forward_kinematics()[0][..., 1].min())
    else:
        ground = float(as_array(ground_height, "ground_height"))
    r = com_k * scale
    a = _second_difference(r, s, motion.frame_time)
    spin_rate = _spin_rate(R, masses.inertia, s, motion.frame_time) if spin else None
    c, cdd, hdot = _multibody(r, a, masses.masses, spin_rate)
    zmp = zmp_from_com(np.nan_to_num(c), np.nan_to_num(cdd), ground_height=ground * scale, g=g,
                       mass=masses.total_mass, angular_momentum_rate=np.nan_to_num(hdot))
    single = zmp_from_com(np.nan_to_num(c), np.nan_to_num(cdd), ground_height=ground * scale,
                          g=g)
    undefined = np.isnan(cdd).any(axis=-1) | np.isnan(hdot).any(axis=-1)
    zmp[undefined] = np.nan
    single[undefined] = np.nan
    return KinematicZMP(zmp=zmp / scale, zmp_com=single / scale, com=c / scale,
                        com_acceleration=cdd, angular_momentum_rate=hdot, ground_height=ground,
                        stride=s)


# -- support polygons ------------------------------------------------------------------------


def convex_hull(points: ArrayLike) -> Array:
    """The convex hull of points on the ground plane, counter-clockwise seen from above.

    Andrew's monotone chain. "Counter-clockwise" in the ``(x, z)`` plane as drawn with x to
    the right and z up the page (the cross product ``(b - a) x (c - a)`` of consecutive
    vertices is positive). Points on an edge (to within 1e-12 of the points' extent squared
    in that cross product) and repeated points are dropped.

    Parameters
    ----------
    points : array_like, shape (n, 2)
        ``(x, z)``.

    Returns
    -------
    ndarray, shape (m, 2)
        The hull's vertices (the first not repeated at the end): ``m = 0`` for no points, 1
        for coincident points, 2 for collinear ones (a segment), otherwise a polygon.
    """
    pts = as_array(points, "points", (2,))
    if pts.ndim != 2:
        raise ValueError(f"points: expected shape (n, 2), got {pts.shape}")
    pts = np.unique(pts, axis=0)  # sorted by x, then z
    if len(pts) <= 2:
        return pts
    # a turn this small (relative to the points' extent squared) is a straight line
    tol = 1e-12 * float(np.ptp(pts, axis=0).max()) ** 2

    def half(seq: Array) -> list[Array]:
        chain: list[Array] = []
        for p in seq:
            while len(chain) >= 2 and _cross(chain[-2], chain[-1], p) <= tol:
                chain.pop()
            chain.append(p)
        return chain

    lower, upper = half(pts), half(pts[::-1])
    hull = np.array(lower[:-1] + upper[:-1])
    return hull


def _cross(o: Array, a: Array, b: Array) -> float:
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def polygon_distance(polygon: ArrayLike, points: ArrayLike) -> Array:
    """Signed distance from points to a convex polygon on the ground plane: negative inside.

    Outside, the distance to the nearest point of the polygon; inside, minus the distance to
    its boundary. A polygon of 1 or 2 vertices (a point, a segment: one foot's contact line)
    has no inside: the distance is never negative there.

    Parameters
    ----------
    polygon : array_like, shape (m, 2)
        Convex, counter-clockwise (:func:`convex_hull`), ``m >= 1``.
    points : array_like, shape (..., 2)
        ``(x, z)``.

    Returns
    -------
    ndarray, shape (...)
    """
    v = as_array(polygon, "polygon", (2,))
    if v.ndim != 2 or len(v) == 0:
        raise ValueError(f"polygon: expected shape (m, 2) with m >= 1, got {v.shape}")
    x = as_array(points, "points", (2,))
    if len(v) == 1:
        out: Array = np.linalg.norm(x - v[0], axis=-1)
        return out
    a, b = v, np.roll(v, -1, axis=0)  # edges a -> b
    e = b - a  # (m, 2)
    w = x[..., None, :] - a  # (..., m, 2)
    t = np.clip(np.einsum("...mi,mi->...m", w, e) / np.einsum("mi,mi->m", e, e), 0.0, 1.0)
    dist: Array = np.asarray(np.linalg.norm(w - t[..., None] * e, axis=-1).min(axis=-1))
    if len(v) < 3:
        return dist
    cross = e[:, 0] * w[..., 1] - e[:, 1] * w[..., 0]  # (..., m)
    inside = (cross >= 0).all(axis=-1)
    signed: Array = np.where(inside, -dist, dist)
    return signed


def in_polygon(polygon: ArrayLike, points: ArrayLike, margin: float = 0.0) -> BoolArray:
    """Whether points are in a convex polygon widened by ``margin``:
    :func:`polygon_distance` ``<= margin``. Shape (...)."""
    inside: BoolArray = polygon_distance(polygon, points) <= float(margin)
    return inside


@dataclass(frozen=True, eq=False)
class SupportPolygons:
    """The support polygon of every frame of a clip (:func:`support_polygons`).

    Attributes
    ----------
    polygons : tuple of ndarray, length F
        Frame ``f``'s :func:`convex_hull` ``(m_f, 2)`` of the ground projections ``(x, z)``
        of its foot joints in contact (``(0, 2)``: none, airborne).
    contacts : ndarray of bool, shape (F, n)
        Which foot joint is in contact in which frame.
    feet : tuple of str, length n
        The foot joints.
    radius : float
        Each contact is a disc of this radius (skeleton units): the support region is the
        hull widened by it (the foot's half width; 0 for bare points).
    """

    polygons: tuple[Array, ...]
    contacts: BoolArray
    feet: tuple[str, ...]
    radius: float

    @property
    def airborne(self) -> BoolArray:
        """Frames with no foot joint in contact, shape (F,)."""
        out: BoolArray = np.logical_not(self.contacts.any(axis=1))
        return out

    def signed_distance(self, points: ArrayLike) -> Array:
        """Per frame, the signed distance of a point to the support region (negative inside):
        :func:`polygon_distance` to the hull minus :attr:`radius`.

        Parameters
        ----------
        points : array_like, shape (F, 2) or (F, 3)
            One point per frame: ``(x, z)``, or y-up points (their x and z are used); NaN
            allowed (the answer is NaN there, as for airborne frames).
        """
        p = np.asarray(points, dtype=float)
        if p.ndim != 2 or p.shape[0] != len(self.polygons) or p.shape[1] not in (2, 3):
            raise ValueError(f"points: expected shape ({len(self.polygons)}, 2) or "
                             f"({len(self.polygons)}, 3), got {p.shape}")
        xz = p[:, [0, 2]] if p.shape[1] == 3 else p
        out = np.full(len(self.polygons), np.nan)
        for f, poly in enumerate(self.polygons):
            if len(poly) and np.isfinite(xz[f]).all():
                out[f] = float(polygon_distance(poly, xz[f])) - self.radius
        return out

    def contains(self, points: ArrayLike) -> BoolArray:
        """Per frame, whether the point is in the support region (False where undefined)."""
        d = self.signed_distance(points)
        inside: BoolArray = np.nan_to_num(d, nan=np.inf) <= 0.0
        return inside


def support_polygons(motion: Motion, feet: Sequence[str], *, radius: float = 0.0,
                     contacts: ArrayLike | None = None, height_tolerance: float | None = None,
                     speed_tolerance: float | None = None) -> SupportPolygons:
    """The support polygon of each frame: the hull of the foot joints in contact.

    The contact test is :func:`course.foot_sliding.foot_contacts`: a foot joint is in contact
    when it is within ``height_tolerance`` of its own lowest height in the clip and its
    horizontal speed is at most ``speed_tolerance`` (defaults: 0.1 and 0.3 per second of the
    rest hip height). The joints in contact are projected on the ground (their x, z), hulled
    (:func:`convex_hull`) and the hull widened by ``radius``.

    Parameters
    ----------
    motion : Motion
    feet : sequence of str
        Foot joint names, e.g. ankle, toe and toe tip of each foot
        (:func:`course.physics.balance.foot_chains`).
    radius : float
        Skeleton units, non-negative.
    contacts : array_like of bool, shape (F, n), optional
        Given contacts instead of the test.
    height_tolerance, speed_tolerance : float, optional
        As :func:`~course.foot_sliding.foot_contacts`.

    Returns
    -------
    SupportPolygons
    """
    from ..foot_sliding import foot_contacts

    radius = as_positive(radius, "radius", allow_zero=True)
    if isinstance(feet, str) or not len(feet):
        raise ValueError(f"feet: expected a non-empty sequence of joint names, got {feet!r}")
    on = (foot_contacts(motion, feet, height_tolerance, speed_tolerance) if contacts is None
          else np.asarray(contacts))
    if on.dtype != np.bool_ or on.shape != (motion.n_frames, len(feet)):
        raise ValueError(f"contacts: expected booleans of shape ({motion.n_frames}, "
                         f"{len(feet)}), got {on.dtype} {on.shape}")
    js = [motion.skeleton.index(f) for f in feet]
    xz = motion.forward_kinematics()[0][:, js][..., [0, 2]]
    polygons = tuple(convex_hull(xz[f][on[f]]) for f in range(motion.n_frames))
    return SupportPolygons(polygons, on, tuple(feet), radius)


# -- a character's clip ----------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class ClipZMP:
    """The kinematic ZMP of a clip against its support polygons (:func:`clip_zmp`).

    Attributes
    ----------
    kinematic : KinematicZMP
    support : SupportPolygons
    distance : ndarray, shape (F,)
        Signed distance of the ZMP to the support region, skeleton units (negative inside);
        NaN where either is undefined (the differences' end frames, airborne frames).
    scale : float
        Meters per skeleton unit.
    """

    kinematic: KinematicZMP
    support: SupportPolygons
    distance: Array
    scale: float

    @property
    def defined(self) -> BoolArray:
        """Frames with both a ZMP and a support polygon, shape (F,)."""
        out: BoolArray = np.isfinite(self.distance)
        return out

    @property
    def inside(self) -> BoolArray:
        """Frames whose ZMP is in the support region, shape (F,)."""
        out: BoolArray = self.defined & (np.nan_to_num(self.distance, nan=np.inf) <= 0)
        return out

    @property
    def fraction_inside(self) -> float:
        """Share of the defined frames whose ZMP is inside, in [0, 1]."""
        n = int(self.defined.sum())
        return float(self.inside.sum()) / n if n else float("nan")

    @property
    def distance_cm(self) -> Array:
        """:attr:`distance` in centimeters, shape (F,)."""
        out: Array = self.distance * self.scale * 100.0
        return out


def foot_joints(character: Character) -> tuple[str, ...]:
    """The names of the character's foot joints, ankle to tip of each foot
    (:func:`course.physics.balance.foot_chains`)."""
    from .balance import foot_chains

    names = character.skeleton.names
    return tuple(names[j] for chain in foot_chains(character) for j in chain)


def foot_radius(character: Character) -> float:
    """The radius of the character's foot geoms, in skeleton units (its capsules are round:
    a foot touches the ground within this distance of its bone's projection)."""
    foot = character.skeleton.index(foot_joints(character)[0])
    geoms = np.flatnonzero(np.asarray(character.model.geom_bodyid) == character.bodies[foot])
    return float(character.model.geom_size[geoms[0], 0]) / character.scale


def clip_zmp(character: Character, motion: Motion, *, stride: int | None = None, spin: bool = True,
             feet: Sequence[str] | None = None, radius: float | None = None,
             ground_height: float | None = None, contacts: ArrayLike | None = None) -> ClipZMP:
    """Where a clip's ZMP is relative to its feet, frame by frame.

    :func:`zmp_from_motion` with the character's mass model (:func:`segment_masses`) against
    :func:`support_polygons` of its feet (default :func:`foot_joints`, widened by
    :func:`foot_radius`).

    Parameters
    ----------
    character : Character
        Built from ``motion``'s skeleton (:func:`~course.physics.model.build_model`).
    motion : Motion
    stride, spin, ground_height
        As :func:`zmp_from_motion`.
    feet, radius, contacts
        As :func:`support_polygons`.

    Returns
    -------
    ClipZMP
    """
    if motion.skeleton.n_joints != character.skeleton.n_joints:
        raise ValueError("motion: its skeleton does not match the character's")
    kin = zmp_from_motion(motion, segment_masses(character), ground_height=ground_height,
                          stride=stride, spin=spin)
    support = support_polygons(motion, foot_joints(character) if feet is None else feet,
                               radius=foot_radius(character) if radius is None else radius,
                               contacts=contacts)
    return ClipZMP(kin, support, support.signed_distance(kin.zmp), character.scale)


# -- MuJoCo ----------------------------------------------------------------------------------


def mujoco_ground_contacts(model: Any, data: Any, *, ground_body: int = 0
                           ) -> tuple[Array, Array]:
    """The contacts of a MuJoCo state with the ground, as y-up points and forces.

    Every contact between a geom of ``ground_body`` (default the world body, which holds the
    floor) and a geom of another body; its force from ``mj_contactForce`` (in the contact
    frame, normal first) turned to the world by the contact frame, and signed as the force
    the ground exerts on the other body (MuJoCo's is that of ``geom1`` on ``geom2``). Run
    ``mj_forward`` (or a step) first: the forces are those of the last constraint solve.
    Torsional and rolling friction (``condim`` 4 and 6) are left out.

    Returns
    -------
    positions : ndarray, shape (k, 3)
        Contact points, y up, meters: MuJoCo's z-up ``(x, y, z)`` is ``(x, z, -y)``.
    forces : ndarray, shape (k, 3)
        Newtons, y up.
    """
    mujoco = import_mujoco()
    bodies = np.asarray(model.geom_bodyid)
    pos, frc = [], []
    f6 = np.zeros(6)
    for i in range(int(data.ncon)):
        contact = data.contact[i]
        b1, b2 = int(bodies[contact.geom1]), int(bodies[contact.geom2])
        if (b1 == ground_body) == (b2 == ground_body):
            continue
        mujoco.mj_contactForce(model, data, i, f6)
        world = np.asarray(contact.frame, dtype=float).reshape(3, 3).T @ f6[:3]
        frc.append(world if b1 == ground_body else -world)
        pos.append(np.asarray(contact.pos, dtype=float))
    if not pos:
        return np.zeros((0, 3)), np.zeros((0, 3))
    C = Y_TO_Z_MATRIX
    return np.asarray(pos) @ C, np.asarray(frc) @ C  # rows: C^T v_z


def zmp_from_mujoco(model: Any, data: Any, *, ground_body: int = 0,
                    ground_height: float | None = None) -> Array:
    """The ZMP of a simulated state from its ground contact forces, y up, meters.

    :func:`zmp_from_forces` of :func:`mujoco_ground_contacts`. For a
    :class:`~course.physics.simulation.Simulation`: ``zmp_from_mujoco(sim.model, sim.data)``.

    Parameters
    ----------
    model, data : mujoco.MjModel, mujoco.MjData
        After ``mj_forward`` or a step.
    ground_body : int
        The body whose geoms are the ground (0, the world).
    ground_height : float, optional
        y-up meters; default the contacts' force-weighted mean height.

    Returns
    -------
    ndarray, shape (3,)
        NaN without ground contact.
    """
    positions, forces = mujoco_ground_contacts(model, data, ground_body=ground_body)
    if len(positions) == 0:
        return np.full(3, np.nan)
    return zmp_from_forces(positions, forces, ground_height=ground_height)


__all__ = [
    "ClipZMP",
    "KinematicZMP",
    "SegmentMasses",
    "SupportPolygons",
    "clip_zmp",
    "DIFFERENCE_SPACING",
    "convex_hull",
    "default_stride",
    "foot_joints",
    "foot_radius",
    "in_polygon",
    "mujoco_ground_contacts",
    "polygon_distance",
    "segment_masses",
    "segment_positions",
    "support_polygons",
    "zmp_from_com",
    "zmp_from_forces",
    "zmp_from_motion",
    "zmp_from_mujoco",
    "zmp_from_points",
]
