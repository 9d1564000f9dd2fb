"""One options object for ik.solve, ik.solve_batch and ik.track, checked when it is made;
keywords are the same fields; a method owns its own parameters."""
import numpy as np
import pytest

import ikteach as ik

ARM = ik.planar_chain([1.0, 1.0, 1.0])
START = np.array([0.1, 0.2, 0.3])


@pytest.mark.parametrize("fields, message", [
    (dict(tol=-1.0), "tol: expected a number > 0"),
    (dict(max_iter=0), "max_iter: expected an integer >= 1"),
    (dict(clamp=0.0), "clamp: expected a number > 0"),
    (dict(stop_rule="fast"), "stop_rule: expected one of"),
    (dict(limit_mode="clip"), "limit_mode: expected one of"),
    (dict(limit_mode="clamp"), "limit_mode: 'clamp' says how to keep joint limits"),
    (dict(rest_gain=0.5), "rest_gain: the gain of the rest-pose level"),
    (dict(joint_limits=(1.0, -1.0)), "joint_limits: expected lower <= upper"),
])
def test_options_are_checked_when_made(fields, message):
    with pytest.raises(ValueError, match=message):
        ik.Options(**fields)


@pytest.mark.parametrize("make, message", [
    (lambda: ik.DLS(damping=-1.0), "damping: expected a number >= 0"),
    (lambda: ik.Pinv(rcond="x"), "rcond: expected a real number"),
    (lambda: ik.SDLS(gamma_max=0.0), "gamma_max: expected a number > 0"),
])
def test_methods_check_their_own_parameters(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_an_options_object_and_keywords_give_the_same_solve():
    options = ik.Options(tol=1e-5, max_iter=50, clamp=0.5, max_step=0.3)
    target = np.array([2.0, 1.0])
    a = ik.solve(ARM, target, START, method=ik.DLS(damping=0.2), options=options)
    b = ik.solve(ARM, target, START, method="dls", damping=0.2, tol=1e-5, max_iter=50, clamp=0.5,
                 max_step=0.3)
    assert (a.status, a.iterations) == (b.status, b.iterations)
    np.testing.assert_array_equal(a.theta, b.theta)
    rows = ik.solve_batch(ARM, np.stack([target] * 10), START, method=ik.DLS(0.2), options=options)
    assert list(rows.status) == [a.status] * 10 and np.all(rows.iterations == a.iterations)
    # keywords beside options win
    c = ik.solve(ARM, target, START, method=ik.DLS(0.2), options=options, max_iter=3)
    assert c.iterations == 3


def test_a_parameter_beside_a_method_object_is_refused():
    with pytest.raises(ValueError, match="damping: give it to the method object"):
        ik.solve(ARM, [2.0, 1.0], START, method=ik.DLS(0.2), damping=0.3)


def test_tracking_refuses_stop_rules_it_never_uses():
    path = np.stack([np.linspace(1.0, 2.0, 5), np.ones(5)], axis=1)
    with pytest.raises(ValueError, match="tol: ik.track takes one step per time step"):
        ik.track(ARM, path, START, tol=1e-3)
    assert ik.track(ARM, path, START, options=ik.Options(clamp=0.2)).theta.shape == (6, 3)


def test_not_an_options_object_is_refused():
    with pytest.raises(ValueError, match="options: expected ik.Options"):
        ik.solve(ARM, [2.0, 1.0], START, options={"tol": 1e-3})


def test_a_fixed_alpha_is_a_parameter_of_the_jacobian_transpose():
    """ik.JT(alpha=a) is the step a * J^T e (lecture 02's fixed step), as the step function."""
    target = np.array([2.0, 1.0])
    by_method = ik.solve(ARM, target, START, method=ik.JT(alpha=0.1), max_iter=300)
    by_function = ik.solve(ARM, target, START, method=lambda J, e: 0.1 * (J.T @ e), max_iter=300)
    assert (by_method.status, by_method.iterations) == (by_function.status, by_function.iterations)
    np.testing.assert_allclose(by_method.theta, by_function.theta, atol=1e-12)
    with pytest.raises(ValueError, match="alpha: expected a number > 0"):
        ik.JT(alpha=-1.0)
