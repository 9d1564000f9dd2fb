import bvhio
import numpy as np
import pytest

import ikteach as ik
from ikteach.characters import bvh, skeleton, walk

# Channel orders other than ZXY, a root offset, a joint without channels and an end site:
# forward kinematics must agree with bvhio (an independent reader) on all of it.
ODD = """HIERARCHY
ROOT Pelvis
{
  OFFSET 1 2 3
  CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation
  JOINT Thigh
  {
    OFFSET 0 -4 1
    CHANNELS 3 Yrotation Zrotation Xrotation
    JOINT Fixed
    {
      OFFSET 0.5 -3 0
      CHANNELS 0
      JOINT Shin
      {
        OFFSET 0 -2 0.5
        CHANNELS 2 Xrotation Zrotation
        End Site
        {
          OFFSET 0 -1 2
        }
      }
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.04
0 0 0 0 0 0 0 0 0 0 0
1 -2 0.5 30 -20 10 45 15 -60 70 5
-3 1 2 -90 45 120 -30 170 20 -45 80
"""


@pytest.fixture(scope="module")
def clip():
    return bvh.load(bvh.walk_path())


def _bvhio_positions(path, frame):
    root = bvhio.readAsHierarchy(str(path))
    root.loadPose(frame)
    return {j.Name: np.array(j.PositionWorld) for j, _, _ in root.layout()}


def _ours(sk, motion, frame):
    rig = skeleton.rig(sk, sk.names)
    root, theta = skeleton.angles(rig, motion.frames)
    return dict(zip(sk.names, skeleton.world_points(rig, root[frame], theta[frame])[0]))


@pytest.mark.parametrize("frame", [0, 1, 2])
def test_forward_kinematics_agrees_with_bvhio_on_any_channel_order(tmp_path, frame):
    path = tmp_path / "odd.bvh"
    path.write_text(ODD)
    sk, motion = bvh.load(path)
    assert sk.channels[1] == ("Yrotation", "Zrotation", "Xrotation") and sk.channels[2] == ()
    theirs, ours = _bvhio_positions(path, frame), _ours(sk, motion, frame)
    assert set(theirs) == set(ours)
    for name in ours:
        np.testing.assert_allclose(ours[name], theirs[name], atol=1e-4, err_msg=name)


@pytest.mark.parametrize("frame", [0, 37, 149])
def test_walk_clip_agrees_with_bvhio(clip, frame):
    sk, motion = clip
    theirs, ours = _bvhio_positions(bvh.walk_path(), frame), _ours(sk, motion, frame)
    for name in ours:
        np.testing.assert_allclose(ours[name], theirs[name], atol=1e-3, err_msg=name)


def test_header_agrees_with_bvhio(clip):
    sk, motion = clip
    theirs = bvhio.readAsBvh(bvh.walk_path())
    joints = [j for j, _, _ in theirs.Root.layout()]
    assert [j.Name for j in joints] == list(sk.names)
    assert [tuple(j.Channels) for j in joints] == list(sk.channels)
    np.testing.assert_allclose([list(j.Offset) for j in joints], sk.offsets, atol=1e-6)
    assert theirs.FrameCount == len(motion) == 150
    assert theirs.FrameTime == pytest.approx(motion.frame_time)


def test_save_then_load_round_trips(clip, tmp_path):
    sk, motion = clip
    path = bvh.save(tmp_path / "copy.bvh", sk, motion)
    sk2, motion2 = bvh.load(path)
    assert (sk2.names, sk2.parents, sk2.channels, sk2.end_parents) == \
        (sk.names, sk.parents, sk.channels, sk.end_parents)
    np.testing.assert_array_equal(sk2.offsets, sk.offsets)
    np.testing.assert_array_equal(sk2.end_offsets, sk.end_offsets)
    np.testing.assert_allclose(motion2.frames, motion.frames, atol=1e-6)
    assert motion2.frame_time == motion.frame_time
    assert path.read_text() == open(bvh.walk_path()).read()  # the shipped file is in our format


def test_odd_file_round_trips(tmp_path):
    (tmp_path / "odd.bvh").write_text(ODD)
    sk, motion = bvh.load(tmp_path / "odd.bvh")
    sk2, motion2 = bvh.load(bvh.save(tmp_path / "again.bvh", sk, motion))
    assert sk2.channels == sk.channels and sk2.parents == sk.parents
    np.testing.assert_allclose(motion2.frames, motion.frames)


def test_shipped_walk_is_what_the_generator_makes(clip):
    assert bvh.format_bvh(walk.walk_skeleton(), walk.walk_motion()) == open(bvh.walk_path()).read()


def test_a_ball_joint_is_three_revolute_axes_in_channel_order(tmp_path):
    (tmp_path / "odd.bvh").write_text(ODD)
    sk, _ = bvh.load(tmp_path / "odd.bvh")
    rig = sk.rig()
    assert isinstance(rig.tree, ik.core.tree.Tree) and rig.tree.n_joints == 3 + 3 + 2
    np.testing.assert_allclose(rig.tree.axes[:8], [[1, 0, 0], [0, 1, 0], [0, 0, 1],   # pelvis XYZ
                                                   [0, 1, 0], [0, 0, 1], [1, 0, 0],   # thigh YZX
                                                   [1, 0, 0], [0, 0, 1]])             # shin XZ
    assert rig.tree.parents == (-1, 0, 1, 2, 3, 4, 5, 6)
    assert rig.revolutes("Thigh", ["Xrotation"]) == [5]
    assert rig.points == ("Pelvis", "Thigh", "Fixed", "Shin", "Shin_end")


def test_rig_jacobian_agrees_with_autodiff(clip):
    sk, motion = clip
    rig = skeleton.rig(sk, ["LeftFoot", "RightHand_end", "Head_end"])
    _, theta = skeleton.angles(rig, motion.frames)
    np.testing.assert_allclose(ik.core.tree.tree_jacobian(rig.tree, theta[40]),
                               ik.core.tree.tree_jacobian_autodiff(rig.tree, theta[40]), atol=1e-8)


def test_frames_from_inverts_angles(clip):
    sk, motion = clip
    rig = skeleton.rig(sk, ["Head"])
    root, theta = skeleton.angles(rig, motion.frames)
    np.testing.assert_allclose(skeleton.frames_from(rig, root, theta, motion.frames), motion.frames,
                               atol=1e-9)


@pytest.mark.parametrize("text, words", [
    ("", ["path", "HIERARCHY"]),
    ("HIERARCHY\nROOT A\n{\nOFFSET 0 0\n}", ["path", "line 5", "offset number"]),
    ("HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 1 Wrotation\n}\nMOTION\nFrames: 1\nFrame Time: 1\n0",
     ["path", "line 5", "channel name"]),
    ("HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}\nMOTION\nFrames: 2\nFrame Time: 0.1\n0",
     ["path", "channel value"]),
    ("HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}\nMOTION\nFrames: 1\nFrame Time: 0\n0",
     ["path", "frame time"]),
])
def test_bad_files_name_the_line_and_what_was_expected(tmp_path, text, words):
    path = tmp_path / "bad.bvh"
    path.write_text(text)
    with pytest.raises(ValueError) as info:
        bvh.load(path)
    for word in words:
        assert word in str(info.value)


def test_bad_arguments_name_the_parameter(clip, tmp_path):
    sk, motion = clip
    with pytest.raises(ValueError, match="^path: no such file"):
        bvh.load(tmp_path / "missing.bvh")
    with pytest.raises(ValueError, match="^path: expected a file name"):
        bvh.load(3)
    with pytest.raises(ValueError, match="^skeleton:"):
        bvh.save(tmp_path / "x.bvh", "skeleton", motion)
    with pytest.raises(ValueError, match="^motion.frames: expected shape"):
        bvh.save(tmp_path / "x.bvh", sk, bvh.Motion(motion.frames[:, :5], 0.1))
    with pytest.raises(ValueError, match="^joint: expected one of"):
        skeleton.rig(sk, ["LeftFoot", "Tail"])
    with pytest.raises(ValueError, match="^points: joint 'Hips' has no end site"):
        skeleton.rig(sk, ["Hips_end"])
    with pytest.raises(ValueError, match="^frames: expected shape"):
        skeleton.angles(skeleton.rig(sk), motion.frames[:, 1:])
