import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import ikteach as ik
from ikteach.core import buss_trees
from ikteach.core.tree import ancestors, depth_levels
from strategies import random_trees

Y = buss_trees.y_tree()
DOUBLE_Y = buss_trees.double_y_tree()
R2, H3 = 1 / np.sqrt(2), np.sqrt(3) / 2


@given(random_trees(), st.integers(0, 2**31 - 1))
def test_stacked_jacobian_agrees_with_autodiff_on_random_trees(arm, seed):
    theta = np.random.default_rng(seed).uniform(-np.pi, np.pi, arm.n_joints)
    J = ik.core.tree.tree_jacobian(arm, theta)
    assert J.shape == (3 * arm.n_effectors, arm.n_joints)
    np.testing.assert_allclose(J, ik.core.tree.tree_jacobian_autodiff(arm, theta), atol=1e-10)


def walk_joint_by_joint(arm, theta):
    """tree_frames' formulas in numpy, one joint at a time in the order they are listed."""
    rest, axes = np.asarray(arm.positions), np.asarray(arm.axes)
    R, p, z = np.zeros((arm.n_joints, 3, 3)), np.zeros((arm.n_joints, 3)), np.zeros((arm.n_joints, 3))
    for j, parent in enumerate(arm.parents):
        Rp, pp = (np.eye(3), rest[j]) if parent < 0 else (R[parent], p[parent] + R[parent] @ (rest[j] - rest[parent]))
        a = axes[j]
        K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
        R[j] = Rp @ (np.eye(3) + np.sin(theta[j]) * K + (1 - np.cos(theta[j])) * K @ K)
        p[j], z[j] = pp, Rp @ a
    on = list(arm.effector_parents)
    x = p[on] + np.einsum("kab,kb->ka", R[on], np.asarray(arm.effectors) - rest[on])
    return p, z, x


FOREST = ik.tree(np.random.default_rng(5).normal(size=(7, 3)), np.random.default_rng(6).normal(size=(7, 3)),
                 [-1, 0, -1, 1, 2, 4, 0], np.random.default_rng(7).normal(size=(3, 3)), [3, 5, 6])


@given(st.one_of(random_trees(), st.just(FOREST), st.just(DOUBLE_Y)), st.integers(0, 2**31 - 1))
def test_the_level_by_level_walk_equals_the_joint_by_joint_walk(arm, seed):
    """tree_frames turns all joints of one depth at once; listed order, roots and depths mixed
    (FOREST: two roots, a joint listed after deeper ones) give the same frames."""
    theta = np.random.default_rng(seed).uniform(-np.pi, np.pi, arm.n_joints)
    for ours, plain in zip(ik.core.tree.tree_frames(arm, theta), walk_joint_by_joint(arm, theta)):
        np.testing.assert_allclose(ours, plain, atol=1e-12)


def test_depth_levels_put_every_parent_one_level_up():
    levels = depth_levels(FOREST.parents)
    assert [lv.tolist() for lv in levels] == [[0, 2], [1, 4, 6], [3, 5]]


@pytest.mark.parametrize("arm", [Y, DOUBLE_Y], ids=["Y", "double Y"])
def test_buss_tree_jacobians_agree_with_autodiff(arm):
    theta = np.random.default_rng(1).uniform(-1, 1, arm.n_joints)
    np.testing.assert_allclose(ik.core.tree.tree_jacobian(arm, theta), ik.core.tree.tree_jacobian_autodiff(arm, theta),
                               atol=1e-10)


def test_y_tree_matches_the_published_rest_pose():
    # BuildTreeYShape: nodes 0-6 joints, 7-8 effectors
    p, w, x = map(np.asarray, ik.core.tree.tree_frames(Y, np.zeros(7)))
    np.testing.assert_allclose(p, [[0, -.5, 0], [0, .4, 0], [0, .4, 0], [.5, 1, 0], [-.5, 1, 0],
                                   [.7, 1.3, 0], [-.8, 1.5, 0]])
    u1 = [np.sqrt(14) / 8, 1 / 8, 7 / 8]
    np.testing.assert_allclose(w, [[0, 0, 1]] * 3 + [[1, 0, 0]] * 2 + [u1] * 2)
    np.testing.assert_allclose(x, [[.7, 2, 0], [-.8, 1.9, 0]])
    assert Y.n_joints == 7 and Y.n_effectors == 2


def test_y_tree_branches_each_move_only_their_own_effector():
    assert ancestors(Y).tolist() == [[1, 1, 0, 1, 0, 1, 0], [1, 0, 1, 0, 1, 0, 1]]
    x0 = np.asarray(ik.core.tree.tree_fk(Y, np.zeros(7)))
    theta = np.zeros(7)
    theta[1] = np.pi / 2                 # left fork joint about z through (0, 0.4, 0)
    x = np.asarray(ik.core.tree.tree_fk(Y, theta))
    np.testing.assert_allclose(x[1], x0[1], atol=1e-12)
    np.testing.assert_allclose(x[0], [0 - 1.6, 0.4 + 0.7, 0], atol=1e-12)  # (0.7, 1.6) turned 90°


def test_double_y_tree_matches_the_published_rest_pose_and_structure():
    p, w, x = map(np.asarray, ik.core.tree.tree_frames(DOUBLE_Y, np.zeros(25)))
    assert DOUBLE_Y.n_joints == 25 and DOUBLE_Y.n_effectors == 4
    y0 = -0.5 + 0.5 * R2
    np.testing.assert_allclose(x, [[0.5 * R2 + 1.5 * H3, y0 + 0.75, 0], [0.5 * R2 + 1.5 * H3, y0 + 1.5 * H3, 0],
                                   [-0.5 * R2 - 1.5 * H3, y0 + 1.5 * H3, 0], [-0.5 * R2 - 1.5 * H3, y0 + 0.75, 0]])
    np.testing.assert_allclose(p[:4], [[0, -1.5, 0], [0, -1, 0], [0, -1, 0], [0, -0.5, 0]])
    np.testing.assert_allclose(w[0], [np.sqrt(14) / 8, 1 / 8, 7 / 8])
    # the demo's node parents, with effector nodes 11, 16, 23, 28 removed from the numbering
    paths = [{10, 9, 8, 7, 5, 3, 2, 1, 0}, {14, 13, 12, 11, 6, 3, 2, 1, 0},
             {20, 19, 18, 16, 15, 4, 2, 1, 0}, {24, 23, 22, 21, 17, 4, 2, 1, 0}]
    assert [set(np.flatnonzero(row)) for row in ancestors(DOUBLE_Y)] == paths


def test_targets_are_the_published_sums_of_sines():
    t = 0.3
    np.testing.assert_allclose(buss_trees.y_targets(t)[0, 0],
                               [2 + 1.5 * np.sin(1.8), 1.2 + 0.2 * np.sin(2.1), 0.3 + 0.2 * np.sin(2.4)])
    np.testing.assert_allclose(buss_trees.double_y_targets(t)[0, 3],
                               [-1.6 + 1.6 * np.sin(1.2), 0.3 + 0.6 * np.sin(1.2), -0.2 + 0.6 * np.sin(0.9)])
    assert buss_trees.double_y_targets(buss_trees.times(10)).shape == (10, 4, 3)


@pytest.mark.parametrize("method", ["dls", "sdls", "pinv"])
def test_solve_reaches_one_target_per_effector(method):
    goal = np.random.default_rng(2).uniform(-0.6, 0.6, 25)
    targets = np.asarray(ik.core.tree.tree_fk(DOUBLE_Y, goal))
    res = ik.solve(DOUBLE_Y, targets, np.zeros(25), method=method, damping=0.1, tol=1e-4, max_iter=2000)
    assert res.status == "converged", res
    assert np.all(np.linalg.norm(np.asarray(ik.core.tree.tree_fk(DOUBLE_Y, res.theta)) - targets, axis=1) < 1e-4)


def test_out_of_reach_tree_targets_stall_without_nan():
    targets = np.array([[10.0, 0, 0], [-10.0, 0, 0]])
    # with Buss's error clamp (D_max = 0.4), as in his demo; unclamped SDLS keeps swinging here
    res = ik.solve(Y, targets, np.zeros(7), method="sdls", clamp=buss_trees.D_MAX, max_iter=3000)
    assert res.status == "stalled"
    assert np.all(np.isfinite(res.theta)) and np.isfinite(res.error)


def test_solve_batch_on_a_tree():
    rng = np.random.default_rng(4)
    targets = np.stack([np.asarray(ik.core.tree.tree_fk(Y, rng.uniform(-0.5, 0.5, 7))) for _ in range(3)])
    batch = ik.solve_batch(Y, targets, np.zeros(7), method="dls", damping=0.1, tol=1e-4, max_iter=2000)
    assert batch.counts()["converged"] == 3


def test_tracking_follows_the_y_targets():
    targets = buss_trees.y_targets(buss_trees.times(300))
    res = ik.track(Y, targets, method="sdls", clamp=buss_trees.D_MAX)
    assert res.theta.shape == (301, 7) and res.error.shape == (300,)
    assert np.all(np.isfinite(res.theta))
    # target 0 is at times out of reach, so the error never reaches 0; but following the
    # targets must do far better than standing still in the rest pose
    still = np.linalg.norm(targets - np.asarray(ik.core.tree.tree_fk(Y, np.zeros(7))), axis=2).sum(axis=1)
    assert res.error.mean() < 0.4 * still.mean()


def test_bad_tree_input_names_the_parameter():
    with pytest.raises(ValueError, match="parents"):
        ik.tree(np.zeros((2, 3)), np.eye(3)[:2], [-1, 1], [[0, 0, 1]], [1])
    with pytest.raises(ValueError, match="effector_parents"):
        ik.tree(np.zeros((2, 3)), np.eye(3)[:2], [-1, 0], [[0, 0, 1]], [2])
    with pytest.raises(ValueError, match="axes"):
        ik.tree(np.zeros((2, 3)), np.zeros((2, 3)), [-1, 0], [[0, 0, 1]], [1])
    with pytest.raises(ValueError, match="target"):
        ik.solve(Y, np.zeros(3), np.zeros(7))
    with pytest.raises(ValueError, match="method"):
        ik.solve(Y, np.zeros((2, 3)), np.zeros(7), method="ccd")


def test_tree_animation_titles_each_frame_with_its_time_and_has_a_still():
    from ikteach.pictures import plot, tree_plot

    times = np.array([0.0, 0.25, 0.5])
    targets = buss_trees.y_targets(times)
    thetas = np.zeros((3, Y.n_joints))
    anim = tree_plot.animate_tree(Y, thetas, targets, times=times, title="Y tree, SDLS")
    assert list(anim.iterations) == [0, 1, 2] and anim.still == 2
    ax = anim._fig.axes[0]
    assert ax.get_title() == "Y tree, SDLS: τ =  0.50"  # laid out at the last frame (Buss's time τ)
    assert {t.get_text() for t in ax.get_legend().get_texts()} >= {"end effectors", "targets"}
    anim._draw_frame(1)
    assert ax.get_title() == "Y tree, SDLS: τ =  0.25"
    assert plot.still_png(anim)[:8] == b"\x89PNG\r\n\x1a\n"


def _tree_tasks():
    from ikteach.characters.clip_ik import MaskedTreeTask
    from ikteach.core.tree import TreeTask

    mask = tuple(float(k % 3 != 0) for k in range(DOUBLE_Y.n_joints))
    return [TreeTask(), MaskedTreeTask(mask=mask)]


@pytest.mark.parametrize("task", _tree_tasks(), ids=["tree", "masked tree (clip_ik)"])
@pytest.mark.parametrize("arm", [Y, DOUBLE_Y], ids=["Y", "double Y"])
def test_error_and_jacobian_from_one_walk_equal_the_two_calls_to_the_bit(arm, task):
    """Solves and tracks take e and J of a tree from one tree_frames walk: a task that
    changes jacobian() (clip_ik's mask) must change error_and_jacobian() too."""
    rng = np.random.default_rng(2)
    theta = rng.uniform(-1, 1, arm.n_joints)
    target = np.asarray(ik.core.tree.tree_fk(arm, rng.uniform(-1, 1, arm.n_joints)))
    if len(getattr(task, "mask", ())) not in (0, arm.n_joints):
        task = type(task)(mask=task.mask[: arm.n_joints])
    e, J = task.error_and_jacobian(arm, target, theta)
    assert np.asarray(e).tobytes() == np.asarray(task.error(arm, target, theta)).tobytes()
    assert np.asarray(J).tobytes() == np.asarray(task.jacobian(arm, theta)).tobytes()
