"""The solver's specialised arithmetic equals the general path it replaces."""
import numpy as np
import pytest

import ikteach as ik
from ikteach.planar import planar_fk, planar_jacobian, planar_positions
from ikteach.small_solve import solve_small

RNG = np.random.default_rng(11)


@pytest.mark.parametrize("lengths", [[1.0], [1.0, 1.0, 1.0], [0.3, 2.0, 0.7, 1.1, 0.5]])
def test_planar_kinematics_by_cumulative_sums_equal_the_frame_walk(lengths):
    arm = ik.planar_chain(lengths, base=(0.4, -0.2))
    for theta in RNG.normal(scale=2.0, size=(10, len(lengths))):
        np.testing.assert_allclose(planar_positions(arm, theta), ik.joint_positions(arm, theta),
                                   atol=1e-12)
        np.testing.assert_allclose(planar_fk(arm, theta), ik.fk(arm, theta), atol=1e-12)
        np.testing.assert_allclose(planar_jacobian(arm, theta), ik.jacobian(arm, theta),
                                   atol=1e-12)


def test_planar_path_handles_axes_pointing_down_and_offsets_off_the_x_axis():
    arm = ik.planar_chain([1.0, 1.0])
    arm = ik.Chain(arm.axes * np.array([[1.0], [-1.0]]), arm.offsets + [[0.0, 0.3, 0.0]] * 2,
                   arm.base, dim=2)
    theta = np.array([0.4, -1.2])
    np.testing.assert_allclose(planar_positions(arm, theta), ik.joint_positions(arm, theta),
                               atol=1e-12)
    np.testing.assert_allclose(planar_jacobian(arm, theta), ik.jacobian(arm, theta), atol=1e-12)


@pytest.mark.parametrize("m", [1, 2, 3, 4, 6])
def test_solve_small_equals_lu(m):
    for _ in range(10):
        J = RNG.normal(size=(m, 7))
        A = J @ J.T + 0.1 * np.eye(m)
        b = RNG.normal(size=m)
        np.testing.assert_allclose(solve_small(A, b), np.linalg.solve(A, b), rtol=1e-10,
                                   atol=1e-12)


def test_dls_step_equals_the_normal_equations_on_a_planar_arm():
    arm = ik.planar_chain([1.0, 1.0, 1.0])
    J = ik.jacobian(arm, [0.1, 0.2, 0.3])
    e = np.array([0.3, -0.2])
    np.testing.assert_allclose(ik.dls_step(J, e, 0.5), ik.dls_step_normal(J, e, 0.5), atol=1e-12)
