import numpy as np
import pytest

from ikteach.characters import bvh, clip_ik, footplant, skeleton, walk

LONG_LEGS = {"LeftLeg": 1.2, "RightLeg": 1.2, "LeftFoot": 1.1, "RightFoot": 1.1}  # thighs, shins
FEET = ["LeftFoot", "RightFoot"]


@pytest.fixture(scope="module")
def clip():
    return bvh.load(bvh.walk_path())


@pytest.fixture(scope="module")
def cleanup(clip):
    return footplant.clean_clip(*clip, LONG_LEGS)


def _feet(sk, motion):
    rig = skeleton.rig(sk, FEET)
    return skeleton.world_points(rig, *skeleton.angles(rig, motion.frames))


def test_contacts_match_the_generators_stance_phases(clip):
    sk, motion = clip
    contact = footplant.contacts(_feet(sk, motion), motion.frame_time, height=9.0, speed=15.0)
    t = np.arange(len(motion)) * motion.frame_time
    for k, phase in enumerate([0.0, 0.5]):          # left, right (see ikteach/characters/walk.py)
        u = t / walk.CYCLE - phase
        stance = (u - np.floor(u)) < walk.DUTY
        found, truth = footplant.intervals(contact[:, k]), footplant.intervals(stance)
        assert len(found) == len(truth) >= 5
        for (a, b), (c, d) in zip(found, truth):    # each contact found within a frame
            assert abs(a - c) <= 1 and abs(b - d) <= 1


def test_the_original_clip_does_not_skate(clip):
    sk, motion = clip
    feet = _feet(sk, motion)
    contact = footplant.contacts(feet, motion.frame_time, height=9.0, speed=15.0)
    assert np.all(footplant.foot_skate(feet, contact) < 0.01)   # cm over the whole clip


def test_retargeting_makes_the_feet_skate_and_planting_removes_95_percent(cleanup):
    before, after = cleanup.skate_before, cleanup.skate_after
    assert np.all(before > 30.0)                  # cm of sliding per foot
    assert np.all(after <= 0.05 * before)
    assert cleanup.feet_before.shape == cleanup.feet_after.shape == (150, 2, 3)


def test_planting_reaches_the_targets_and_leaves_other_joints_alone(cleanup):
    reached = np.linalg.norm(cleanup.feet_after - cleanup.targets, axis=-1)
    assert reached.max() < 1e-2                   # cm
    active = sum((footplant.leg_joints(cleanup.rig, f) for f in FEET), [])
    idle = np.setdiff1d(np.arange(cleanup.rig.n_joints), active)
    np.testing.assert_array_equal(cleanup.theta_after[:, idle], cleanup.theta_before[:, idle])


def test_planting_makes_no_pops(cleanup):
    """The largest frame-to-frame joint change stays within 1.5x the clip's own."""
    assert footplant.largest_step(cleanup.theta_after) <= 1.5 * footplant.largest_step(cleanup.theta_before)


def test_planted_toes_stay_on_the_floor_and_the_feet_keep_the_clips_orientation(cleanup):
    """The retargeted clip puts the toes 0.3 cm under the floor; the cleaned one never below it
    (floor 0, tolerance of the solve), and each foot keeps the clip's ankle-to-toe vector
    instead of pitching with the knee (without the toe rows it pitched them 1 cm under)."""
    assert cleanup.toes_before[..., 1].min() < -0.2
    assert cleanup.toes_after[..., 1].min() > -1e-3
    foot_before = cleanup.toes_before - cleanup.feet_before
    foot_after = cleanup.toes_after - cleanup.feet_after
    assert np.abs(foot_after - foot_before).max() < 1e-2


def test_floor_lift_moves_a_foot_up_as_one_piece():
    targets = np.zeros((2, 1, 2, 3))
    targets[:, 0, :, 1] = [[8.0, -0.5], [9.0, 2.0]]        # frame 0: toe under the floor
    lifted = footplant.floor_lift(targets, 0.0)
    np.testing.assert_allclose(lifted[:, 0, :, 1], [[8.5, 0.0], [9.0, 2.0]])
    with pytest.raises(ValueError, match="^floor:"):
        footplant.floor_lift(targets, "low")


def test_foot_skate_counts_only_frames_in_contact():
    positions = np.zeros((4, 1, 3))
    positions[:, 0, 0] = [0, 1, 3, 6]             # steps of 1, 2, 3 along x
    positions[:, 0, 1] = [5, 6, 7, 8]             # vertical motion never counts
    contact = np.array([[True], [True], [False], [True]])
    np.testing.assert_allclose(footplant.foot_skate(positions, contact), [1.0])


def test_plant_targets_hold_still_in_contact_and_glide_between():
    positions = np.zeros((6, 1, 3))
    positions[:, 0, 2] = [0, 1, 2, 3, 4, 5]
    contact = np.array([True, True, False, False, True, True])[:, None]
    targets = footplant.plant_targets(positions, contact)[:, 0, 2]
    # corrections -0.5 at frame 1 and +0.5 at frame 4, interpolated over frames 2 and 3
    np.testing.assert_allclose(targets, [0.5, 0.5, 2 - 1 / 6, 3 + 1 / 6, 4.5, 4.5])


def test_bad_input_names_the_parameter(clip, cleanup):
    sk, motion = clip
    feet = _feet(sk, motion)
    with pytest.raises(ValueError, match="^speed: expected a number >"):
        footplant.contacts(feet, motion.frame_time, height=9.0, speed=-1)
    with pytest.raises(ValueError, match="^frame_time:"):
        footplant.contacts(feet, 0.0, height=9.0, speed=15)
    with pytest.raises(ValueError, match="^positions: expected shape"):
        footplant.contacts(feet[:, :, :2], motion.frame_time, height=9.0, speed=15)
    with pytest.raises(ValueError, match="^contact: expected shape"):
        footplant.foot_skate(feet, np.ones((3, 2), bool))
    with pytest.raises(ValueError, match=r"^scales\['LeftLeg'\]: expected a number >"):
        footplant.retarget(sk, motion, {"LeftLeg": 0})
    with pytest.raises(ValueError, match="^joint: expected one of"):
        footplant.retarget(sk, motion, {"Tail": 2})
    rig, root = cleanup.rig, cleanup.root
    targets = cleanup.all_targets                  # ankles, then toes
    with pytest.raises(ValueError, match="^targets: expected shape"):
        clip_ik.solve_clip(rig, root, cleanup.theta_before, cleanup.targets, [0])
    with pytest.raises(ValueError, match="^active: expected indices"):
        clip_ik.solve_clip(rig, root, cleanup.theta_before, targets, [rig.n_joints])
    with pytest.raises(ValueError, match="^damping:"):
        clip_ik.solve_clip(rig, root, cleanup.theta_before, targets, [0], damping=-1)
