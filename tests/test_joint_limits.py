"""Joint limits: no result of solve, solve_batch or track ever leaves [lower, upper]."""
import logging
import re

import jax
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import ikteach as ik
import strategies
from strategies import planar_arms

# Two tree shapes (parents, effector parents): the geometry is random, the shapes few, so
# hypothesis explores geometry and targets without a compile per example.
TOPOLOGIES = [((-1, 0, 1, 1, 3), (2, 4)), ((-1, 0, 0, 2, 3, 4), (1, 5))]


def random_trees():
    return strategies.random_trees(shapes=TOPOLOGIES)


MODES = ["clamp", "clamping_loop"]
SLICING = {"dynamic_slice", "slice"}


def random_limits(rng, n):
    """Per-joint limits around 0 of random width; some joints unlimited on one or both sides."""
    lower = -rng.uniform(0.0, 1.5, n)
    upper = rng.uniform(0.0, 1.5, n)
    lower[rng.random(n) < 0.2] = -np.inf
    upper[rng.random(n) < 0.2] = np.inf
    return lower, upper


def assert_within(theta, lower, upper):
    theta = np.asarray(theta)
    assert np.all(theta >= lower) and np.all(theta <= upper), (theta, lower, upper)


@settings(max_examples=12, deadline=None)
@given(random_trees(), st.integers(0, 2**31 - 1), st.sampled_from(MODES))
def test_tree_solves_never_leave_the_limits(arm, seed, mode):
    rng = np.random.default_rng(seed)
    lower, upper = random_limits(rng, arm.n_joints)
    targets = rng.normal(size=(arm.n_effectors, 3)) * 2
    theta0 = rng.uniform(-2, 2, arm.n_joints)  # may start outside: moved onto the limits
    res = ik.solve(arm, targets, theta0, joint_limits=(lower, upper), limit_mode=mode, max_iter=60)
    assert_within(res.trace.theta, lower, upper)
    assert np.all(np.isfinite(res.theta))


@settings(max_examples=6, deadline=None)
@given(random_trees(), st.integers(0, 2**31 - 1))
def test_tree_batches_and_tracks_never_leave_the_limits(arm, seed):
    rng = np.random.default_rng(seed)
    lower, upper = random_limits(rng, arm.n_joints)
    targets = rng.normal(size=(arm.n_effectors, 3)) * 2
    theta0 = rng.uniform(-2, 2, arm.n_joints)
    batch = ik.solve_batch(arm, targets[None] + rng.normal(size=(3, *targets.shape)), theta0,
                           joint_limits=(lower, upper), max_iter=60)
    assert_within(batch.theta, lower, upper)
    path = ik.track(arm, targets[None] + np.linspace(0, 1, 8)[:, None, None], theta0,
                    joint_limits=(lower, upper), limit_mode="clamp")
    assert_within(path.theta[1:], lower, upper)


@settings(max_examples=15, deadline=None)
@given(planar_arms(min_joints=4, max_joints=4), st.integers(0, 2**31 - 1),
       st.sampled_from(["dls", "jt", "pinv", "sdls", "ccd", "fabrik"]))
def test_chain_solves_never_leave_the_limits(arm, seed, method):
    rng = np.random.default_rng(seed)
    lower, upper = random_limits(rng, arm.n_joints)
    target = rng.normal(size=2) * ik.reach(arm) / 2
    res = ik.solve(arm, target, np.zeros(arm.n_joints), method=method,
                   joint_limits=(lower, upper), max_iter=60)
    assert_within(res.trace.theta, lower, upper)


def test_wide_limits_change_nothing():
    arm, target = ik.planar_chain([1.0, 1.0, 1.0]), [1.2, 1.9]
    free = ik.solve(arm, target, np.zeros(3))
    for mode in MODES:
        wide = ik.solve(arm, target, np.zeros(3), joint_limits=(-np.inf, np.inf), limit_mode=mode)
        np.testing.assert_array_equal(wide.trace.theta, free.trace.theta)


def test_new_limits_do_not_recompile(caplog, monkeypatch):
    # the bound on compiled programs may clear JAX's caches between the two solves: off here
    monkeypatch.setenv("IKTEACH_MAX_PROGRAMS", "0")
    arm, target = ik.planar_chain([1.0, 1.0, 1.0]), [1.2, 1.9]
    ik.solve(arm, target, np.zeros(3), joint_limits=([-0.4, -2, -0.2], [0.1, 0.4, 2]))  # stalls too
    with jax.log_compiles(True), caplog.at_level(logging.DEBUG):
        res = ik.solve(arm, target, np.zeros(3), joint_limits=([-0.5, -2, -0.1], [0.2, 0.3, 2]))
    compiled = {re.match(r"Compiling jit\((\w+)\)", r.getMessage()).group(1)
                for r in caplog.records if r.getMessage().startswith("Compiling")}
    assert compiled <= SLICING, compiled  # only the trace's slicing to its length, never the loop
    assert_within(res.theta, [-0.5, -2, -0.1], [0.2, 0.3, 2])


def test_clamping_loop_reaches_a_target_near_a_limit_in_fewer_steps():
    """Base joint held to +-0.1 rad: clamping throws its share of each step away, the
    clamping loop hands it to the free joints."""
    arm = ik.planar_chain([2 / 3] * 3)
    lower, upper = np.array([-0.1, -2, -2]), np.array([0.1, 2, 2])
    target = 1.7 * np.array([np.cos(0.6), np.sin(0.6)])
    clamp, loop = (ik.solve(arm, target, np.zeros(3), joint_limits=(lower, upper), limit_mode=m)
                   for m in MODES)
    assert clamp.converged and loop.converged
    assert loop.iterations < clamp.iterations / 2
    assert abs(loop.theta[0]) == pytest.approx(0.1)  # the base joint ends on a limit


def test_pinned_joint_never_moves():
    arm = ik.planar_chain([1.0, 1.0, 1.0])
    res = ik.solve(arm, [0.5, 1.5], [0.0, 0.3, 0.0], joint_limits=([-3, 0.3, -3], [3, 0.3, 3]))
    assert np.all(res.trace.theta[:, 1] == 0.3)
    assert res.converged


def test_limits_with_a_user_step_run_eagerly():
    arm = ik.planar_chain([1.0, 1.0, 1.0])
    lower, upper = np.full(3, -0.4), np.full(3, 0.4)

    def step(J, e):  # numpy: not traceable, so the loop runs eagerly
        J, e = np.asarray(J), np.asarray(e)
        return J.T @ np.linalg.solve(J @ J.T + 0.25 * np.eye(2), e)

    for mode in MODES:
        res = ik.solve(arm, [2.0, 1.5], np.zeros(3), method=step, joint_limits=(lower, upper),
                       limit_mode=mode, max_iter=50)
        assert_within(res.trace.theta, lower, upper)


def test_limits_on_a_built_in_method_are_compiled_without_a_trial_trace(monkeypatch):
    """The clamping loop around a built-in is JAX code (is_jax), so the solve goes straight to
    the compiled loop; around a user's step function it is tried by tracing it."""
    from ikteach.core import methods
    from ikteach.core.joint_limits import ClampingLoop

    assert ClampingLoop(ik.Pinv(), 0.0, 1.0, np.inf).is_jax
    assert not ClampingLoop(methods.as_method(lambda J, e: e), 0.0, 1.0, np.inf).is_jax
    tried, real = [], methods.jax.eval_shape

    def spy(fn, *args, **kwargs):  # the trial trace is a lambda of methods.py
        if getattr(fn, "__module__", None) == methods.__name__:
            tried.append(1)
        return real(fn, *args, **kwargs)

    monkeypatch.setattr(methods.jax, "eval_shape", spy)
    arm = ik.planar_chain([1.0, 1.0, 1.0])
    for mode in MODES:
        ik.solve(arm, [0.5, 1.5], np.zeros(3), method="dls", joint_limits=(np.full(3, -1.0), np.ones(3)),
                 limit_mode=mode)
    assert tried == []


@pytest.mark.parametrize("limits, mode, match", [
    ((np.zeros(2), np.ones(3)), None, "joint_limits: expected lower"),
    ((np.ones(3), np.zeros(3)), None, "joint_limits: expected lower <= upper"),
    ((np.full(3, np.nan), np.ones(3)), None, "joint_limits: lower"),
    ((np.full(3, np.inf), np.full(3, np.inf)), None, "joint_limits: lower"),
    (np.ones(3), None, "joint_limits: expected a pair"),
    ((-1, 1), "squash", "limit_mode"),
])
def test_bad_limits_name_the_parameter(limits, mode, match):
    with pytest.raises(ValueError, match=match):
        ik.solve(ik.planar_chain([1.0, 1.0, 1.0]), [1.0, 1.0], np.zeros(3), joint_limits=limits,
                 limit_mode=mode)


@pytest.mark.parametrize("method", ["ccd", "fabrik"])
def test_clamping_loop_needs_a_jacobian_method(method):
    arm = ik.planar_chain([1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="limit_mode: 'clamping_loop'"):
        ik.solve(arm, [1.0, 1.0], np.zeros(3), method=method, joint_limits=(-1, 1),
                 limit_mode="clamping_loop")
    res = ik.solve(arm, [1.0, 1.0], np.zeros(3), method=method, joint_limits=(-1, 1))  # clamps
    assert_within(res.trace.theta, -1, 1)
