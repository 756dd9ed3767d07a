"""course.physics.zmp: the ZMP from forces, from the COM, from a clip, and the support polygon.

The formulas are checked by what defines the ZMP (the horizontal moment about it vanishes), a
static pose's ZMP is its COM's projection, a box resting on a MuJoCo plane has its ZMP under
its COM, and the kinematic ZMP of a simulated motion equals the ZMP of the simulation's own
contact forces. The CMU walk's figures (docs/walking.md) were measured on this build; the
bounds asserted leave a margin around them. The simulations have no randomness; hypothesis
properties are derandomised.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from course.bvh import load_bvh
from course.motion import Motion
from course.physics.lip import G
from course.physics.zmp import (
    SegmentMasses,
    convex_hull,
    default_stride,
    in_polygon,
    polygon_distance,
    zmp_from_com,
    zmp_from_forces,
    zmp_from_motion,
    zmp_from_points,
)
from course.rotations import matrix_from_quat, quat_from_rotvec, quat_mul
from course.skeleton import Skeleton

PROPERTY = settings(max_examples=60, derandomize=True, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.too_slow])


def _vectors(n, lo, hi):
    return hnp.arrays(np.float64, (n, 3), elements=st.floats(lo, hi).map(lambda v: round(v, 6)))


def _horizontal_moment(points, forces, p):
    """x and z parts of sum (r_i - p) x f_i."""
    m = np.cross(points - p, forces).sum(axis=0)
    return m[[0, 2]]


# -- forces and the COM ----------------------------------------------------------------------


def test_on_flat_ground_the_zmp_is_the_force_weighted_mean_of_the_contacts():
    r = np.array([[0.0, 0, 0], [0.2, 0, 0], [0.2, 0, 0.1], [0.0, 0, 0.1]])
    f = np.array([[0.0, 10, 0], [0, 30, 0], [0, 30, 0], [0, 10, 0]])
    np.testing.assert_allclose(zmp_from_forces(r, f), [0.15, 0.0, 0.05])
    # horizontal forces at points on the ground change nothing (their arm is 0)
    f_shear = f + np.array([3.0, 0.0, -2.0])
    np.testing.assert_allclose(zmp_from_forces(r, f_shear), [0.15, 0.0, 0.05])
    # a batch of frames (..., k, 3) and a frame without support (NaN, not an error)
    batch = zmp_from_forces(np.stack([r, r]), np.stack([f, 0 * f]))
    assert batch.shape == (2, 3)
    np.testing.assert_allclose(batch[0], [0.15, 0.0, 0.05])
    assert np.isnan(batch[1]).all()


@PROPERTY
@given(r=_vectors(4, -1.0, 1.0), f=_vectors(4, -5.0, 5.0), up=st.floats(1.0, 50.0),
       ground=st.floats(-0.5, 0.5))
def test_the_moment_of_the_contact_forces_about_the_zmp_has_no_horizontal_part(r, f, up, ground):
    f = f.copy()
    f[:, 1] = np.abs(f[:, 1]) + up
    p = zmp_from_forces(r, f, ground_height=ground)
    assert p[1] == ground
    np.testing.assert_allclose(_horizontal_moment(r, f, p), 0.0, atol=1e-9 * up * 10)


def test_the_zmp_of_a_static_body_is_its_com_projection():
    c = np.array([[0.3, 0.9, -0.2], [1.0, 1.2, 2.0]])
    np.testing.assert_allclose(zmp_from_com(c, np.zeros(3)), [[0.3, 0, -0.2], [1.0, 0, 2.0]])
    np.testing.assert_allclose(zmp_from_com(c, np.zeros(3), ground_height=0.1),
                               [[0.3, 0.1, -0.2], [1.0, 0.1, 2.0]])


def test_the_single_mass_zmp_numbers_and_signs():
    # accelerating forwards (+z) at 1 m/s^2 with the COM 0.9 m up: the ZMP 9.2 cm behind
    p = zmp_from_com([0.0, 0.9, 0.0], [0.0, 0.0, 1.0])
    np.testing.assert_allclose(p, [0.0, 0.0, -0.9 / G])
    # the height above the ground, not the COM's y: the same body on a floor at y = 0.5
    np.testing.assert_allclose(zmp_from_com([0.0, 1.4, 0.0], [0.0, 0.0, 1.0], ground_height=0.5),
                               [0.0, 0.5, -0.9 / G])
    # pushed up harder (c̈_y > 0) the lever of the horizontal acceleration shrinks
    assert abs(zmp_from_com([0, 0.9, 0], [0, 2.0, 1.0])[2]) < 0.9 / G
    # in free fall there is no ZMP
    assert np.isnan(zmp_from_com([0, 0.9, 0], [0, -G, 0])).all()


def test_the_rate_of_angular_momentum_moves_the_zmp_with_y_up_signs():
    M, c = 60.0, np.array([0.0, 1.0, 0.0])
    # spinning up about +z (x right, y up: the +x side rising) takes the ground pushing up
    # on the +x side, (+x) × (+y) = +z; spinning up about +x (the -z side rising) takes it
    # on the -z side, (-z) × (+y) = +x: hence +Ḣ_z and -Ḣ_x in y up
    p = zmp_from_com(c, np.zeros(3), mass=M, angular_momentum_rate=[0.0, 0.0, 30.0])
    np.testing.assert_allclose(p, [30.0 / (M * G), 0.0, 0.0])
    p = zmp_from_com(c, np.zeros(3), mass=M, angular_momentum_rate=[30.0, 0.0, 0.0])
    np.testing.assert_allclose(p, [0.0, 0.0, -30.0 / (M * G)])
    with pytest.raises(ValueError, match="^mass"):
        zmp_from_com(c, np.zeros(3), angular_momentum_rate=[0.0, 0.0, 1.0])


@PROPERTY
@given(r=_vectors(5, -1.0, 1.0), a=_vectors(5, -3.0, 3.0),
       m=hnp.arrays(np.float64, 5, elements=st.floats(0.5, 10.0)))
def test_the_multibody_zmp_zeroes_the_moment_of_gravity_and_inertia(r, a, m):
    r = r + np.array([0.0, 1.5, 0.0])  # above the ground
    p = zmp_from_points(r, a, m)
    # the ground reaction at p balances sum m_i (a_i + g y): its moment about p is
    # sum (r_i - p) x m_i (a_i + g y), whose horizontal part must vanish
    f = m[:, None] * (a + np.array([0.0, G, 0.0]))
    np.testing.assert_allclose(_horizontal_moment(r, f, p), 0.0, atol=1e-9 * f.sum())
    # one point mass: the single-mass formula
    np.testing.assert_allclose(zmp_from_points(r[:1], a[:1], m[:1]), zmp_from_com(r[0], a[0]),
                               atol=1e-12)


@pytest.mark.parametrize("call, name", [
    (lambda: zmp_from_forces(np.zeros((2, 3)), np.zeros((2, 2))), "forces"),
    (lambda: zmp_from_forces(np.zeros(3), np.zeros(3)), "positions, forces"),
    (lambda: zmp_from_com([0, 1, 0], [0, 0, np.nan]), "com_acceleration"),
    (lambda: zmp_from_com([0, 1], [0, 0, 0]), "com"),
    (lambda: zmp_from_com([0, 1, 0], [0, 0, 0], g=-9.81), "g"),
    (lambda: zmp_from_com([0, 1, 0], [0, 0, 0], mass=0.0, angular_momentum_rate=[0, 0, 1]),
     "mass"),
    (lambda: zmp_from_points(np.zeros((2, 3)), np.zeros((2, 3)), [1.0, -1.0]), "masses"),
    (lambda: convex_hull(np.zeros((3, 3))), "points"),
    (lambda: polygon_distance(np.zeros((0, 2)), [0.0, 0.0]), "polygon"),
])
def test_bad_arguments_are_refused_by_name(call, name):
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        call()


# -- polygons --------------------------------------------------------------------------------


def test_convex_hull_of_a_square_with_inner_and_edge_points():
    pts = [[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5], [0.5, 0], [1, 0], [0.2, 0.7]]
    hull = convex_hull(pts)
    assert len(hull) == 4
    assert {tuple(v) for v in hull} == {(0, 0), (1, 0), (1, 1), (0, 1)}
    # counter-clockwise in (x, z): positive area
    x, z = hull[:, 0], hull[:, 1]
    assert 0.5 * np.sum(x * np.roll(z, -1) - np.roll(x, -1) * z) == pytest.approx(1.0)
    assert convex_hull([[1, 2], [1, 2]]).shape == (1, 2)
    assert convex_hull([[0, 0], [1, 1], [2, 2]]).tolist() == [[0, 0], [2, 2]]
    assert convex_hull(np.zeros((0, 2))).shape == (0, 2)


@settings(PROPERTY, max_examples=30)
@given(pts=hnp.arrays(np.float64, (12, 2), elements=st.floats(-1, 1).map(lambda v: round(v, 6))))
def test_convex_hull_matches_scipy(pts):
    spatial = pytest.importorskip("scipy.spatial")
    try:
        ref = spatial.ConvexHull(pts)
    except spatial.QhullError:  # degenerate (collinear) input
        return
    hull = convex_hull(pts)
    area = 0.5 * np.sum(hull[:, 0] * np.roll(hull[:, 1], -1) - np.roll(hull[:, 0], -1) * hull[:, 1])
    assert area == pytest.approx(ref.volume, rel=1e-9)
    assert {tuple(v) for v in hull} <= {tuple(v) for v in pts[ref.vertices]}


def test_polygon_distance_is_signed_negative_inside():
    square = convex_hull([[0, 0], [1, 0], [1, 1], [0, 1]])
    d = polygon_distance(square, [[0.5, 0.5], [0.9, 0.5], [2, 0.5], [2, 2], [1, 0.5]])
    np.testing.assert_allclose(d, [-0.5, -0.1, 1.0, math.sqrt(2), 0.0])
    assert in_polygon(square, [[0.5, 0.5], [1.05, 0.5]]).tolist() == [True, False]
    assert in_polygon(square, [1.05, 0.5], margin=0.1)
    # a segment (one foot's contact line) and a point have no inside
    segment = np.array([[0.0, 0.0], [1.0, 0.0]])
    np.testing.assert_allclose(polygon_distance(segment, [[0.5, 0.0], [0.5, 0.3], [2, 0]]),
                               [0.0, 0.3, 1.0])
    np.testing.assert_allclose(polygon_distance([[1.0, 1.0]], [[1.0, 2.0]]), [1.0])


@PROPERTY
@given(pts=hnp.arrays(np.float64, (8, 2), elements=st.floats(-1, 1).map(lambda v: round(v, 6))),
       w=hnp.arrays(np.float64, 8, elements=st.floats(0.01, 1)), out=st.floats(0.01, 2.0))
def test_polygon_distance_inside_convex_combinations_and_outside_along_normals(pts, w, out):
    hull = convex_hull(pts)
    if len(hull) < 3:
        return
    inner = (w / w.sum()) @ pts
    assert polygon_distance(hull, inner) <= 1e-12
    # from an edge's midpoint along its outward normal the distance is the offset
    a, b = hull[0], hull[1]
    normal = np.array([b[1] - a[1], a[0] - b[0]]) / np.linalg.norm(b - a)  # right of a -> b
    assert polygon_distance(hull, (a + b) / 2 + out * normal) == pytest.approx(out, rel=1e-9)


# -- clips: synthetic ------------------------------------------------------------------------


def _one_body(rotations, position, frame_time, inertia, mass=2.0):
    skel = Skeleton(["body"], [-1], [[0.0, 0.0, 0.0]])
    n = len(rotations)
    motion = Motion(skel, rotations[:, None], np.tile(position, (n, 1)), frame_time)
    masses = SegmentMasses((0,), np.array([mass]), np.zeros((1, 3)), inertia[None], 1.0)
    return motion, masses


def test_a_static_pose_has_its_zmp_at_the_com_projection():
    skel = Skeleton(["hip", "knee", "ankle"], [-1, 0, 1], [[0, 0, 0], [0.1, -0.4, 0.05],
                                                          [0, -0.4, 0]])
    q = quat_from_rotvec(np.array([[0.1, 0.2, -0.3], [0.4, 0.0, 0.1], [0.0, 0.0, 0.0]]))
    motion = Motion(skel, np.tile(q, (5, 1, 1)), np.tile([0.2, 0.9, -0.1], (5, 1)), 1 / 60)
    masses = SegmentMasses((0, 1), np.array([10.0, 4.0]),
                           np.array([[0.0, -0.2, 0.0], [0.05, -0.2, 0.0]]),
                           np.tile(0.1 * np.eye(3), (2, 1, 1)), 1.0)
    kin = zmp_from_motion(motion, masses, stride=1, ground_height=0.0)
    com = kin.com[1:-1]
    np.testing.assert_allclose(kin.zmp[1:-1], com * [1, 0, 1], atol=1e-12)
    np.testing.assert_allclose(kin.zmp_com[1:-1], com * [1, 0, 1], atol=1e-12)
    assert np.isnan(kin.zmp[[0, -1]]).all()  # no central difference at the ends


def test_a_spinning_body_shifts_the_zmp_by_its_euler_torque():
    # constant angular velocity about a tilted axis through the COM, anisotropic inertia:
    # L̇ = ω × (I ω) ≠ 0, so p_x = Ḣ_z / (M g), p_z = -Ḣ_x / (M g) with the COM still
    omega = np.array([1.5, 2.0, -0.5])
    inertia = np.diag([0.05, 0.2, 0.12])
    dt = 1 / 240
    t = np.arange(21) * dt
    q0 = quat_from_rotvec(np.array([0.3, -0.2, 0.1]))
    q = quat_mul(quat_from_rotvec(t[:, None] * omega), np.broadcast_to(q0, (21, 4)))
    motion, masses = _one_body(q, [0.0, 1.0, 0.0], dt, inertia)
    kin = zmp_from_motion(motion, masses, stride=1, ground_height=0.0)
    R = matrix_from_quat(q[10])
    L = R @ inertia @ R.T @ omega
    hdot = np.cross(omega, L)
    np.testing.assert_allclose(kin.angular_momentum_rate[10], hdot, rtol=1e-3, atol=1e-6)
    np.testing.assert_allclose(kin.zmp[10], [hdot[2] / (2 * G), 0.0, -hdot[0] / (2 * G)],
                               rtol=1e-3, atol=1e-7)
    # as point masses it would not move at all
    still = zmp_from_motion(motion, masses, stride=1, ground_height=0.0, spin=False)
    np.testing.assert_allclose(still.zmp[10], [0.0, 0.0, 0.0], atol=1e-12)


def test_default_stride_is_a_twentieth_of_a_second():
    assert default_stride(1 / 120) == 6
    assert default_stride(1 / 60) == 3
    assert default_stride(1 / 10) == 1


def test_zmp_from_motion_refuses_by_name():
    motion, masses = _one_body(np.tile([1.0, 0, 0, 0], (4, 1)), [0, 1, 0], 0.01, np.eye(3))
    with pytest.raises(ValueError, match="^motion: 4 frames"):
        zmp_from_motion(motion, masses, stride=2)
    with pytest.raises(ValueError, match="^stride"):
        zmp_from_motion(motion, masses, stride=0)
    with pytest.raises(ValueError, match="^masses"):
        zmp_from_motion(motion, None)  # type: ignore[arg-type]


# -- MuJoCo: the mass model, a box, the simulated character ----------------------------------

mujoco = pytest.importorskip(
    "mujoco", reason="MuJoCo is not installed (pip install 'course-kinematics[physics]')")

from course.physics.balance import standing_pose  # noqa: E402
from course.physics.controllers import PD  # noqa: E402
from course.physics.model import (  # noqa: E402
    Y_TO_Z_MATRIX,
    build_model,
    motion_from_qpos,
    qpos_from_motion,
)
from course.physics.simulation import Push, Simulation  # noqa: E402
from course.physics.zmp import (  # noqa: E402
    clip_zmp,
    foot_joints,
    foot_radius,
    mujoco_ground_contacts,
    segment_masses,
    segment_positions,
    support_polygons,
    zmp_from_mujoco,
)

pytestmark = pytest.mark.usefixtures("mujoco_log_elsewhere")


@pytest.fixture(scope="module")
def walk(shared_bvh_dir: Path):
    return load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")[1:]  # frame 0: the T-pose


@pytest.fixture(scope="module")
def character(walk):
    return build_model(walk.skeleton)


BOX = """
<mujoco>
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 1"/>
    <body name="box" pos="0.3 -0.2 {z}">
      <freejoint/>
      <geom type="box" size="0.1 0.05 0.075" mass="2"/>
      <geom type="sphere" size="0.02" pos="0.06 0.02 0" mass="3" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_a_box_resting_on_the_plane_has_its_zmp_under_its_com():
    model = mujoco.MjModel.from_xml_string(BOX.format(z=0.2))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert np.isnan(zmp_from_mujoco(model, data)).all()  # in the air: no ZMP
    for _ in range(1500):
        mujoco.mj_step(model, data)
    mujoco.mj_forward(model, data)
    positions, forces = mujoco_ground_contacts(model, data)
    assert len(positions) == 4  # the four bottom corners
    np.testing.assert_allclose(forces.sum(axis=0), [0.0, 5.0 * 9.81, 0.0], atol=1e-6)
    com = Y_TO_Z_MATRIX.T @ data.xipos[1]  # y up: MuJoCo's (x, y, z) is (x, z, -y)
    # where the box landed (it settles a little as it lands on its offset COM)
    np.testing.assert_allclose(com[[0, 2]], [0.3 + 0.06 * 3 / 5, 0.2 - 0.02 * 3 / 5], atol=1e-3)
    p = zmp_from_mujoco(model, data)
    np.testing.assert_allclose(p[[0, 2]], com[[0, 2]], atol=1e-6)
    assert abs(p[1]) < 1e-3  # on the plane, up to the contact's penetration
    np.testing.assert_allclose(zmp_from_mujoco(model, data, ground_height=0.0)[[0, 2]],
                               com[[0, 2]], atol=1e-6)


def test_the_mass_model_is_the_characters_bodies_placed_by_fk(walk, character):
    masses = segment_masses(character)
    assert masses.total_mass == pytest.approx(character.total_mass)
    assert len(masses.joints) == len(character.simulated_joints)
    clip = walk[100:103]
    com_k, _ = segment_positions(clip, masses)
    data = mujoco.MjData(character.model)
    for f, qpos in enumerate(qpos_from_motion(character, clip)):
        data.qpos[:] = qpos
        mujoco.mj_kinematics(character.model, data)
        mujoco.mj_comPos(character.model, data)
        bodies = [character.bodies[j] for j in masses.joints]
        np.testing.assert_allclose(com_k[f] * character.scale,
                                   data.xipos[bodies] @ Y_TO_Z_MATRIX, atol=1e-9)
        whole = masses.masses @ com_k[f] / masses.total_mass
        np.testing.assert_allclose(whole * character.scale,
                                   Y_TO_Z_MATRIX.T @ data.subtree_com[character.bodies[0]],
                                   atol=1e-9)


def test_a_static_cmu_pose_has_its_zmp_at_the_com_projection(walk, character):
    still = Motion(walk.skeleton, np.repeat(walk.local_rotations[200:201], 9, axis=0),
                   np.repeat(walk.root_positions[200:201], 9, axis=0), walk.frame_time)
    kin = zmp_from_motion(still, segment_masses(character), stride=2, ground_height=0.0)
    ok = slice(2, -2)
    np.testing.assert_allclose(kin.zmp[ok], kin.com[ok] * [1, 0, 1], atol=1e-9)
    np.testing.assert_allclose(kin.com_acceleration[ok], 0.0, atol=1e-9)


def test_the_kinematic_zmp_of_a_simulated_motion_is_the_zmp_of_its_contact_forces(character):
    """Standing, pushed, swaying on flat feet: two independent ZMPs, one mass model.

    Measured (frame 1/120 s, h 1/600 s, a 72 N push for 0.2 s from 0.2 s): outside the push
    (an external force the kinematic ZMP cannot know about) they agree within 0.38 cm with the
    segments' spin (0.51 cm as point masses), while the ZMP moves over 28 cm x 16 cm; the
    single-mass formula is 6.4 cm off, Ḣ with its sign flipped 22 cm.
    """
    pose = standing_pose(character)
    q0 = qpos_from_motion(character, pose)[0]
    contact_zmp = []
    sim = Simulation(character, q0, frame_time=1 / 120, h=1 / 600,
                     push=Push("Hips", (40.0, 0.0, 60.0), 0.2, 0.2),
                     on_frame=lambda i, frame: contact_zmp.append(
                         zmp_from_mujoco(sim.model, sim.data)))
    contact_zmp.append(zmp_from_mujoco(sim.model, sim.data))
    record = sim.run(PD(q0, kp=1000, kd=5), n_frames=121)
    assert record.reason == "end"
    zc = np.array(contact_zmp)  # y-up meters
    motion = motion_from_qpos(character, record.qpos, 1 / 120)
    masses = segment_masses(character)
    floor = -0.04 / character.scale  # build_model's plane: one capsule radius below the clip
    t = np.arange(len(zc)) / 120
    calm = ((t < 0.19) | (t > 0.42)) & np.isfinite(zc).all(axis=1)
    calm[[0, -1]] = False

    def gap_cm(kin_zmp):
        return np.linalg.norm((kin_zmp * character.scale - zc)[calm][:, [0, 2]], axis=1) * 100

    kin = zmp_from_motion(motion, masses, stride=1, ground_height=floor)
    assert np.ptp(zc[calm][:, [0, 2]], axis=0).min() > 0.1  # it really sways: > 10 cm
    assert gap_cm(kin.zmp).max() < 1.0
    assert gap_cm(zmp_from_motion(motion, masses, stride=1, ground_height=floor,
                                  spin=False).zmp).max() < 1.5
    assert gap_cm(kin.zmp_com).max() > 3.0  # the single mass misses the limbs' swing
    wrong = zmp_from_com(kin.com * character.scale, np.nan_to_num(kin.com_acceleration),
                         ground_height=-0.04, mass=masses.total_mass,
                         angular_momentum_rate=-np.nan_to_num(kin.angular_momentum_rate))
    assert gap_cm(wrong / character.scale).max() > 10.0


def test_the_support_polygons_of_the_walk(walk, character):
    feet = foot_joints(character)
    assert feet == ("LeftFoot", "LeftToeBase", "LeftToeBase_end", "RightFoot", "RightToeBase",
                    "RightToeBase_end")
    assert foot_radius(character) * character.scale == pytest.approx(0.04)
    support = support_polygons(walk, feet, radius=foot_radius(character))
    assert len(support.polygons) == walk.n_frames
    positions = walk.forward_kinematics()[0]
    for f in range(0, walk.n_frames, 7):
        on = np.flatnonzero(support.contacts[f])
        assert len(support.polygons[f]) == len(convex_hull(positions[f, [walk.skeleton.index(
            feet[k]) for k in on]][:, [0, 2]]))
        for k in on:  # every contact joint is in its frame's support region
            joint = positions[f, walk.skeleton.index(feet[k])]
            one = np.full((walk.n_frames, 3), np.nan)
            one[f] = joint
            assert support.signed_distance(one)[f] <= -support.radius + 1e-12
    assert support.airborne.sum() <= 5  # a walk: some foot is always down (the test errs)


def test_the_cmu_walk_zmp_is_inside_its_support_polygon_about_half_the_time(walk, character):
    """docs/walking.md, "The CMU walk": 52.2% of 508 frames inside at the default 1/20 s
    stride, median distance -0.1 cm, 95th percentile 12 cm; double support 91% inside; the
    COM's projection 35%; consecutive frames (stride 1) are swamped by mocap noise."""
    result = clip_zmp(character, walk)
    assert result.kinematic.stride == 6
    assert 500 <= result.defined.sum() <= 511
    assert 0.45 <= result.fraction_inside <= 0.60
    d = result.distance_cm[result.defined]
    assert abs(np.median(d)) < 2.0
    assert np.percentile(d, 95) < 20.0
    contacts = result.support.contacts
    double = contacts[:, :3].any(axis=1) & contacts[:, 3:].any(axis=1) & result.defined
    assert double.sum() >= 30
    assert result.inside[double].mean() >= 0.8
    com_inside = result.support.contains(result.kinematic.com)[result.defined].mean()
    assert com_inside < result.fraction_inside - 0.1  # the dynamics matter: c̈ moves the ZMP
    noisy = clip_zmp(character, walk, stride=1)
    assert np.percentile(noisy.distance_cm[noisy.defined], 95) > 50.0
