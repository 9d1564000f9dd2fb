import numpy as np
from hypothesis import given

import ikteach as ik
from strategies import arm_and_angles, planar_arms, spatial_arms


@given(arm_and_angles(planar_arms()))
def test_three_jacobians_agree_on_planar_arms(case):
    arm, theta = case
    J = ik.jacobian(arm, theta)
    assert J.shape == (2, arm.n_joints)
    np.testing.assert_allclose(J, ik.jacobian_autodiff(arm, theta), atol=1e-10)
    np.testing.assert_allclose(J, ik.jacobian_fd(arm, theta), atol=1e-6)


@given(arm_and_angles(spatial_arms()))
def test_three_jacobians_agree_on_spatial_chains(case):
    arm, theta = case
    J = ik.jacobian(arm, theta)
    assert J.shape == (3, arm.n_joints)
    np.testing.assert_allclose(J, ik.jacobian_autodiff(arm, theta), atol=1e-10)
    np.testing.assert_allclose(J, ik.jacobian_fd(arm, theta), atol=1e-6)


def test_column_is_axis_cross_lever_arm():
    arm = ik.planar_chain([1.0, 1.0])
    # straight arm along x: joint 0 at the origin, effector at (2, 0)
    J = ik.jacobian(arm, [0.0, 0.0])
    np.testing.assert_allclose(J, [[0, 0], [2, 1]], atol=1e-12)


def test_full_jacobian_appends_angular_rows():
    planar = ik.planar_chain([1.0, 1.0, 1.0])
    Jp = ik.jacobian(planar, [0.1, 0.2, 0.3], full=True)
    assert Jp.shape == (3, 3)
    np.testing.assert_allclose(Jp[2], [1, 1, 1])
    spatial = ik.serial_chain([[0, 0, 1], [0, 1, 0]], [[0, 0, 1], [1, 0, 0]])
    Js = ik.jacobian(spatial, [0.4, 0.2], full=True)
    assert Js.shape == (6, 2)
    np.testing.assert_allclose(Js[3:, 0], [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(Js[3:], axis=0), [1, 1])
