"""course.physics.character: a MuJoCo character built from a Skeleton, PD tracking a Motion.

Numbers measured on the CMU walk (cmu_12_01_walk.bvh, frames 1.., 120 fps; frame 0 of that
clip is a different pose, ~160 rad/s away from frame 1, so it is dropped), h = 1/600 s,
kd = 0.2 sqrt(kp) unless said (docs/physics.md, "A simulated character").
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from course.bvh import load_bvh
from course.motion import is_end_site

mujoco = pytest.importorskip(
    "mujoco", reason="MuJoCo is not installed (pip install 'course-kinematics[physics]')"
)

from course.physics.character import (  # noqa: E402
    Y_TO_Z_MATRIX,
    build_model,
    effective_inertia,
    motion_from_qpos,
    qpos_from_motion,
    set_state,
    track,
)

SAMPLE = Path(__file__).resolve().parents[1] / "course" / "data" / "samples" / "wave.bvh"
H = 1.0 / 600.0


pytestmark = pytest.mark.usefixtures("mujoco_log_elsewhere")


@pytest.fixture(scope="module")
def walk(shared_bvh_dir: Path):
    return load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")[1:]


@pytest.fixture(scope="module")
def walker(walk):
    return build_model(walk.skeleton)


@pytest.fixture(scope="module")
def wave():
    return load_bvh(SAMPLE)


def test_import_course_physics_does_not_import_mujoco() -> None:
    code = (
        "import sys, course, course.physics; "
        "assert 'mujoco' not in sys.modules, 'mujoco imported'; "
        "from course.physics import build_model; assert 'mujoco' not in sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


@pytest.mark.parametrize("which", ["walk", "wave"])
def test_model_compiles_with_one_body_and_joint_per_non_end_site(which, request) -> None:
    motion = request.getfixturevalue(which)
    skel = motion.skeleton
    ch = build_model(skel)
    model = ch.model
    simulated = [j for j in range(skel.n_joints) if not is_end_site(skel, j)]
    # Mapping: skeleton joint j (not an End Site) <-> MuJoCo body ch.bodies[j] with one joint
    # (free for the root, ball otherwise); End Sites have no body and no joint.
    assert model.nbody - 1 == len(simulated) == model.njnt
    assert ch.simulated_joints == tuple(simulated)
    assert model.nq == 7 + 4 * (len(simulated) - 1)
    assert model.nv == 6 + 3 * (len(simulated) - 1)
    assert model.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE
    assert all(t == mujoco.mjtJoint.mjJNT_BALL for t in model.jnt_type[1:])
    for j in simulated:
        assert model.body(ch.bodies[j]).name == skel.names[j]
        assert model.jnt_qposadr[model.body_jntadr[ch.bodies[j]]] == ch.qpos_address[j]
    assert np.all(model.body_mass[1:] > 0)
    assert 20.0 < ch.total_mass < 150.0


@pytest.mark.parametrize("which", ["walk", "wave"])
def test_round_trip_motion_qpos_motion_keeps_fk(which, request) -> None:
    motion = request.getfixturevalue(which)
    ch = build_model(motion.skeleton)
    back = motion_from_qpos(ch, qpos_from_motion(ch, motion), motion.frame_time)
    p_back, _ = back.forward_kinematics()
    p_clip, _ = motion.forward_kinematics()
    assert np.abs(p_back - p_clip).max() < 1e-9


def test_mujoco_body_positions_are_the_clip_fk_in_z_up_meters(walk, walker) -> None:
    data = mujoco.MjData(walker.model)
    positions, _ = walk.forward_kinematics()
    for frame in (0, 100, 300):
        set_state(walker, data, walk, frame)
        expected = positions[frame] * walker.scale @ Y_TO_Z_MATRIX.T
        for j in walker.simulated_joints:
            assert np.allclose(data.xpos[walker.bodies[j]], expected[j], atol=1e-9)


def test_gravity_without_torques_makes_it_fall(walk, walker) -> None:
    run = track(walker, walk, kp=0.0, kd=0.0, torques=False, n_frames=121, h=H)
    assert not run.unstable
    assert run.root_height[-1] < 0.5 * run.root_height[0]
    assert run.fell and run.fall_time is not None and run.fall_time < 0.6  # measured 0.34 s


def test_pd_with_the_root_held_follows_the_walk(walk, walker) -> None:
    errors = {}
    for kp in (100.0, 1000.0):
        run = track(walker, walk, kp=kp, kd=0.2 * np.sqrt(kp), hold_root=True, h=H)
        assert not run.unstable
        errors[kp] = run.error_cm
    # measured: kp=100 mean 19.2 cm (max 36); kp=1000 mean 1.2 cm (max 2.7)
    assert errors[1000.0].mean() < 2.0 and errors[1000.0].max() < 4.0
    assert errors[100.0].mean() > 5 * errors[1000.0].mean()


def test_pd_with_the_root_free_falls_within_the_clip(walk, walker) -> None:
    run = track(walker, walk, kp=1000.0, kd=0.2 * np.sqrt(1000.0), h=H)
    assert not run.unstable
    assert run.fell and run.fall_time is not None
    assert 0.5 < run.fall_time < 2.0 < walk.duration  # measured 1.25 s of 4.36 s


def _largest_stable_kp(walker, walk, kd_per_kp: float, stable_pd: bool) -> float:
    def stable(kp: float) -> bool:
        run = track(walker, walk, kp=kp, kd=kd_per_kp * kp, hold_root=True, n_frames=61, h=H,
                    stable_pd=stable_pd)
        return not run.unstable and run.error_cm.max() < 50.0

    lo, hi = 100.0, 1e6
    for _ in range(10):
        mid = float(np.sqrt(lo * hi))
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo


def test_largest_stable_kp_is_near_omega_h_equals_two(walk, walker) -> None:
    i_min = float(effective_inertia(walker, walk).min())  # kg m^2, a hand DOF (armature incl.)
    predicted = i_min * (2.0 / H) ** 2  # omega_max h = 2 with omega = sqrt(kp / I)
    kp_max = _largest_stable_kp(walker, walk, 0.0, stable_pd=False)
    # measured: I_min 0.0105, predicted 1.5e4, largest stable 1.04e4 (omega h = 1.66)
    assert 0.4 * predicted < kp_max < 1.0 * predicted


def test_stable_pd_is_stable_where_plain_pd_is_not(walk, walker) -> None:
    kp = 1e4  # kd = kp h, Tan et al.'s condition for stable PD
    plain = track(walker, walk, kp=kp, kd=kp * H, hold_root=True, n_frames=121, h=H)
    spd = track(walker, walk, kp=kp, kd=kp * H, hold_root=True, n_frames=121, h=H,
                stable_pd=True)
    assert plain.unstable
    assert not spd.unstable and spd.error_cm.mean() < 1.0  # measured 0.26 cm


def test_stable_pd_ceiling_is_the_first_order_position_term(walk, walker) -> None:
    """One joint with implicit damping b = h kd / I and the position predicted at q + h q̇ is
    stable iff a = kp h² / I < (4 + 2b) / 3 (docs/physics.md): with kd = kp h that is a < 4,
    the same ceiling as undamped plain PD; with kd = 10 kp h there is none. Measured: the
    first stops at a = 4.02 (I = I_min), the second is stable up to kp = 1e8."""
    i_min = float(effective_inertia(walker, walk).min())
    kp = 8.0 * i_min / H**2  # a = 8: twice the ceiling of kd = kp h
    low = track(walker, walk, kp=kp, kd=kp * H, hold_root=True, n_frames=61, h=H,
                stable_pd=True)
    high = track(walker, walk, kp=kp, kd=10 * kp * H, hold_root=True, n_frames=61, h=H,
                 stable_pd=True)
    assert low.unstable or low.error_cm.max() > 50.0
    assert not high.unstable and high.error_cm.max() < 5.0


def test_zero_torque_limit_is_the_passive_ragdoll(walk, walker) -> None:
    clipped = track(walker, walk, kp=1000.0, kd=6.0, torque_limit=0.0, n_frames=31, h=H)
    passive = track(walker, walk, kp=0.0, kd=0.0, torques=False, n_frames=31, h=H)
    assert np.allclose(clipped.root_height, passive.root_height, atol=1e-12)


def test_held_root_follows_the_clip_root(walk, walker) -> None:
    run = track(walker, walk, kp=300.0, kd=3.5, hold_root=True, n_frames=31, h=H)
    assert np.allclose(run.motion.root_positions, walk.root_positions[:31], atol=1e-9)
    assert run.motion.n_frames == 31 and run.h == pytest.approx(H, rel=1e-4)  # frame_time / 5
