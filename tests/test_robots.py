"""Built-in arms: the product-of-exponentials chains reproduce their published DH tables."""
import numpy as np
import pytest

import ikteach as ik
from ikteach.core import robots


def test_ur5_home_position_matches_the_published_dh_numbers():
    # At theta = 0 the UR5 lies stretched: x = a2 + a3, y = -(d4 + d6), z = d1 - d5.
    np.testing.assert_allclose(np.asarray(ik.fk(ik.core.robots.ur5(), np.zeros(6))),
                               [-0.425 - 0.39225, -(0.10915 + 0.0823), 0.089159 - 0.09465], atol=1e-12)


def test_iiwa14_home_is_straight_up():
    np.testing.assert_allclose(np.asarray(ik.fk(ik.core.robots.iiwa14(), np.zeros(7))),
                               [0.0, 0.0, 0.36 + 0.42 + 0.4 + 0.126], atol=1e-12)
    assert ik.core.robots.iiwa14().n_joints == 7 and ik.core.robots.ur5().n_joints == 6


@pytest.mark.parametrize("name", sorted(robots.ROBOTS))
def test_chain_equals_the_dh_product_at_random_angles(name):
    make, dh = robots.ROBOTS[name]
    arm = make()
    M = robots.dh_home_rotation(**dh)
    rng = np.random.default_rng(5)
    for _ in range(10):
        theta = rng.uniform(-np.pi, np.pi, arm.n_joints)
        T_dh = robots.dh_fk(dh["d"], dh["a"], dh["alpha"], theta)
        T = np.asarray(ik.fk_pose(arm, theta))
        np.testing.assert_allclose(T[:3, 3], T_dh[:3, 3], atol=1e-12)
        np.testing.assert_allclose(T[:3, :3] @ M, T_dh[:3, :3], atol=1e-12)


def test_dh_transform_is_the_standard_convention():
    # Rot_z(theta) Trans_z(d) Trans_x(a) Rot_x(alpha) moves the origin to (a cos t, a sin t, d).
    A = robots.dh_transform(0.3, 0.5, 0.7, 0.4)
    np.testing.assert_allclose(A[:3, 3], [0.5 * np.cos(0.4), 0.5 * np.sin(0.4), 0.3])
    np.testing.assert_allclose(A[:3, 2], [np.sin(0.4) * np.sin(0.7), -np.cos(0.4) * np.sin(0.7), np.cos(0.7)])
