"""The 3-D reachability map (ikteach/core/reach_map.py) on a real arm, the iiwa 14: points known
reachable with the tool orientation are reached, points beyond the reach are not, bad input
names its parameter; and its pyvista picture (ik.pictures.workspace_maps.reach_scene)."""
import numpy as np
import pytest

import ikteach as ik
from ikteach.core import reach_map as rm
from ikteach.core import robots

ARM = robots.iiwa14()
TOOL_DOWN = np.diag([1.0, -1.0, -1.0])  # the hand's z axis points down
STARTS = np.random.default_rng(3).uniform(-np.pi, np.pi, (2, 7))


def known_reachable(count, seed=0):
    """Hand positions the iiwa reaches holding TOOL_DOWN: its last three axes meet in the wrist
    centre w (the DH flange minus R o_7), the wrist turns the hand to any rotation, so
    p = w + R_t o_7 for the wrist centre of any joint angles (DH forward kinematics)."""
    o7 = np.asarray(ARM.offsets)[-1]
    out = []
    for q in np.random.default_rng(seed).uniform(-np.pi, np.pi, (count, 7)):
        T = robots.dh_fk(theta=q, **robots.IIWA14_DH)
        out.append(T[:3, 3] - T[:3, :3] @ o7 + TOOL_DOWN @ o7)
    return np.array(out)


@pytest.fixture(scope="module")
def small_map():
    far = np.array([[1.0, 1.0, 0.5], [0.0, 0.0, 1.5], [-1.4, 0.0, 0.0]])  # |p| > reach 1.306
    points = np.vstack([known_reachable(3), far])
    return rm.reach_map(ARM, TOOL_DOWN, points, STARTS, max_iter=50, stall_tol=0, damping=0.01)


def test_known_reachable_points_are_reached_and_far_ones_not(small_map):
    assert np.linalg.norm(small_map.points[3:], axis=1).min() > float(ik.reach(ARM))
    assert small_map.reached.tolist() == [True] * 3 + [False] * 3
    assert (small_map.status[:3] == "converged").all() and (small_map.status[3:] == "max_iter").all()
    assert small_map.converged.max() <= len(STARTS) and small_map.counts()["converged"] == 3


def test_a_reached_point_keeps_a_theta_that_holds_the_pose(small_map):
    for p, theta in zip(small_map.points[:3], small_map.theta[:3]):
        e_p, e_o = ik.pose_errors(ARM, theta, rm.tool_poses(TOOL_DOWN, p[None])[0])
        assert e_p < float(ik.reach(ARM)) / 3000 and e_o < 1 / 3000


def test_box_grid_runs_x_fastest_and_includes_both_ends():
    g = rm.box_grid([0.0, 0.0, 0.0], [1.0, 0.5, 0.5], 0.5)
    assert g.shape == (3 * 2 * 2, 3)
    np.testing.assert_allclose(g[:3, 0], [0.0, 0.5, 1.0])
    np.testing.assert_allclose(g[-1], [1.0, 0.5, 0.5])


@pytest.mark.parametrize("call, name", [
    (lambda: rm.reach_map(ik.planar_chain([1.0, 1.0]), TOOL_DOWN, [[0, 0, 0]], STARTS), "arm"),
    (lambda: rm.reach_map(ARM, 2 * TOOL_DOWN, [[0, 0, 0]], STARTS), "rotation"),
    (lambda: rm.reach_map(ARM, TOOL_DOWN[:2], [[0, 0, 0]], STARTS), "rotation"),
    (lambda: rm.reach_map(ARM, TOOL_DOWN, [[0, 0]], STARTS), "points"),
    (lambda: rm.reach_map(ARM, TOOL_DOWN, [[0, 0, np.nan]], STARTS), "points"),
    (lambda: rm.reach_map(ARM, TOOL_DOWN, [[0, 0, 0]], STARTS[:, :6]), "starts"),
    (lambda: rm.reach_map(ARM, TOOL_DOWN, np.zeros((0, 3)), STARTS), "points"),
    (lambda: rm.box_grid([0, 0, 0], [1, 1, 1], 0.0), "step"),
    (lambda: rm.box_grid([0, 0, 0], [1, -1, 1], 0.5), "upper"),
    (lambda: rm.box_grid([0, 0], [1, 1, 1], 0.5), "lower"),
])
def test_bad_input_names_the_parameter(call, name):
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        call()


def test_the_picture_draws_every_status_in_its_colour(small_map):
    from ikteach.pictures import scene
    from ikteach.pictures import workspace_maps as ws

    p = ws.reach_scene(ARM, small_map.theta[0], small_map, step=0.15)
    assert "3 converged (green), 3 max_iter (red)" in p._ikteach_alt
    image = scene.render(p).reshape(-1, 3).astype(int)
    p.close()
    green = np.array([int(ws.STATUS_COLORS["converged"][k:k + 2], 16) for k in (1, 3, 5)])
    assert (np.abs(image - green).max(axis=1) < 40).any()
