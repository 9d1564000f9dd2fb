"""Pose targets: fk_pose, the rotation log near 0 and pi, pose solves on the built-in arms."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ikteach as ik

AXIS = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
ANGLES = [0.0, 1e-12, 1e-7, 1e-3, 0.3, 1.5, 2.5, 2.9, np.pi - 1e-3, np.pi - 1e-7, np.pi - 1e-12]


@pytest.mark.parametrize("angle", ANGLES)
def test_rotation_log_is_exact_from_0_to_pi(angle):
    w = np.asarray(ik.core.pose.rotation_log(ik.core.kinematics.rotation_about(AXIS, angle)))
    assert np.all(np.isfinite(w))
    np.testing.assert_allclose(w, angle * AXIS, atol=1e-12)


def test_rotation_log_at_pi_gives_the_axis_up_to_sign():
    for axis in [AXIS, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])]:
        w = np.asarray(ik.core.pose.rotation_log(ik.core.kinematics.rotation_about(axis, np.pi)))
        assert np.all(np.isfinite(w))
        assert min(np.abs(w - np.pi * axis).max(), np.abs(w + np.pi * axis).max()) < 1e-12


@pytest.mark.parametrize("angle", [0.0, 1e-9, 1e-4, 1.0, 3.0, np.pi - 1e-6])
def test_rotation_log_gradient_is_finite_and_correct(angle):
    """log(exp(w)) = w for |w| < pi, so its Jacobian is the identity, also at 0 and near pi."""
    J = jax.jacfwd(lambda w: ik.core.pose.rotation_log(ik.core.pose.rotation_exp(w)))(jnp.asarray(angle * AXIS))
    np.testing.assert_allclose(np.asarray(J), np.eye(3), atol=1e-6)


def test_rotation_log_gradient_matches_finite_differences_near_pi():
    R0 = np.asarray(ik.core.kinematics.rotation_about(AXIS, np.pi - 1e-3))
    f = lambda t: ik.core.pose.rotation_log(ik.core.kinematics.rotation_about(np.array([0.0, 1.0, 0.0]), t) @ R0)
    g = np.asarray(jax.jacfwd(f)(0.1))
    h = 1e-6
    fd = (np.asarray(f(0.1 + h)) - np.asarray(f(0.1 - h))) / (2 * h)
    np.testing.assert_allclose(g, fd, atol=1e-6)


def test_rotation_exp_inverts_log(rng=np.random.default_rng(3)):
    for _ in range(20):
        w = rng.normal(size=3)
        w *= rng.uniform(0, np.pi - 1e-3) / np.linalg.norm(w)
        np.testing.assert_allclose(np.asarray(ik.core.pose.rotation_log(ik.core.pose.rotation_exp(w))), w, atol=1e-10)


def test_fk_pose_matches_fk_and_is_a_rigid_transform():
    arm = ik.core.robots.ur5()
    theta = np.array([0.2, -1.0, 0.7, 0.3, -0.4, 1.1])
    T = np.asarray(ik.fk_pose(arm, theta))
    np.testing.assert_allclose(T[:3, 3], np.asarray(ik.fk(arm, theta)), atol=1e-14)
    np.testing.assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(T[3], [0, 0, 0, 1])


def test_orientation_rows_of_the_6xn_jacobian_drive_the_log_error():
    """d/dtheta log(R_t R(theta)^T) = -J_angular at R = R_t (first-order check); the task
    weighs the orientation rows by the arm's reach L, in e and in J alike."""
    arm = ik.core.robots.iiwa14()
    theta = np.array([0.1, 0.5, -0.3, -1.0, 0.2, 0.7, -0.4])
    T = np.asarray(ik.fk_pose(arm, theta))
    task = ik.core.pose.PoseTask()
    J_err = jax.jacfwd(lambda q: task.error(arm, jnp.asarray(T), q))(jnp.asarray(theta))
    J = np.asarray(ik.jacobian(arm, theta, full=True))
    weighed = np.vstack([J[:3], float(ik.reach(arm)) * J[3:]])
    np.testing.assert_allclose(np.asarray(J_err), -weighed, atol=1e-10)
    np.testing.assert_allclose(np.asarray(task.jacobian(arm, jnp.asarray(theta))), weighed, atol=1e-12)


@pytest.mark.parametrize("arm_fn", [ik.core.robots.ur5, ik.core.robots.iiwa14])
@pytest.mark.parametrize("method", ["dls", "pinv"])
def test_pose_targets_from_fk_of_random_angles_converge(arm_fn, method):
    arm = arm_fn()
    rng = np.random.default_rng(7)
    for _ in range(4):
        truth = rng.uniform(-2.0, 2.0, arm.n_joints)
        target = np.asarray(ik.fk_pose(arm, truth))
        start = truth + rng.normal(0, 0.25, arm.n_joints)
        res = ik.solve(arm, target, start, method=method, tol=1e-6, max_iter=300, damping=0.01)
        assert res.status == "converged", res
        e_p, e_o = ik.pose_errors(arm, res.theta, target)
        assert e_p < 1e-6 and e_o < 1e-6


def test_solve_batch_takes_pose_targets():
    arm = ik.core.robots.iiwa14()
    rng = np.random.default_rng(11)
    truths = rng.uniform(-1.5, 1.5, (8, arm.n_joints))
    targets = np.stack([np.asarray(ik.fk_pose(arm, q)) for q in truths])
    res = ik.solve_batch(arm, targets, truths + rng.normal(0, 0.2, truths.shape), tol=1e-6,
                         damping=0.01, max_iter=300)
    assert res.counts()["converged"] == 8
    for q, T in zip(res.theta, targets):
        assert max(ik.pose_errors(arm, q, T)) < 1e-6


def test_weights_trade_position_against_orientation():
    """An unreachable orientation at a reachable point: weighting orientation by ~0 gives the
    position exactly; weighting position by ~0 gives the orientation exactly."""
    arm = ik.planar_chain([1.0, 1.0])  # planar, so use a spatial arm built from the same idea
    arm = ik.serial_chain([[0, 0, 1], [0, 0, 1]], [[1, 0, 0], [1, 0, 0]])
    target = np.asarray(ik.make_pose(ik.core.kinematics.rotation_about(np.array([1.0, 0, 0]), 0.5), [1.2, 0.8, 0.0]))
    theta0 = np.array([0.3, 0.5])
    pos = ik.solve(arm, target, theta0, weights=(1.0, 1e-4), tol=1e-12, max_iter=300)
    ori = ik.solve(arm, target, theta0, weights=(1e-4, 1.0), tol=1e-12, max_iter=300)
    p_pos, o_pos = ik.pose_errors(arm, pos.theta, target)
    p_ori, o_ori = ik.pose_errors(arm, ori.theta, target)
    assert p_pos < 1e-3 < p_ori
    assert o_pos > 0.5 - 1e-6 and o_pos > o_ori


def test_pose_input_errors_name_the_parameter():
    arm = ik.core.robots.ur5()
    with pytest.raises(ValueError, match="weights"):
        ik.solve(ik.planar_chain([1, 1]), [1.0, 0.5], [0.1, 0.1], weights=(1, 1))
    with pytest.raises(ValueError, match="weights"):
        ik.solve(arm, np.eye(4), np.zeros(6), weights=(1, -1))
    with pytest.raises(ValueError, match="weights"):
        ik.solve(arm, np.eye(4), np.zeros(6), weights=3)
    with pytest.raises(ValueError, match=r"target.*\(4, 4\)"):
        ik.solve(arm, np.eye(3), np.zeros(6))
    with pytest.raises(ValueError, match="target"):
        ik.solve(ik.planar_chain([1, 1]), np.eye(4), [0.1, 0.1])
