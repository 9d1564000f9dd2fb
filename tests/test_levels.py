"""Priority levels in ik.solve: the first level wins a conflict; the rest pose uses what is left."""
import numpy as np
import pytest

import ikteach as ik

# A planar 4-joint arm as a tree: effector 0 at the elbow (on joint 1), effector 1 at the tip.
ARM = ik.tree(positions=[[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], axes=[[0, 0, 1]] * 4,
              parents=[-1, 0, 1, 2], effectors=[[2, 0, 0], [4, 0, 0]], effector_parents=[1, 3])
CONFLICT = np.array([[1.2, 1.4, 0.0], [0.0, 3.5, 0.0]])  # each reachable, not both at once
START = np.full(4, 0.1)


def distances(theta, targets):
    return np.linalg.norm(np.asarray(ik.core.tree.tree_fk(ARM, theta)) - targets, axis=1)


@pytest.mark.parametrize("levels, winner", [((0, 1), 0), ((1, 0), 1)])
def test_the_first_level_wins_a_conflict(levels, winner):
    res = ik.solve(ARM, CONFLICT, START, levels=levels)
    d = distances(res.theta, CONFLICT)
    assert res.status == "stalled"           # not both met: the step dies out
    assert d[winner] < 1e-3                  # the first level is met
    assert d[1 - winner] > 0.3               # the other does what it can


def test_without_levels_both_give_way():
    d = distances(ik.solve(ARM, CONFLICT, START).theta, CONFLICT)
    assert np.all(d > 1e-2)


def test_rest_pose_drifts_to_the_solution_nearest_the_rest_pose():
    """One effector, four joints: many solutions. Tracking a fixed target, the rest level
    pulls theta towards theta_rest in the null space while the target stays met."""
    arm = ik.tree(ARM.positions, ARM.axes, ARM.parents, ARM.effectors[1:], ARM.effector_parents[1:])
    targets, rest = np.tile([[2.0, 2.0, 0.0]], (300, 1, 1)), np.array([0.3, 0.3, 0.3, 0.3])
    start = np.array([1.2, -0.6, 1.2, -0.6])
    plain = ik.track(arm, targets, start)
    rested, rested_elsewhere = (ik.track(arm, targets, q, rest_pose=rest, rest_gain=0.2)
                                for q in (start, START))
    assert plain.error[-1] < 1e-6 and rested.error[-1] < 1e-6
    far, near = (np.linalg.norm(r.theta[-1] - rest) for r in (plain, rested))
    assert near < 0.5 * far
    # from another start, the same nearest-to-rest solution
    np.testing.assert_allclose(rested_elsewhere.theta[-1], rested.theta[-1], atol=1e-6)
    # the rest level's own step has died out: theta sits at the nearest-to-rest solution
    assert np.abs(rested.theta[-1] - rested.theta[-2]).sum() < 1e-8


def test_batch_gives_the_same_iterates_as_solve():
    one = ik.solve(ARM, CONFLICT, START, levels=(1, 0))
    batch = ik.solve_batch(ARM, CONFLICT[None], START, levels=(1, 0))
    np.testing.assert_array_equal(batch.theta[0], one.theta)
    assert batch.iterations[0] == one.iterations


def test_track_with_levels_keeps_the_first_level():
    path = np.linspace(CONFLICT[1] - [0, 1, 0], CONFLICT[1], 30)
    targets = np.stack([np.broadcast_to(CONFLICT[0], path.shape), path], axis=1)
    res = ik.track(ARM, targets, START, levels=(0, 1), damping=0.5)
    elbow = [distances(q, t)[0] for q, t in zip(res.theta[1:], targets)]
    assert elbow[-1] < 1e-3


@pytest.mark.parametrize("kwargs, match", [
    (dict(levels=(0,)), "levels: expected 2"),
    (dict(levels=(0, -1)), "levels: expected 2"),
    (dict(levels="ab"), "levels: expected one integer"),
    (dict(levels=(0, 1), method="ccd"), "method: levels= and rest_pose="),
    (dict(rest_pose=np.zeros(3)), "rest_pose: expected shape"),
    (dict(rest_pose=np.zeros(4), rest_gain=0), "rest_gain"),
])
def test_bad_levels_name_the_parameter(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ik.solve(ARM, CONFLICT, START, **kwargs)
