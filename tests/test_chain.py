import numpy as np
import pytest

import ikteach as ik


def test_planar_forward_kinematics_matches_the_cosine_sum():
    lengths = np.array([1.0, 0.7, 0.4])
    theta = np.array([0.3, -1.1, 0.8])
    phi = np.cumsum(theta)
    expected = np.array([np.sum(lengths * np.cos(phi)), np.sum(lengths * np.sin(phi))])
    arm = ik.planar_chain(lengths)
    np.testing.assert_allclose(ik.fk(arm, theta), expected, atol=1e-12)


def test_joint_positions_start_at_base_and_end_at_the_effector():
    arm = ik.planar_chain([1.0, 2.0], base=(0.5, -0.5))
    pos = np.asarray(ik.joint_positions(arm, [np.pi / 2, 0.0]))
    np.testing.assert_allclose(pos, [[0.5, -0.5], [0.5, 0.5], [0.5, 2.5]], atol=1e-12)
    np.testing.assert_allclose(pos[-1], ik.fk(arm, [np.pi / 2, 0.0]), atol=1e-12)


def test_results_are_float64():
    arm = ik.planar_chain([1.0, 1.0])
    assert ik.fk(arm, [0.1, 0.2]).dtype == np.float64
    assert ik.jacobian(arm, [0.1, 0.2]).dtype == np.float64


def test_spatial_chain_turns_about_its_axes():
    arm = ik.serial_chain(axes=[[0, 0, 1], [0, 1, 0]], offsets=[[0, 0, 1], [1, 0, 0]])
    np.testing.assert_allclose(ik.fk(arm, [0.0, 0.0]), [1, 0, 1], atol=1e-12)
    # turning the base by 90 degrees swings the arm to +y
    np.testing.assert_allclose(ik.fk(arm, [np.pi / 2, 0.0]), [0, 1, 1], atol=1e-12)
    # turning the elbow (axis y) by -90 degrees lifts the last link to +z
    np.testing.assert_allclose(ik.fk(arm, [0.0, -np.pi / 2]), [0, 0, 2], atol=1e-12)


def test_axes_are_normalised_and_reach_is_the_total_length():
    arm = ik.serial_chain(axes=[[0, 0, 2.0]], offsets=[[3.0, 4.0, 0.0]])
    np.testing.assert_allclose(arm.axes, [[0, 0, 1]])
    assert ik.reach(arm) == pytest.approx(5.0)
    assert ik.reach(ik.planar_chain([1, 2, 3])) == pytest.approx(6.0)
