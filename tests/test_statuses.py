"""Statuses that mean what they say (issue 34): poses at any unit, "stalled" only at a minimum,
priorities with the plain vocabulary, FABRIK's fixed point, a rest level that cannot explode,
tiny arms for every method, clear messages."""
import types

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import ikteach as ik
from ikteach.core import stop_rules
from ikteach.core._validate import round_finite
from ikteach.core.levels import rest_gain_bound
from ikteach.core.problem import Problem
from ikteach.core.tasks import task_for

UR5_GOAL = np.array([0.3, -1.0, 1.2, 0.4, 0.8, -0.5])


def scaled_ur5(scale):
    u = ik.core.robots.ur5()
    return ik.Chain(np.asarray(u.axes), np.asarray(u.offsets) * scale, np.asarray(u.base) * scale,
                    dim=3)


# 1. Pose targets at any unit ------------------------------------------------------------------

@pytest.mark.parametrize("scale", [1.0, 1000.0])  # metres, millimetres
def test_a_ur5_pose_converges_alike_in_metres_and_millimetres(scale):
    arm = scaled_ur5(scale)
    T = np.asarray(ik.fk_pose(arm, UR5_GOAL))
    res = ik.solve(arm, T, UR5_GOAL + 0.3)
    position, orientation = ik.pose_errors(arm, res.theta, T)
    assert res.status == "converged", res
    assert orientation < 1e-3 and position < scale * 1e-3
    metres = ik.solve(scaled_ur5(1.0), np.asarray(ik.fk_pose(scaled_ur5(1.0), UR5_GOAL)), UR5_GOAL + 0.3)
    assert res.iterations == metres.iterations
    np.testing.assert_allclose(res.theta, metres.theta, atol=1e-9)


def converged_within_the_stated_tolerances(arm, res, T):
    """converged means |p_t - p| < tol and angle < tol / L (L = ik.reach, tol = L / 3000)."""
    L = float(ik.reach(arm))
    position, orientation = ik.pose_errors(arm, res.theta, T)
    return position < L / 3000 and orientation < 1 / 3000


@given(st.floats(-3, 3), st.lists(st.floats(-np.pi, np.pi), min_size=6, max_size=6),
       st.integers(0, 2**31 - 1))
def test_pose_statuses_are_the_same_at_every_arm_scale(log_scale, goal, seed):
    """Arm scaled by 1e-3 .. 1e3, defaults only: the same status and iterations as in metres,
    and "converged" never accepts an orientation error above the stated 1/3000 rad."""
    goal = np.array(goal)
    start = goal + np.random.default_rng(seed).uniform(-0.4, 0.4, 6)
    unit, arm = scaled_ur5(1.0), scaled_ur5(10.0**log_scale)
    at_one = ik.solve(unit, np.asarray(ik.fk_pose(unit, goal)), start)
    T = np.asarray(ik.fk_pose(arm, goal))
    res = ik.solve(arm, T, start)
    assert (res.status, res.iterations) == (at_one.status, at_one.iterations)
    if res.status == "converged":
        assert converged_within_the_stated_tolerances(arm, res, T)


def test_converged_never_accepts_an_orientation_error_above_tol_over_L():
    """A tolerance given by hand means tol in position and tol / L radians in orientation."""
    arm = scaled_ur5(1000.0)
    T = np.asarray(ik.fk_pose(arm, UR5_GOAL))
    L = float(ik.reach(arm))
    for tol in (L / 30, L / 300, L / 3000):
        res = ik.solve(arm, T, UR5_GOAL + 0.3, tol=tol)
        assert res.status == "converged"
        assert ik.pose_errors(arm, res.theta, T)[1] < tol / L


# 2. "stalled" only at a real minimum -----------------------------------------------------------

def test_a_weak_direction_does_not_pass_for_a_minimum():
    """Nearly straight arm, target 5e-6 inward along J's weak direction (sigma 1e-3 sigma_max):
    ||J^T e|| is 0.1% of sigma_max ||e||, but a lighter step reaches it: "damped", not "stalled"."""
    arm = ik.planar_chain([1.0] * 3)
    theta = np.array([0.3, 0.002, 0.0])
    x = np.asarray(ik.fk(arm, theta))
    u_weak = np.linalg.svd(np.asarray(ik.jacobian(arm, theta)))[0][:, -1]
    target = x - 5e-6 * np.sign(u_weak @ x) * u_weak      # towards the base: reachable
    res = ik.solve(arm, target, theta, tol=1e-8)
    assert res.status == "damped", res
    assert ik.solve(arm, target, res.theta, tol=1e-8, damping=1e-3).converged


def monotone_damped_descent(task, arm, target, theta, steps=300):
    """Levenberg-Marquardt with only downhill steps (each turn at most 0.1 rad): the lowest
    ||e|| reachable from theta without leaving its basin."""
    error = jax.jit(lambda q: task.error(arm, target, q))
    jac = jax.jit(lambda q: task.jacobian(arm, q))
    cost = lambda q: float(np.sum(np.asarray(error(q)) ** 2))
    theta, mu = np.asarray(theta), 1e-2
    for _ in range(steps):
        J, e = np.asarray(jac(theta)), np.asarray(error(theta))
        while mu < 1e12:
            d = np.linalg.solve(J.T @ J + mu * np.eye(theta.size), J.T @ e)
            d *= min(1.0, 0.1 / np.abs(d).max())
            if cost(theta + d) < cost(theta):
                theta, mu = theta + d, mu / 3
                break
            mu *= 2
    return np.sqrt(cost(theta))


def test_the_y_tree_of_the_issue_stops_at_a_real_local_minimum():
    """The issue's Y tree "stalled" at 0.328 is a local minimum: downhill steps from there gain
    2e-4 of ||e|| at most, and the Hessian is positive definite. (Damping 0.005 converges from
    there only by jumping out of the basin: its first step raises ||e|| to 2.5.)"""
    Y = ik.core.buss_trees.y_tree()
    t = np.array([[-0.19529626583323784, -0.27869979609357226, 0.7538360295293157],
                  [1.461955312870125, 0.3324016630525436, 0.5347503011382019]])
    res = ik.solve(Y, t, np.array([0, np.pi, 0, np.pi, 0, np.pi, 0]))
    assert res.status == "stalled" and abs(res.error - 0.328) < 1e-3
    task = task_for(Y, t.shape)
    assert monotone_damped_descent(task, Y, jnp.asarray(t), res.theta) > res.error * (1 - 2e-4)
    restart = ik.solve(Y, t, res.theta, damping=0.005)
    assert restart.converged and restart.trace.error[1] > 5 * res.error


P3 = ik.planar_chain([1.0] * 3)


@pytest.mark.parametrize("kw", [{}, {"rest_pose": np.zeros(3)}, {"levels": (0,)}])
def test_priorities_and_the_rest_pose_say_damped_like_plain_solves(kw):
    assert ik.solve(P3, [1, 1], np.full(3, 0.3), max_step=1e-6, **kw).status == "damped"


@pytest.mark.parametrize("kw", [{}, {"rest_pose": np.zeros(3)}, {"levels": (0,)}])
def test_priorities_and_the_rest_pose_say_singular_like_plain_solves(kw):
    """Straight arm, target on its own line: a saddle whichever way the solve is asked."""
    assert ik.solve(P3, [2.0, 0.0], np.zeros(3), **kw).status == "singular"


FABRIK_ARM = ik.serial_chain([[0.62, -0.78, 0.13], [-0.75, -0.6, -0.28], [-0.91, -0.1, -0.39]],
                             [[0.99, 0.07, -0.11], [-0.22, -0.52, -0.82], [-0.59, 0.72, -0.36]])
FABRIK_TARGET = np.asarray(ik.fk(FABRIK_ARM, [0.78, -0.83, -1.99]))
NO_LIMITS = types.SimpleNamespace(tol=float(ik.reach(FABRIK_ARM)) / 3000, lower=-np.inf,
                                  upper=np.inf, max_step=np.inf)  # the solve's defaults


def test_fabrik_on_a_hinge_chain_stops_at_its_own_fixed_point():
    """FABRIK (no damping, cap or clamp) stops far from a reachable target: its fixed point,
    not a minimum of ||e||; a Jacobian method goes on from there."""
    res = ik.solve(FABRIK_ARM, FABRIK_TARGET, np.zeros(3), method="fabrik")
    assert res.status != "damped" and res.error > 1.0
    problem = Problem(task_for(FABRIK_ARM, (3,)), FABRIK_ARM, jnp.asarray(FABRIK_TARGET))
    kinds = stop_rules.why_stalled(problem, FABRIK_TARGET[None], res.theta[None], np.array([True]),
                                   ik.Options(tol=NO_LIMITS.tol).resolved(1.0, 3), ((0, 1, 2),),
                                   own_update=True)
    assert stop_rules.KIND_STATUS[int(kinds[0])] == "fixed_point"
    assert ik.solve(FABRIK_ARM, FABRIK_TARGET, res.theta, method="pinv").converged


def test_fabrik_says_fixed_point():
    assert ik.solve(FABRIK_ARM, FABRIK_TARGET, np.zeros(3), method="fabrik").status == "fixed_point"


def test_a_true_minimum_out_of_reach_still_says_stalled():
    for kw in ({}, {"levels": (0,)}):
        assert ik.solve(P3, [3.5, 1.0], np.full(3, 0.1), clamp=0.3, **kw).status == "stalled", kw


# 3. A rest level that cannot explode -----------------------------------------------------------

def test_a_rest_gain_above_the_stable_bound_is_refused_with_the_bound():
    arm = ik.planar_chain([1.0] * 5)
    bound = rest_gain_bound(5 / 6)  # the default damping L / 6
    with pytest.raises(ValueError, match=r"rest_gain: .*at most 1 \+ damping\^2 = 1\.694.* got 5"):
        ik.solve(arm, [10.0, 0.0], np.full(5, 0.3), rest_pose=np.zeros(5), rest_gain=5.0)
    with pytest.raises(ValueError, match="rest_gain"):
        ik.track(arm, np.tile([10.0, 0.0], (5, 1)), np.full(5, 0.3), rest_pose=np.zeros(5),
                 rest_gain=1.01 * bound)
    res = ik.solve(arm, [10.0, 0.0], np.full(5, 0.3), rest_pose=np.zeros(5), rest_gain=bound)
    assert np.max(np.abs(res.trace.theta)) < 10, res


def test_the_issues_undamped_rest_gain_near_the_old_bound_is_refused():
    """Issue 40: P3, lambda 0, rest_gain 1.99 (below the old bound 2) drove theta_3 to 33 rad."""
    with pytest.raises(ValueError, match=r"rest_gain: expected a gain of at most 1 \+ damping\^2 = 1 "):
        ik.solve(P3, [1.5, 1.0], np.full(3, 0.3), damping=0.0, rest_pose=np.zeros(3), rest_gain=1.99)
    assert ik.solve(P3, [1.5, 1.0], np.full(3, 0.3), damping=0.0, rest_pose=np.zeros(3),
                    rest_gain=1.0).converged


def test_huge_finite_angles_print_as_numbers():
    printed = round_finite(np.array([2.9e307, -1.23456789, 1e15, np.inf]), 4).tolist()
    assert printed == [2.9e307, -1.2346, 1e15, np.inf]


# 4. Tiny accepted scales, rigid targets, clear messages ----------------------------------------

@pytest.mark.parametrize("scale", [1e-40, 1e-13, 1e-11, 1e30])
@pytest.mark.parametrize("method", ["jt", "pinv", "dls", "sdls", "ccd", "fabrik"])
def test_every_method_works_on_every_accepted_arm_size(method, scale):
    arm = ik.planar_chain([scale] * 3)
    target = np.asarray(ik.fk(arm, [0.5, 0.4, 0.3]))
    assert ik.solve(arm, target, np.full(3, 0.1), method=method).converged
    far = ik.solve(arm, np.array([3.5, 1.0]) * scale, np.full(3, 0.1), method=method)
    assert far.status == ("max_iter" if method == "pinv" else "stalled")


@pytest.mark.parametrize("target", [2 * np.eye(4), np.diag([1.0, 1.0, -1.0, 1.0]),
                                    np.diag([2.0, 2.0, 2.0, 1.0])])
def test_pose_errors_refuses_non_rigid_targets(target):
    with pytest.raises(ValueError, match="target: expected a r"):
        ik.pose_errors(ik.core.robots.ur5(), np.zeros(6), target)


def test_make_pose_names_the_parameter():
    with pytest.raises(ValueError, match=r"R: expected shape \(3, 3\), got shape \(2, 2\)"):
        ik.make_pose(np.eye(2), [0, 0, 0])
    with pytest.raises(ValueError, match=r"p: expected shape \(3,\)"):
        ik.make_pose(np.eye(3), [0, 0])
    with pytest.raises(ValueError, match="p: expected finite"):
        ik.make_pose(np.eye(3), [0, np.nan, 0])
    np.testing.assert_array_equal(jax.jit(ik.make_pose)(np.eye(3), jnp.ones(3)),
                                  ik.make_pose(np.eye(3), [1, 1, 1]))
