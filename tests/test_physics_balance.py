"""course.physics.balance: lecture 10's static balance on the simulated character.

Figures measured at h = 1/600 s, frame 1/60 s, joint PD kp = 1000, kd = 5, COM PD 1000/200,
pushes on the root for 0.1 s from t = 0.25 s, survival 1.5 s after (docs/physics.md, "A
character that stands: static balance"). The simulation has no randomness: every figure is
the same on every run of the same build.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from course.bvh import load_bvh

mujoco = pytest.importorskip(
    "mujoco", reason="MuJoCo is not installed (pip install 'course-kinematics[physics]')"
)

from course.physics.balance import (  # noqa: E402
    com_jacobian,
    foot_chains,
    largest_push,
    stance_com_jacobian,
    stand,
    standing_pose,
    support_centre,
)
from course.physics.character import (  # noqa: E402
    Y_TO_Z_MATRIX,
    Push,
    build_model,
    qpos_from_motion,
    track,
)

SAMPLE = Path(__file__).resolve().parents[1] / "course" / "data" / "samples" / "wave.bvh"
FORWARD = (0.0, 0.0, 1.0)  # y-up: the way the feet point in both skeletons' rest pose


pytestmark = pytest.mark.usefixtures("mujoco_log_elsewhere")


@pytest.fixture(scope="module")
def sample():
    motion = load_bvh(SAMPLE)
    return build_model(motion.skeleton)


@pytest.mark.parametrize("which", ["sample", "cmu"])
def test_standing_pose_has_flat_feet_on_the_ground_and_com_above_them(which, request) -> None:
    ch = request.getfixturevalue(which)
    pose = standing_pose(ch)
    assert pose.n_frames == 1
    positions, _ = pose.forward_kinematics()
    feet = [j for chain in foot_chains(ch) for j in chain]
    assert len(foot_chains(ch)) == 2
    assert np.allclose(positions[0, feet, 1], 0.0, atol=1e-6)  # flat, on the clip ground
    data = mujoco.MjData(ch.model)
    data.qpos[:] = qpos_from_motion(ch, pose)[0]
    mujoco.mj_forward(ch.model, data)
    com = Y_TO_Z_MATRIX.T @ data.subtree_com[ch.bodies[0]]
    sup = support_centre(ch, pose)
    assert np.hypot(*(com - sup)[[0, 2]]) < 1e-3  # COM above the feet's centre (m)
    # nothing but the feet (and the shin capsules' ends, at the ankles) touches the floor
    touching = {int(ch.model.geom_bodyid[data.contact.geom[k]].max()) for k in range(data.ncon)}
    ankles = [c[0] for c in foot_chains(ch)]
    allowed = {ch.bodies[j] for j in feet if j >= 0} | {
        ch.bodies[ch.skeleton.parents[a]] for a in ankles}
    assert touching and touching <= allowed


@pytest.mark.parametrize("which", ["sample", "cmu"])
def test_com_controller_stands_unpushed_and_the_ragdoll_falls(which, request) -> None:
    ch = request.getfixturevalue(which)
    up = stand(ch, controller="com", duration=2.0)
    assert not up.fell and up.fall_time is None
    assert up.motion.n_frames == 121 and up.com.shape == (121, 3)
    assert np.hypot(*(up.com[-1] - up.com_target)[[0, 2]]) < 0.02  # measured <= 0.5 cm
    down = stand(ch, controller="none", duration=1.0, torques=False)
    assert down.fell and down.fall_time is not None and down.fall_time < 1.0  # 0.32-0.57 s


def test_com_jacobian_matches_finite_differences_of_the_com(sample) -> None:
    ch = sample
    model, data = ch.model, mujoco.MjData(ch.model)
    rng = np.random.default_rng(7)
    pose = standing_pose(ch)
    data.qpos[:] = qpos_from_motion(ch, pose)[0]
    data.qpos[7:] += 0.1 * rng.standard_normal(model.nq - 7)  # a generic pose (renormalized)
    mujoco.mj_normalizeQuat(model, data.qpos)
    mujoco.mj_forward(model, data)
    jac = com_jacobian(ch, model, data)
    eps = 1e-6
    fd = np.zeros_like(jac)
    for k in range(model.nv):
        com = []
        for sign in (1.0, -1.0):
            d2 = mujoco.MjData(model)
            d2.qpos[:] = data.qpos
            dq = np.zeros(model.nv)
            dq[k] = sign * eps
            mujoco.mj_integratePos(model, d2.qpos, dq, 1.0)
            mujoco.mj_forward(model, d2)
            com.append(d2.subtree_com[ch.bodies[0]].copy())
        fd[:, k] = (com[0] - com[1]) / (2 * eps)
    assert np.abs(jac - fd).max() < 1e-6


def test_stance_jacobian_is_the_com_motion_with_the_foot_held(sample) -> None:
    """Move the leg joints by dq, then move the root so the foot is back where it was: the COM
    moves by J̃ dq (first order). Independent of the formula: the root is found by Newton on
    the foot's pose."""
    ch = sample
    model, data = ch.model, mujoco.MjData(ch.model)
    data.qpos[:] = qpos_from_motion(ch, standing_pose(ch))[0]
    mujoco.mj_forward(model, data)
    foot = ch.bodies[foot_chains(ch)[0][0]]
    jt = stance_com_jacobian(ch, model, data, foot)
    assert np.allclose(jt[:, :6], 0.0)
    rng = np.random.default_rng(3)
    dq = np.zeros(model.nv)
    dq[6:] = 1e-5 * rng.standard_normal(model.nv - 6)
    p0, r0 = data.xpos[foot].copy(), data.xmat[foot].copy().reshape(3, 3)
    d2 = mujoco.MjData(model)
    d2.qpos[:] = data.qpos
    mujoco.mj_integratePos(model, d2.qpos, dq, 1.0)
    for _ in range(5):  # root correction putting the foot back
        mujoco.mj_forward(model, d2)
        jp, jr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
        mujoco.mj_jacBody(model, d2, jp, jr, foot)
        rot = d2.xmat[foot].reshape(3, 3)
        dr = np.zeros(3)
        mujoco.mju_mat2Quat(q := np.zeros(4), (r0 @ rot.T).ravel())
        mujoco.mju_quat2Vel(dr, q, 1.0)
        err = np.concatenate([p0 - d2.xpos[foot], dr])
        step = np.zeros(model.nv)
        step[:6] = np.linalg.solve(np.vstack([jp, jr])[:, :6], err)
        mujoco.mj_integratePos(model, d2.qpos, step, 1.0)
    mujoco.mj_forward(model, d2)
    moved = d2.subtree_com[ch.bodies[0]] - data.subtree_com[ch.bodies[0]]
    assert np.allclose(moved, jt @ dq, atol=1e-9, rtol=1e-3)


def test_jacobian_transpose_torque_does_the_virtual_work_of_the_force(sample) -> None:
    ch = sample
    model, data = ch.model, mujoco.MjData(ch.model)
    data.qpos[:] = qpos_from_motion(ch, standing_pose(ch))[0]
    mujoco.mj_forward(model, data)
    rng = np.random.default_rng(11)
    for foot in foot_chains(ch):
        jt = stance_com_jacobian(ch, model, data, ch.bodies[foot[0]])
        for _ in range(5):
            f, dq = rng.standard_normal(3), rng.standard_normal(model.nv)
            tau = jt.T @ f
            assert tau @ dq == pytest.approx(f @ (jt @ dq), rel=1e-12, abs=1e-12)


def test_push_checks_its_input(sample) -> None:
    with pytest.raises(ValueError, match=r"'Pelvis'.*Hips"):
        Push("Pelvis", (10.0, 0.0, 0.0), 0.0, 0.1).body(sample)
    with pytest.raises(ValueError, match="End Site"):
        Push("Head_end", (10.0, 0.0, 0.0), 0.0, 0.1).body(sample)
    with pytest.raises(ValueError, match="force"):
        Push("Hips", (1.0, 2.0), 0.0, 0.1)
    with pytest.raises(ValueError, match="duration"):
        Push("Hips", (1.0, 2.0, 3.0), 0.0, 0.0)
    with pytest.raises(ValueError, match="start"):
        Push("Hips", (1.0, 2.0, 3.0), -1.0, 0.1)
    push = Push("Hips", [30.0, 0.0, 40.0], 0.5, 0.2)
    assert push.impulse == pytest.approx(10.0)
    assert np.allclose(push.force_z_up(), [30.0, -40.0, 0.0])
    with pytest.raises(ValueError, match="controller"):
        stand(sample, controller="hip", duration=0.1)


def test_push_moves_the_com_by_its_impulse_in_free_fall(sample) -> None:
    """A 35 N push for 0.05 s on the passive character, sideways: over the push the COM's mean
    horizontal velocity is half the impulse over the mass (constant force); friction with the
    floor (the feet do not slide yet) takes the 10% allowed."""
    ch = sample
    pose = standing_pose(ch)
    push = Push("Hips", (35.0, 0.0, 0.0), 0.0, 0.05)
    pushed = stand(ch, pose, controller="none", duration=0.05, frame_time=0.05, torques=False,
                   push=push)
    vx = (pushed.com[1, 0] - pushed.com[0, 0]) / 0.05
    # average velocity over the push is half the final (constant force): J / m / 2
    assert vx == pytest.approx(push.impulse / ch.total_mass / 2, rel=0.1)


def test_on_frame_sees_every_frame_as_it_is_made(sample) -> None:
    seen: list[tuple[int, np.ndarray, np.ndarray]] = []
    run = stand(sample, controller="com", duration=0.5,
                on_frame=lambda i, m: seen.append((i, m.local_rotations, m.root_positions)))
    assert [i for i, _, _ in seen] == list(range(1, run.motion.n_frames))
    for i, rot, root in seen:
        assert rot.shape[0] == 1
        assert np.allclose(rot[0], run.motion.local_rotations[i], atol=1e-12)
        assert np.allclose(root[0], run.motion.root_positions[i], atol=1e-12)


def test_track_on_frame_and_push(sample) -> None:
    motion = load_bvh(SAMPLE)
    seen: list[int] = []
    run = track(sample, motion, kp=1000.0, kd=5.0, n_frames=11,
                on_frame=lambda i, m: seen.append(i) if m.n_frames == 1 else None)
    assert seen == list(range(1, 11))
    shoved = track(sample, motion, kp=1000.0, kd=5.0, n_frames=11,
                   push=Push("Hips", (400.0, 0.0, 0.0), 0.0, 0.1))
    dx = shoved.motion.root_positions[-1, 0] - run.motion.root_positions[-1, 0]
    assert dx > 0  # pushed along +x


def test_joint_limits_hold_under_a_violent_push(sample) -> None:
    limit = np.radians(30.0)
    ch = build_model(sample.skeleton, joint_limits=limit)
    assert 'limited="true"' in ch.xml and ch.model.jnt_limited[1:].all()
    loose = build_model(sample.skeleton, joint_limits=False)
    assert not loose.model.jnt_limited.any()
    with pytest.raises(ValueError, match="joint_limits"):
        build_model(sample.skeleton, joint_limits=4.0)
    run = stand(ch, controller="none", duration=1.0, kp=20.0, kd=1.0,
                push=Push("Head", (0.0, 0.0, 1500.0), 0.1, 0.1))
    q = run.motion.local_rotations[:, [j for j in ch.simulated_joints if j > 0]]
    angle = 2 * np.arccos(np.clip(np.abs(q[..., 0]), 0.0, 1.0))
    # without limits the same push bends joints far beyond 30 degrees
    free = stand(loose, controller="none", duration=1.0, kp=20.0, kd=1.0,
                 push=Push("Head", (0.0, 0.0, 1500.0), 0.1, 0.1))
    qf = free.motion.local_rotations[:, [j for j in ch.simulated_joints if j > 0]]
    free_max = (2 * np.arccos(np.clip(np.abs(qf[..., 0]), 0.0, 1.0))).max()
    assert free_max > limit + 0.3
    assert angle.max() < limit + np.radians(5.0)  # measured 3.4 degrees over


def _pushes(ch):
    pose = standing_pose(ch)
    return {c: largest_push(ch, pose, controller=c, direction=FORWARD) for c in
            ("none", "ankle", "com")}


def test_balance_controllers_survive_larger_pushes_sample(sample) -> None:
    f = _pushes(sample)
    # measured (N, 0.1 s, forward): none 37.5, ankle 84.4, com 131.2
    assert f["com"] >= 1.5 * f["none"] > 0
    assert f["ankle"] >= 1.5 * f["none"]
    assert f["com"] > f["ankle"]


def test_balance_controllers_survive_larger_pushes_cmu(cmu) -> None:
    f = _pushes(cmu)
    # measured (N, 0.1 s, forward): none 46.9, ankle 87.5, com 121.9
    assert f["com"] >= 1.5 * f["none"] > 0
    assert f["ankle"] >= 1.5 * f["none"]
    assert f["com"] > f["ankle"]


def test_largest_push_is_deterministic_and_a_bracket(sample) -> None:
    pose = standing_pose(sample)
    a = largest_push(sample, pose, controller="ankle", direction=FORWARD, tol=10.0)
    b = largest_push(sample, pose, controller="ankle", direction=FORWARD, tol=10.0)
    assert a == b
    kept = stand(sample, pose, controller="ankle", duration=1.85,
                 push=Push("Hips", a * np.array(FORWARD), 0.25, 0.1))
    lost = stand(sample, pose, controller="ankle", duration=1.85,
                 push=Push("Hips", (a + 10.0) * np.array(FORWARD), 0.25, 0.1))
    assert not kept.fell and lost.fell
