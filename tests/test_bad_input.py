import jax
import numpy as np
import pytest

import ikteach as ik

ARM = ik.planar_chain([1.0, 1.0, 1.0])


@pytest.mark.parametrize("lengths, message", [
    ([], "lengths: expected at least one"),
    ([1.0, -1.0], "lengths: expected link lengths >= 0"),
    ([0.0, 0.0], "lengths: expected a positive total"),
    ([1.0, 1e160], r"lengths: expected numbers of magnitude at most 1e\+40"),
    ([1.0, 1e-170], r"lengths: expected link lengths of 0 or within \[1e-40, 1e\+40\]"),
    ([6e39, 6e39], r"lengths: expected a total link length of at most 1e\+40"),
    (["1", "2"], "lengths: expected an array of numbers"),
    ([True, True], "lengths: expected an array of numbers, got booleans"),
    ([1.0, 1j], "lengths: expected real numbers, got complex"),
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
    ([[0, 0, 1]], [[0, 0, 0]], "offsets: expected a positive total"),
    ([[0, 0, 1]], [[1e-170, 0, 0]], "offsets: expected link lengths of 0 or within"),
    ([[0, 0, 1]], [["1", 0, 0]], "offsets: expected an array of numbers"),
])
def test_bad_serial_chain(axes, offsets, message):
    with pytest.raises(ValueError, match=message):
        ik.serial_chain(axes, offsets)


@pytest.mark.parametrize("kwargs, message", [
    (dict(target=[1.0]), r"target: expected shape \(2,\)"),
    (dict(target=[1.0, np.nan]), "target: expected finite"),
    (dict(theta0=[0.0, 0.0]), r"theta0: expected shape \(3,\)"),
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
    (dict(target=["1", "1"]), "target: expected an array of numbers"),
    (dict(target=[1e300, 0.0]), "target: expected numbers of magnitude at most"),
    (dict(theta0=[True, False, True]), "theta0: expected an array of numbers, got booleans"),
    (dict(tol=True), "tol: expected a real number, got True"),
    (dict(tol="0.1"), "tol: expected a real number"),
    (dict(tol=1e-3 + 0j), "tol: expected real numbers, got complex"),
    (dict(tol=5e-324), r"tol: expected a number >= 1e-100"),
    (dict(tol=1e200), r"tol: expected a number of magnitude at most 1e\+40"),
    (dict(damping=np.bool_(True)), "damping: expected a real number"),
    (dict(damping="0.5"), "damping: expected a real number"),
    (dict(clamp=[1.0]), "clamp: expected a single number"),
    (dict(stall_tol=False), "stall_tol: expected a real number"),
    (dict(max_iter=True), "max_iter: expected an integer"),
    (dict(max_iter="10"), "max_iter: expected an integer"),
    (dict(levels=(0.7,)), "levels: expected one integer priority"),
    (dict(levels=(True,)), "levels: expected one integer priority"),
    (dict(rest_gain=0.2), "rest_gain: .* needs rest_pose"),
    (dict(limit_mode="clamp"), "limit_mode: 'clamp' .* needs joint_limits"),
    (dict(joint_limits=(["-1"] * 3, 1.0)), "joint_limits: expected lower as a number"),
    (dict(rest_pose=np.zeros(3), rest_gain=True), "rest_gain: expected a real number"),
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


SPATIAL = ik.serial_chain([[0, 0, 1], [0, 1, 0], [1, 0, 0], [0, 0, 1]],
                          [[0, 0, 0.5], [0.5, 0, 0], [0.5, 0, 0], [0.2, 0, 0]])


def rigid(R=np.eye(3), p=(0.6, 0.2, 0.3)):
    return np.asarray(ik.make_pose(R, p))


@pytest.mark.parametrize("target, message", [
    (rigid(2.0 * np.eye(3)), r"target: expected a rotation .*scaled or sheared"),
    (rigid(np.diag([1.0, 1.0, -1.0])), "target: expected a rotation .*got a reflection"),
    (rigid() + np.array([[0, 0, 0, 0]] * 3 + [[0.5, 0, 0, 0]]), r"target: expected a rigid transform with bottom row \[0, 0, 0, 1\]"),
    (rigid(np.eye(3) + 1e-5), "target: expected a rotation"),
])
def test_a_pose_target_must_be_a_rigid_transform(target, message):
    with pytest.raises(ValueError, match=message):
        ik.solve(SPATIAL, target, np.zeros(4), method="dls")
    stack = np.stack([rigid()] * 3 + [target])
    with pytest.raises(ValueError, match=message.replace("target:", r"targets\[3\]:")):
        ik.solve_batch(SPATIAL, stack, np.zeros(4))
    with pytest.raises(ValueError, match=message.replace("target:", r"targets\[3\]:")):
        ik.track(SPATIAL, stack, np.zeros(4))


def test_a_nearly_rigid_pose_is_accepted():
    """Within RIGID_TOL (1e-6): rounding noise is no reason to refuse a pose."""
    assert np.isfinite(ik.solve(SPATIAL, rigid(np.eye(3) + 1e-8), np.zeros(4)).error)


@pytest.mark.parametrize("method", ["ccd", "fabrik"])
def test_ccd_and_fabrik_name_themselves_for_a_pose_target(method):
    with pytest.raises(ValueError, match=f"method: '{method}' works on chains with position "
                                         f"targets .*got a 4x4 pose target"):
        ik.solve(SPATIAL, rigid(), np.zeros(4), method=method)
    with pytest.raises(ValueError, match=f"method: '{method}'"):
        ik.solve_batch(SPATIAL, np.stack([rigid()] * 9), np.zeros(4), method=method)
    with pytest.raises(ValueError, match=f"method: '{method}'"):
        ik.track(SPATIAL, np.stack([rigid()] * 2), np.zeros(4), method=method)


def test_empty_batches_and_tracks_are_refused():
    with pytest.raises(ValueError, match="targets: expected at least one target, got none"):
        ik.solve_batch(ARM, np.zeros((0, 2)), np.zeros(3))
    with pytest.raises(ValueError, match="targets: expected at least one time step, got none"):
        ik.track(ARM, np.zeros((0, 2)), np.zeros(3))


@pytest.mark.parametrize("step, message", [
    (lambda J, e: None, "method: the step function must return an array .*got None"),
    (lambda J, e: "step", "method: the step function must return an array .*got 'step'"),
    (lambda J, e: J.T @ e * 1j, "method: the step function must return .*got complex"),
    (lambda J, e: J.T @ e > 0, "method: the step function must return .*got dtype bool"),
])
def test_a_step_function_must_return_real_numbers(step, message):
    with pytest.raises(ValueError, match=message):
        ik.solve(ARM, [1.0, 1.0], np.zeros(3), method=step)
    with pytest.raises(ValueError, match=message):
        ik.solve_batch(ARM, np.ones((9, 2)), np.zeros(3), method=step)


def test_a_numpy_step_function_is_refused_by_solve_batch_only():
    def numpy_jt(J, e):
        return np.asarray(J).T @ np.asarray(e) * 0.1

    assert ik.solve(ARM, [1.0, 1.0], np.zeros(3), method=numpy_jt, max_iter=5).iterations == 5
    with pytest.raises(ValueError, match="method: ik.solve_batch compiles the step function .*"
                                         "must use jax.numpy"):
        ik.solve_batch(ARM, np.ones((9, 2)), np.zeros(3), method=numpy_jt)


@pytest.mark.parametrize("kwargs, message", [
    (dict(axes=np.array([[0, 0, 2.0]])), r"axes: expected unit joint axes, got \|axes\[0\]\| = 2"),
    (dict(offsets=np.zeros((2, 3))), r"offsets: expected shape \(1, 3\)"),
    (dict(base=np.zeros(2)), r"base: expected shape \(3,\)"),
    (dict(offsets=np.zeros((1, 3))), "offsets: expected a positive total"),
    (dict(axes=[["0", "0", "1"]]), "axes: expected an array of numbers"),
    (dict(dim=4), "dim: expected 2 .* or 3"),
    (dict(dim=2, axes=np.array([[0, 1.0, 0]])), "dim: a planar chain"),
])
def test_a_chain_built_directly_is_checked(kwargs, message):
    args = dict(axes=np.array([[0, 0, 1.0]]), offsets=np.array([[1.0, 0, 0]]),
                base=np.zeros(3), dim=3) | kwargs
    with pytest.raises(ValueError, match=message):
        ik.Chain(**args)


def test_a_chain_built_directly_solves_and_jax_rebuilds_it_unchecked():
    arm = ik.Chain([[0, 0, 1.0]] * 3, [[1.0, 0, 0]] * 3, [0.0, 0, 0], dim=2)
    assert isinstance(arm.axes, np.ndarray)
    assert ik.solve(arm, [1.0, 1.0], np.zeros(3)).converged
    # JAX puts markers (None, in_axes) and tracers in a chain's leaves: no checks then
    leaves, tree = jax.tree_util.tree_flatten(arm)
    assert jax.tree_util.tree_unflatten(tree, [None] * len(leaves)).axes is None
    reach_of = jax.jit(lambda a: ik.fk(a, np.zeros(3)))  # the chain goes in as tracers
    scaled = jax.tree_util.tree_unflatten(tree, [arm.axes, 2 * arm.offsets, arm.base])
    np.testing.assert_allclose(reach_of(scaled), [6.0, 0.0])
    assert jax.tree_util.tree_map(lambda leaf: 0, arm).axes == 0  # an in_axes spec


def test_zero_length_links_are_alike_for_planar_and_spatial_chains():
    """Two joints at one point (a spherical wrist, a zero link) are allowed in both."""
    planar = ik.planar_chain([1.0, 0.0, 1.0])
    spatial = ik.serial_chain([[0, 0, 1]] * 3, [[1, 0, 0], [0, 0, 0], [1, 0, 0]])
    theta = np.array([0.3, -0.2, 0.5])
    np.testing.assert_allclose(ik.fk(planar, theta), ik.fk(spatial, theta)[:2], atol=1e-12)


@pytest.mark.parametrize("method", ["jt", "pinv", "dls", "ccd"])
def test_arms_at_the_documented_size_bounds_solve_as_at_size_one(method):
    """Within HUGE and TINY (1e+-40, ikteach/core/_validate.py) an arm scaled by s behaves as
    at s = 1 (damping, tol and the "motion" stall rule scaled with it)."""
    def run(scale):
        arm = ik.planar_chain(scale * np.array([1.0, 1.0, 1.0]))
        return ik.solve(arm, scale * np.array([1.0, 1.0]), np.array([0.1, 0.2, 0.3]),
                        method=method, tol=1e-6 * scale, damping=0.5 * scale, stop_rule="motion")

    one = run(1.0)
    for scale in (1e-40, 3e39):  # the shortest link, the longest total
        res = run(scale)
        assert (res.status, res.iterations) == (one.status, one.iterations)
        assert 0 < res.error / scale < 2 * one.error


def test_a_start_outside_the_limits_is_moved_onto_them():
    res = ik.solve(ARM, [1.0, 1.0], [2.0, 0.0, 0.0], joint_limits=(-1.0, 1.0))
    np.testing.assert_array_equal(res.trace.theta[0], [1.0, 0.0, 0.0])


# Issue 40: inputs that were accepted without a meaning, or refused without naming the parameter
@pytest.mark.parametrize("kwargs, message", [
    (dict(method=ik.Pinv, rcond=None), "method: expected a method object such as Pinv()"),
    (dict(method=ik.DLS), r"method: expected a method object such as DLS\(\) .* the class DLS"),
    (dict(method="jt", damping=-1.0), "damping: expected a number >= 0"),
    (dict(method="dls", gamma_max=0.0), "gamma_max: expected a number > 0"),
    (dict(method="pinv", damping=np.nan), "damping: expected a finite number"),
    (dict(method="dls", rcond=2.0), "rcond: expected a relative cut-off 0 <= rcond < 1"),
])
def test_parameters_of_other_methods_are_checked_and_classes_named(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ik.solve(ARM, [1.0, 1.0], np.zeros(3), **kwargs)


@pytest.mark.parametrize("make, message", [
    (lambda: ik.Pinv(rcond=2.0), "rcond: expected a relative cut-off 0 <= rcond < 1"),
    (lambda: ik.Pinv(rcond=1.0), "rcond: expected a relative cut-off 0 <= rcond < 1"),
    (lambda: ik.JT(alpha=0.0), "alpha: expected a number > 0"),
    (lambda: ik.SDLS(gamma_max=0.0), "gamma_max: expected a number > 0"),
])
def test_method_parameters_that_would_never_move_are_refused(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_none_means_the_default_for_max_iter_and_stop_rule():
    """None is "the default" for every option: stop_rule=None is the motion rule (it used to run
    the report's unit-dependent joint_steps rule), max_iter=None is 1000."""
    plain = ik.solve(ARM, [3.5, 1.0], np.full(3, 0.1), method="jt")
    given = ik.solve(ARM, [3.5, 1.0], np.full(3, 0.1), method="jt", stop_rule=None, max_iter=None)
    report = ik.solve(ARM, [3.5, 1.0], np.full(3, 0.1), method="jt", stop_rule="joint_steps")
    assert (given.status, given.iterations) == (plain.status, plain.iterations)
    assert report.iterations != plain.iterations  # the two rules differ here, so None is not it
    assert ik.Options(stop_rule=None, max_iter=None) == ik.Options()


TREE_JOINTS = dict(axes=[[0, 0, 1], [0, 0, 1]], parents=[-1, 0], effector_parents=[1])


@pytest.mark.parametrize("scale, message", [
    (0.0, "positions: expected a positive total link length"),
    (1e-60, r"positions: expected link lengths of 0 or within \[1e-40"),
])
def test_a_tree_of_size_zero_or_below_tiny_is_refused_like_a_chain(scale, message):
    with pytest.raises(ValueError, match=message):
        ik.tree(np.array([[0.0, 0, 0], [1, 0, 0]]) * scale, effectors=np.array([[2.0, 0, 0]]) * scale,
                **TREE_JOINTS)
    ik.tree(np.array([[0.0, 0, 0], [1, 0, 0]]) * 1e-30, effectors=np.array([[2.0, 0, 0]]) * 1e-30,
            **TREE_JOINTS)  # above TINY: accepted
