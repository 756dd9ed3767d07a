"""course.foot_sliding: contact frames and how far planted feet slide, checked on hand-made
motions whose sliding is known in closed form, and on the blends of notebook 11."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from course import data
from course import keyframes as kf
from course.bvh import load_bvh
from course.data.registry import CMU_CM_PER_UNIT
from course.foot_sliding import foot_contacts, foot_sliding
from course.motion import Motion
from course.skeleton import Skeleton

PROPERTY = settings(max_examples=40, derandomize=True, deadline=None, database=None)
HIP = 10.0  # rest hip height of the hand-made skeleton: contacts below 1 unit, 3 units/s
TOES = ("LeftToeBase", "RightToeBase")


def planted_then_dragged(k: int, frames: int, speed: float, frame_time: float,
                         lift: float = 0.0) -> Motion:
    """A hip over one foot: the foot stands still for k frames, then is dragged along x at
    ``speed`` units per second (x_f = speed * dt * max(0, f - (k - 1))), ``lift`` above the
    floor while dragged."""
    skel = Skeleton(["Hips", "Foot"], [-1, 0], [[0.0, 0.0, 0.0], [0.0, -HIP, 0.0]])
    f = np.arange(frames)
    moved = np.maximum(0, f - (k - 1))
    root = np.stack([speed * frame_time * moved, HIP + lift * (moved > 0), 0 * f], axis=1)
    rotations = np.tile([1.0, 0.0, 0.0, 0.0], (frames, 2, 1))
    return Motion(skel, rotations, root.astype(float), frame_time)


@PROPERTY
@given(k=st.integers(2, 30), dragged=st.integers(2, 30), fps=st.sampled_from([30, 60, 120]),
       slow=st.floats(0.05, 0.95))
def test_a_slowly_dragged_foot_slides_its_drag(k, dragged, fps, slow):
    """Below the speed threshold (0.3 hip heights per second) every frame is a contact: the
    foot slides exactly the distance it was dragged, at the drag speed."""
    speed = slow * 0.3 * HIP
    clip = planted_then_dragged(k, k + dragged, speed, 1 / fps)
    s = foot_sliding(clip, ["Foot"], cm_per_unit=2.0)
    assert s.contact_frames.tolist() == [k + dragged]
    assert s.total_cm[0] == pytest.approx(2.0 * speed * dragged / fps, rel=1e-9)
    assert np.allclose(s.steps_cm[: k - 1], 0.0, atol=1e-12)
    np.testing.assert_allclose(s.speed_cm_per_s[k - 1:], 2.0 * speed, rtol=1e-9)
    # the mean over the k + dragged - 1 contact steps, in cm/s whatever the frame rate
    assert s.mean_cm_per_s[0] == pytest.approx(2.0 * speed * dragged / (k + dragged - 1),
                                               rel=1e-9)


@PROPERTY
@given(k=st.integers(2, 30), dragged=st.integers(3, 30), fast=st.floats(2.1, 10.0))
def test_a_fast_drag_is_not_a_contact_unless_the_contacts_say_so(k, dragged, fast):
    """Faster than twice the threshold, only the first k - 1 planted frames are contacts (the
    central difference at the last one sees half the drag speed), so the drag is not measured;
    measured on contacts given from elsewhere, it is all sliding."""
    speed, dt = fast * 0.3 * HIP, 1 / 30
    clip = planted_then_dragged(k, k + dragged, speed, dt)
    on = foot_contacts(clip, ["Foot"])
    assert on[:, 0].tolist() == [True] * (k - 1) + [False] * (dragged + 1)
    assert foot_sliding(clip, ["Foot"]).total_cm[0] == 0.0
    given_on = foot_sliding(clip, ["Foot"], contacts=np.ones((k + dragged, 1), bool),
                            cm_per_unit=1.0)
    assert given_on.total_cm[0] == pytest.approx(speed * dt * dragged, rel=1e-9)
    assert np.nanmax(given_on.speed_cm_per_s) == pytest.approx(speed, rel=1e-9)


def test_a_lifted_foot_is_not_in_contact():
    """Raised more than 0.1 hip heights above its lowest point, a slow foot is swinging."""
    k, dragged = 5, 6
    low = foot_contacts(planted_then_dragged(k, k + dragged, 0.5, 0.1, lift=0.9), ["Foot"])
    high = foot_contacts(planted_then_dragged(k, k + dragged, 0.5, 0.1, lift=1.1), ["Foot"])
    assert low.all() and high[:, 0].tolist() == [True] * k + [False] * dragged
    sliding = foot_sliding(planted_then_dragged(k, k + dragged, 0.5, 0.1, lift=1.1), ["Foot"])
    assert sliding.total_cm[0] == 0.0 and sliding.mean_cm_per_s[0] == 0.0


def test_thresholds_scale_with_the_skeleton():
    """Thresholds in hip heights: the same motion scaled by 3 has the same contacts."""
    clip = planted_then_dragged(4, 12, 2.5, 0.1)
    big = Motion(Skeleton(clip.skeleton.names, clip.skeleton.parents, 3 * clip.skeleton.offsets),
                 clip.local_rotations, 3 * clip.root_positions, clip.frame_time)
    small_s, big_s = foot_sliding(clip, ["Foot"]), foot_sliding(big, ["Foot"])
    np.testing.assert_array_equal(small_s.contacts, big_s.contacts)
    assert big_s.total_cm[0] == pytest.approx(3 * small_s.total_cm[0], rel=1e-12)


def test_never_in_contact_has_no_mean_and_prints_a_row_per_foot():
    clip = planted_then_dragged(2, 10, 100.0, 0.1)
    s = foot_sliding(clip, ["Foot"], contacts=np.zeros((10, 1), bool))
    assert s.contact_frames.tolist() == [0] and np.isnan(s.mean_cm_per_s[0])
    assert "nan cm/s mean" in str(s) and "nan cm/s max" in str(s)
    on = foot_sliding(clip, ["Foot"], contacts=np.ones((10, 1), bool), cm_per_unit=1.0)
    assert str(on).startswith("Foot") and "80.00 cm," in str(on) and "100.00 cm/s max" in str(on)


def test_a_one_frame_clip_has_no_steps_and_prints():
    """One frame: no step to slide, so no mean or largest speed (printing it raised numpy's
    "zero-size array to reduction operation fmax")."""
    s = foot_sliding(planted_then_dragged(1, 1, 0.0, 0.1), ["Foot"])
    assert s.steps_cm.shape == (0, 1) and s.total_cm.tolist() == [0.0]
    assert str(s) == ("Foot              1 contact frames: slides   0.00 cm,    nan cm/s mean,"
                      "    nan cm/s max")


def test_planted_feet_of_the_bundled_clip_do_not_slide():
    wave = data.load("wave")
    s = foot_sliding(wave, ("LeftFoot", "RightFoot"))
    assert np.all(s.contact_frames > 0.9 * wave.n_frames)  # standing nearly all the time
    assert np.nanmax(s.steps_cm) < 1e-2


def test_bad_input_names_the_argument():
    clip = planted_then_dragged(3, 8, 1.0, 0.1)
    with pytest.raises(ValueError, match="feet: .*'Lefty'"):
        foot_sliding(clip, ["Lefty"])
    with pytest.raises(ValueError, match="feet: expected a non-empty sequence"):
        foot_contacts(clip, "Foot")
    with pytest.raises(ValueError, match=r"contacts: expected booleans of shape \(8, 1\)"):
        foot_sliding(clip, ["Foot"], contacts=np.ones((3, 1), bool))
    with pytest.raises(ValueError, match="contacts: expected booleans"):
        foot_sliding(clip, ["Foot"], contacts=np.ones((8, 1)))
    with pytest.raises(ValueError, match="cm_per_unit"):
        foot_sliding(clip, ["Foot"], cm_per_unit=0.0)
    with pytest.raises(ValueError, match="height_tolerance, speed_tolerance"):
        foot_contacts(clip, ["Foot"], speed_tolerance=-1.0)
    assert CMU_CM_PER_UNIT == pytest.approx(5.644, abs=1e-3)


# --------------------------------------------------------------------------- blends
def test_concatenated_contacts_take_each_clip_and_both_in_the_fade():
    a = np.array([[1, 1], [1, 0], [0, 1], [1, 1]], bool)
    b = np.array([[1, 0], [1, 1], [0, 0]], bool)
    on = kf.concatenated_contacts(a, b, 2)
    assert on.tolist() == [[1, 1], [1, 0], [0, 0], [1, 1], [0, 0]]
    assert kf.concatenated_contacts(a, b, 0).tolist() == np.vstack([a, b]).tolist()
    with pytest.raises(ValueError, match="blend_frames: expected an integer from 0 to 3"):
        kf.concatenated_contacts(a, b, 4)
    with pytest.raises(ValueError, match="first, second: expected booleans"):
        kf.concatenated_contacts(a, b[:, :1], 1)


def test_matched_blend_slides_less_than_a_mismatched_one(shared_bvh_dir):
    walk = load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh")[1:]  # frame 0 is a T pose
    first = walk[:300]

    def seam_sliding(start, n=20):
        out = kf.concatenate(first, walk[start:], n)
        on = kf.concatenated_contacts(foot_contacts(first, TOES),
                                      foot_contacts(walk[start:], TOES), n)
        return np.nanmean(foot_sliding(out, TOES, contacts=on).speed_cm_per_s[300 - n:300])

    assert seam_sliding(129) < 0.5 * seam_sliding(150)
