import numpy as np
import pytest

import ikteach as ik

ARM = ik.planar_chain([1.0, 1.0, 1.0])


@pytest.mark.parametrize("lengths, message", [
    ([], "lengths: expected at least one"),
    ([1.0, -1.0], "lengths: expected positive"),
    ([1.0, 0.0], "lengths: expected positive"),
    ([1.0, np.nan], "lengths: expected finite"),
    ([[1.0, 2.0]], "lengths: expected 1 dimension"),
    (["a"], "lengths: expected an array of numbers"),
    (None, "lengths: expected an array of numbers"),
])
def test_bad_link_lengths(lengths, message):
    with pytest.raises(ValueError, match=message):
        ik.planar_chain(lengths)


@pytest.mark.parametrize("axes, offsets, message", [
    ([[0, 0, 1]], [[1, 0]], r"offsets: expected shape \(1, 3\)"),
    ([[0, 0, 0]], [[1, 0, 0]], "axes: expected non-zero"),
    ([[0, 0]], [[1, 0, 0]], r"axes: expected shape \(any, 3\)"),
    ([[0, 0, np.inf]], [[1, 0, 0]], "axes: expected finite"),
])
def test_bad_serial_chain(axes, offsets, message):
    with pytest.raises(ValueError, match=message):
        ik.serial_chain(axes, offsets)


@pytest.mark.parametrize("kwargs, message", [
    (dict(target=[1.0]), r"target: expected shape \(2,\)"),
    (dict(target=[1.0, np.nan]), "target: expected finite"),
    (dict(theta0=[0.0, 0.0]), r"theta0: expected shape \(3\)"),
    (dict(theta0=[0.0, np.inf, 0.0]), "theta0: expected finite"),
    (dict(method="newton"), "method: expected one of"),
    (dict(method=42), "method: expected one of"),
    (dict(method=lambda J: J), "method: a step function must accept two arguments"),
    (dict(damping=-0.1), "damping: expected a number >= 0"),
    (dict(damping=np.nan), "damping: expected a finite number"),
    (dict(tol=0.0), "tol: expected a number > 0"),
    (dict(max_iter=0), "max_iter: expected an integer >= 1"),
    (dict(max_iter=10.5), "max_iter: expected an integer"),
    (dict(clamp=0.0), "clamp: expected a number > 0"),
    (dict(max_step=-1.0), "max_step: expected a number > 0"),
    (dict(stall_tol=-1.0), "stall_tol: expected a number >= 0"),
    (dict(arm="arm"), "arm: expected a chain"),
    (dict(target=np.eye(4)), r"target: expected shape \(2,\)"),
])
def test_bad_solver_input(kwargs, message):
    args = dict(arm=ARM, target=[1.0, 1.0], theta0=[0.0, 0.0, 0.0]) | kwargs
    with pytest.raises(ValueError, match=message):
        ik.solve(**args)


def test_step_function_with_the_wrong_output_shape():
    with pytest.raises(ValueError, match=r"method: the step function returned shape \(2,\)"):
        ik.solve(ARM, [1.0, 1.0], np.zeros(3), method=lambda J, e: e)


@pytest.mark.parametrize("targets, theta0, message", [
    (np.ones(2), np.zeros(3), "targets: expected one target per row"),
    (np.ones((4, 3)), np.zeros(3), r"targets: expected shape \(2,\)"),
    (np.ones((4, 2)), np.zeros((3, 3)), r"theta0: expected shape \(4, 3\)"),
])
def test_bad_batch_input(targets, theta0, message):
    with pytest.raises(ValueError, match=message):
        ik.solve_batch(ARM, targets, theta0)


@pytest.mark.parametrize("fn", [ik.fk, ik.joint_positions, ik.jacobian, ik.jacobian_autodiff])
def test_kinematics_name_a_wrong_number_of_angles(fn):
    with pytest.raises(ValueError, match=r"theta: expected shape \(3,\)"):
        fn(ARM, np.zeros(2))
