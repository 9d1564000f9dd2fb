import collections

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import ikteach as ik
from ikteach.core.fabrik import fabrik_pass
from strategies import arm_and_angles, planar_arms

ARM = ik.planar_chain([1.0, 1.0, 1.0])
START = np.array([0.1, 0.2, 0.3])
TEN = ik.planar_chain(np.ones(10))


@given(st.floats(-np.pi, np.pi), st.floats(0.1, 3.0), st.floats(-2, 2))
def test_ccd_angle_turns_a_point_onto_the_targets_ray(phi, radius, height):
    w = np.array([0.0, 0.0, 1.0])
    x = np.array([1.0, 0.0, 0.3])
    t = np.array([radius * np.cos(phi), radius * np.sin(phi), height])
    angle = float(ik.core.ccd.ccd_angle(w, np.zeros(3), x, t))
    assert angle == pytest.approx(phi, abs=1e-9) or abs(abs(phi) - np.pi) < 1e-9


@pytest.mark.parametrize("method", ["ccd", "fabrik"])
@pytest.mark.parametrize("arm, target", [(ARM, [2.5, 0.5]), (ARM, [0.3, 1.2]), (ARM, [-1.0, -1.5]),
                                         (TEN, [4.0, -6.0]), (TEN, [-2.0, 1.0])])
def test_converges_on_reachable_targets(method, arm, target):
    theta0 = np.full(arm.n_joints, 0.1)
    # CCD's last digits come slowly: the stall stop is set below its step size here
    res = ik.solve(arm, target, theta0, method=method, tol=1e-4, max_iter=2000, stall_tol=1e-9)
    assert res.status == "converged", res
    assert np.linalg.norm(np.asarray(ik.fk(arm, res.theta)) - target) < 1e-4


@pytest.mark.parametrize("method", ["ccd", "fabrik"])
@pytest.mark.parametrize("target", [[3.5, 1.0], [0.0, -4.0], [-5.0, 5.0]])
def test_stalls_out_of_reach_stretched_toward_the_target(method, target):
    res = ik.solve(ARM, target, START, method=method, max_iter=3000)
    assert res.status == "stalled", res
    assert np.all(np.isfinite(res.theta))
    assert res.error == pytest.approx(np.linalg.norm(target) - 3.0, abs=1e-3)
    tip = np.asarray(ik.fk(ARM, res.theta))
    np.testing.assert_allclose(tip / np.linalg.norm(tip), np.asarray(target) / np.linalg.norm(target),
                               atol=1e-3)


@given(arm_and_angles(planar_arms(min_joints=2)), st.floats(-4, 4), st.floats(-4, 4))
def test_fabrik_pass_keeps_link_lengths_and_base(case, tx, ty):
    arm, theta = case
    points = np.asarray(ik.core.kinematics.joint_frames(arm, theta)[0])
    lengths = np.linalg.norm(arm.offsets, axis=1)
    new = np.asarray(fabrik_pass(points, lengths, np.array([tx, ty, 0.0])))
    np.testing.assert_allclose(np.linalg.norm(np.diff(new, axis=0), axis=1), lengths, atol=1e-9)
    np.testing.assert_allclose(new[0], points[0], atol=1e-12)


@given(arm_and_angles(planar_arms()), st.floats(-3, 3), st.floats(-3, 3))
def test_one_ccd_sweep_never_moves_the_tip_away(case, tx, ty):
    arm, theta = case
    target = np.array([tx, ty])
    before = np.linalg.norm(np.asarray(ik.fk(arm, theta)) - target)
    after = np.linalg.norm(np.asarray(ik.fk(arm, ik.core.ccd.ccd_sweep(arm, target, theta))) - target)
    assert after <= before + 1e-9


def test_batch_runs_ccd_and_fabrik():
    rng = np.random.default_rng(0)
    targets = np.stack([np.asarray(ik.fk(TEN, rng.uniform(-1, 1, 10))) for _ in range(5)])
    for method in ("ccd", "fabrik"):
        batch = ik.solve_batch(TEN, targets, np.full(10, 0.1), method=method, tol=1e-3, max_iter=2000)
        assert batch.counts()["converged"] == 5, method


def test_ccd_and_fabrik_refuse_trees():
    Y = ik.core.buss_trees.y_tree()
    for method in ("ccd", "fabrik"):
        with pytest.raises(ValueError, match="method"):
            ik.solve(Y, np.zeros((2, 3)), np.zeros(7), method=method)


def test_fabrik_pass_keeps_link_lengths_when_points_coincide():
    # straight arm, target on the base: the forward pass lands a joint on the next one
    arm = ik.planar_chain([1.0, 1.0, 1.0])
    points = np.asarray(ik.core.kinematics.joint_frames(arm, np.zeros(3))[0])
    new = np.asarray(fabrik_pass(points, np.ones(3), np.zeros(3)))
    np.testing.assert_allclose(np.linalg.norm(np.diff(new, axis=0), axis=1), [1.0, 1.0, 1.0])
    np.testing.assert_allclose(new[0], points[0])


def test_fabrik_never_settles_on_the_ur5_where_ccd_converges():
    """fabrik.py's note, measured: the UR5's hinges cannot follow FABRIK's free points."""
    U = ik.core.robots.ur5()
    rng = np.random.default_rng(1)
    goals = rng.uniform(-np.pi, np.pi, (20, 6))
    targets = np.stack([np.asarray(ik.fk(U, g)) for g in goals])
    starts = goals + rng.uniform(-0.5, 0.5, goals.shape)
    fabrik = ik.solve_batch(U, targets, starts, method="fabrik")
    assert collections.Counter(fabrik.status) == {"max_iter": 20}
    relative = fabrik.error / float(ik.reach(U))
    assert 0.06 < relative.min() and relative.max() < 0.4
    assert set(ik.solve_batch(U, targets, starts, method="ccd").status) == {"converged"}
