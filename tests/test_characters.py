"""Reach with feet planted, look-at and the drawings of notebook 09."""
import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from ikteach.characters import bvh, clip_ik, look_at, skeleton
from ikteach.pictures import character_plot, character_scene, scene  # noqa: E402

REACH = ["LeftFoot", "RightFoot", "LeftFoot_end", "RightFoot_end", "RightHand_end"]
MAY_TURN = {"Hips": ["Xrotation"], "Spine": ["Xrotation"], "Chest": ["Xrotation", "Yrotation"],
            "RightArm": None, "RightForeArm": ["Xrotation"],
            "LeftUpLeg": None, "LeftLeg": ["Xrotation"], "LeftFoot": ["Xrotation"],
            "RightUpLeg": None, "RightLeg": ["Xrotation"], "RightFoot": ["Xrotation"]}


@pytest.fixture(scope="module")
def clip():
    sk, motion = bvh.load(bvh.walk_path())
    rig = skeleton.rig(sk, REACH)
    root, theta = skeleton.angles(rig, motion.frames)
    return sk, rig, root[2], theta[2]


def test_reach_with_a_hand_keeps_both_feet_planted(clip):
    sk, rig, root, theta = clip
    start = skeleton.world_points(rig, root, theta)[0]
    goal = start.copy()
    goal[4] = root + [-30.0, -40.0, 45.0]
    active = sum((rig.revolutes(n, c) for n, c in MAY_TURN.items()), [])
    res = clip_ik.solve_clip(rig, root[None], theta[None], goal[None], active, tol=1e-2, damping=5.0,
                             clamp=2.0, max_iter=500)
    after = skeleton.world_points(rig, root, res.theta[0])[0]
    assert res.status[0] == "converged"
    assert np.linalg.norm(after[4] - start[4]) > 40.0            # the hand really moved
    assert np.all(np.linalg.norm(after - goal, axis=1) < 1e-2)    # hand on target, feet where they were
    idle = np.setdiff1d(np.arange(rig.n_joints), active)
    np.testing.assert_array_equal(res.theta[0, idle], theta[idle])


def test_look_at_turns_only_the_neck_and_head_until_the_eyes_face_the_point(clip):
    sk, rig, root, theta = clip
    point = root + [80.0, 60.0, 150.0]
    eyes = skeleton.rig(sk, [("Head", look_at.EYES)])
    gaze = skeleton.rig(sk, [("Head", np.add(look_at.EYES, [0, 0, 100.0]))])
    before = look_at.gaze_angle(skeleton.world_points(eyes, root, theta)[0, 0],
                                skeleton.world_points(gaze, root, theta)[0, 0], point)
    new, angle = look_at.look_at(sk, root, theta, point)
    assert before > 20.0 and angle < 0.01
    turned = {sk.names[rig.joint_of[i]] for i in np.flatnonzero(new != theta)}
    assert turned <= {"Neck", "Head"} and turned


def test_gaze_angle_is_the_angle_between_the_two_directions():
    assert look_at.gaze_angle(np.zeros(3), [1.0, 0, 0], [0, 2.0, 0]) == pytest.approx(90.0)
    assert look_at.gaze_angle(np.zeros(3), [1.0, 1.0, 0], [3.0, 3.0, 0]) == pytest.approx(0.0, abs=1e-6)


def test_offset_points_and_bones(clip):
    sk, _, root, theta = clip
    rig = skeleton.rig(sk, ["Hips", "Neck", "Head", ("Head", (0, 8, 10)), "Head_end"])
    assert rig.bones() == [(0, 1), (1, 2), (2, 3), (2, 4)]      # Neck hangs on Hips (Spine not drawn)
    p = skeleton.world_points(rig, root, np.zeros(rig.n_joints))[0]
    np.testing.assert_allclose(p[3] - p[2], [0, 8, 10], atol=1e-12)


def test_drawings_show_every_bone(clip):
    import matplotlib.pyplot as plt

    sk, _, root, theta = clip
    rig = skeleton.rig(sk)
    points = skeleton.world_points(rig, root, theta)[0]
    fig, ax = plt.subplots()
    lines, _ = character_plot.draw_skeleton(ax, rig, points, "front")
    assert len(lines) == len(rig.bones()) == len(rig.points) - 1
    np.testing.assert_allclose(lines[0].get_xydata(), points[list(rig.bones()[0])][:, [0, 1]])
    plt.close(fig)
    with pytest.raises(ValueError, match="^view: expected one of"):
        character_plot.draw_skeleton(ax, rig, points, "diagonal")


def test_views_are_not_mirrored(clip):
    """Seen from above (z forward up the page) the left foot is on the page's left; seen from
    the front it is on the page's right; drawing twice on one axes keeps the top view right."""
    import matplotlib.pyplot as plt

    sk, _, root, theta = clip
    rig = skeleton.rig(sk)
    points = skeleton.world_points(rig, root, theta)[0]
    left, right = rig.points.index("LeftFoot"), rig.points.index("RightFoot")
    for view, left_on_the_left in (("top", True), ("front", False)):
        fig, ax = plt.subplots()
        for _ in range(2):
            character_plot.draw_skeleton(ax, rig, points, view)
        fig.canvas.draw()
        i, j = character_plot.VIEWS[view]
        screen = ax.transData.transform(points[[left, right]][:, [i, j]])
        assert (screen[0, 0] < screen[1, 0]) == left_on_the_left, view
        plt.close(fig)


def test_character_scene_renders_off_screen(clip):
    sk, _, root, theta = clip
    rig = skeleton.rig(sk)
    points = skeleton.world_points(rig, root, theta)[0]
    image = scene.render(character_scene.character_scene(rig, points, targets=points[0] + 30))
    assert image.ndim == 3 and image.shape[2] == 3
    assert (image < 200).mean() > 0.01                            # something dark was drawn on white


def test_a_character_scene_has_alt_text_naming_the_target_and_the_point_beside_it(clip):
    sk, _, root, theta = clip
    rig = skeleton.rig(sk)
    points = skeleton.world_points(rig, root, theta)[0]
    hand = [k for k, name in enumerate(rig.points) if (name if isinstance(name, str) else name[0]) == "RightHand"]
    target = points[hand[0]] + [0.0, 0.0, 0.5]
    alt = character_scene.character_scene(rig, points, targets=target)._ikteach_alt
    assert alt.startswith("3-D view") and f"{len(points)} points" in alt
    assert "purple target ball" in alt and "on the RightHand (reached)" in alt
    away = character_scene.describe(rig, points, points[hand[0]] + [0.0, 0.0, 40.0])
    k = int(np.argmin(np.linalg.norm(points - (points[hand[0]] + [0.0, 0.0, 40.0]), axis=1)))
    gap = np.linalg.norm(points[k] - points[hand[0]] - [0.0, 0.0, 40.0])
    assert f"{gap:.1f} units from the nearest point" in away and "reached" not in away
    assert "target" not in character_scene.describe(rig, points)


def test_bad_input_names_the_parameter(clip):
    sk, rig, root, theta = clip
    with pytest.raises(ValueError, match="^point: expected shape"):
        look_at.look_at(sk, root, theta, [1.0, 2.0])
    with pytest.raises(ValueError, match="^distance:"):
        look_at.look_at(sk, root, theta, root + 100, distance=0)
    with pytest.raises(ValueError, match="^clamp:"):
        clip_ik.solve_clip(rig, root[None], theta[None], np.zeros((1, 5, 3)), [0], clamp=0)
    with pytest.raises(ValueError, match="^points: expected joint names or"):
        skeleton.rig(sk, [3])


def test_feet_first_priorities_keep_the_feet_when_the_hand_cannot_reach(clip):
    """Out of reach, stacked DLS lets the feet slide; with the feet as level 0 they stay."""
    import ikteach as ik

    sk, rig, root, theta = clip
    active = sum((rig.revolutes(n, c) for n, c in MAY_TURN.items()), [])
    lower, upper = theta.copy(), theta.copy()
    lower[active], upper[active] = -np.inf, np.inf            # the other joints are pinned
    start = skeleton.world_points(rig, root, theta)[0]
    far = start.copy()
    far[4] = root + [-30.0, -40.0, 200.0]
    options = dict(tol=1e-2, damping=5.0, clamp=2.0, max_iter=500, joint_limits=(lower, upper))
    slid = {}
    for name, levels in [("stacked", None), ("feet first", [0, 0, 0, 0, 1])]:
        res = ik.solve(rig.tree, far - root, theta, levels=levels, **options)
        p = skeleton.world_points(rig, root, res.theta)[0]
        slid[name] = np.linalg.norm(p[:4] - start[:4], axis=1).max()
        assert np.linalg.norm(p[4] - far[4]) < np.linalg.norm(start[4] - far[4]) - 20  # reached out
    # run to its stall (the motion rule), stacked DLS gives the feet only a little: 0.004 cm here
    assert slid["stacked"] > 1e-3 and slid["feet first"] < 1e-6
