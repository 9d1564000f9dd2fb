import dataclasses

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

import ikteach as ik
from strategies import angles

ARM = ik.planar_chain([1.0, 1.0, 1.0])
START = np.array([0.1, 0.2, 0.3])
three_angles = st.lists(angles, min_size=3, max_size=3).map(np.array)


@given(three_angles, st.sampled_from(["pinv", "dls"]))
def test_reachable_targets_converge_and_really_reach(theta_goal, method):
    target = np.asarray(ik.fk(ARM, theta_goal))
    # on the boundary itself (straight arm) damping slows DLS to a crawl: keep to the interior
    assume(np.linalg.norm(target) < 0.98 * ik.reach(ARM))
    res = ik.solve(ARM, target, START, method=method, tol=1e-4, max_iter=500, max_step=0.5)
    assert res.status == "converged"
    assert np.linalg.norm(ik.fk(ARM, res.theta) - target) < 1e-4
    assert res.error < 1e-4


def test_spatial_chain_reaches_a_target_made_by_fk():
    rng = np.random.default_rng(3)
    axes = rng.normal(size=(5, 3))
    arm = ik.serial_chain(axes, rng.uniform(-1, 1, size=(5, 3)))
    target = np.asarray(ik.fk(arm, rng.uniform(-1, 1, 5)))
    res = ik.solve(arm, target, np.zeros(5), method="dls", damping=0.1, tol=1e-5)
    assert res.status == "converged"
    assert np.linalg.norm(ik.fk(arm, res.theta) - target) < 1e-5


@pytest.mark.parametrize("target", [[3.5, 1.0], [0.0, -4.0], [-5.0, 5.0]])
def test_out_of_reach_dls_with_clamp_stalls_stretched_toward_the_target(target):
    res = ik.solve(ARM, target, START, method="dls", clamp=0.3)
    assert res.status == "stalled"
    distance = np.linalg.norm(target) - ik.reach(ARM)
    assert res.error == pytest.approx(distance, abs=1e-3)
    tip = np.asarray(ik.fk(ARM, res.theta))
    np.testing.assert_allclose(tip / np.linalg.norm(tip), np.asarray(target) / np.linalg.norm(target),
                               atol=1e-3)


@pytest.mark.parametrize("target", [[3.5, 1.0], [0.0, -4.0], [3.001, 0.0]])
def test_pseudoinverse_never_claims_convergence_out_of_reach(target):
    res = ik.solve(ARM, target, START, method="pinv", max_iter=300)
    assert res.status != "converged"
    assert np.all(np.isfinite(res.theta)) and np.isfinite(res.error)


def test_the_reports_story_pinv_and_dls_beat_jacobian_transpose():
    target = [2.5, 0.5]
    its = {m: ik.solve(ARM, target, START, method=m).iterations for m in ("jt", "pinv", "dls")}
    assert all(ik.solve(ARM, target, START, method=m).converged for m in its)
    assert its["pinv"] * 3 <= its["jt"] and its["dls"] * 3 <= its["jt"], its


def test_trace_has_one_entry_per_iteration_plus_the_start():
    res = ik.solve(ARM, [1.0, 1.5], START, method="jt")
    assert res.trace.theta.shape == (res.iterations + 1, 3)
    assert res.trace.error.shape == (res.iterations + 1,)
    np.testing.assert_allclose(res.trace.theta[0], START)
    np.testing.assert_allclose(res.trace.theta[-1], res.theta)
    assert res.trace.error[-1] == res.error
    assert res.trace.error[0] == pytest.approx(np.linalg.norm([1.0, 1.5] - np.asarray(ik.fk(ARM, START))))
    assert np.all(res.trace.error[:-1] >= 1e-3)  # only the last entry is below tol


def test_convergence_is_checked_before_any_step():
    target = np.asarray(ik.fk(ARM, START))
    res = ik.solve(ARM, target, START, method="pinv")
    assert (res.status, res.iterations) == ("converged", 0)


def test_max_iter_stops_the_loop():
    res = ik.solve(ARM, [2.5, 0.5], START, method="jt", max_iter=3, tol=1e-12)
    assert (res.status, res.iterations) == ("max_iter", 3)


def test_result_is_frozen():
    res = ik.solve(ARM, [1.0, 1.0], START)
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.status = "converged"
    with pytest.raises(ValueError):
        res.theta[0] = 1.0


def test_max_step_caps_every_joint_change():
    res = ik.solve(ARM, [-2.0, -1.0], START, method="pinv", max_step=np.radians(5))
    assert np.max(np.abs(np.diff(res.trace.theta, axis=0))) <= np.radians(5) + 1e-12


def test_clamp_bounds_the_error_the_step_sees():
    seen = []

    def spy(J, e):
        seen.append(float(np.linalg.norm(e)))
        return np.asarray(ik.dls_step(J, e, 0.5))

    ik.solve(ARM, [-2.5, 0.5], START, method=spy, clamp=0.2, max_iter=20)
    assert max(seen) <= 0.2 + 1e-12


def test_a_jax_step_function_and_a_numpy_one_give_the_same_answer():
    jax_step = lambda J, e: ik.dls_step(J, e, 0.5)
    numpy_step = lambda J, e: np.linalg.solve(np.asarray(J) @ np.asarray(J).T + 0.25 * np.eye(2),
                                              np.asarray(e)) @ np.asarray(J)
    a = ik.solve(ARM, [1.0, 1.5], START, method=jax_step)
    b = ik.solve(ARM, [1.0, 1.5], START, method=numpy_step)
    c = ik.solve(ARM, [1.0, 1.5], START, method="dls", damping=0.5)
    assert a.iterations == b.iterations == c.iterations
    np.testing.assert_allclose(a.theta, b.theta, atol=1e-10)
    np.testing.assert_allclose(a.theta, c.theta, atol=1e-10)


def test_a_step_returning_nan_ends_diverged_with_finite_theta():
    res = ik.solve(ARM, [1.0, 1.5], START, method=lambda J, e: np.full(3, np.nan))
    assert res.status == "diverged"
    assert np.all(np.isfinite(res.theta)) and np.all(np.isfinite(res.trace.theta))


def test_undamped_dls_at_a_singularity_diverges_without_nan():
    res = ik.solve(ARM, [3.5, 0.0], np.zeros(3), method="dls", damping=0.0)
    assert res.status in {"diverged", "stalled", "max_iter"}
    assert np.all(np.isfinite(res.theta)) and np.isfinite(res.error)


@pytest.mark.parametrize("start", [np.zeros(3), np.array([0.0, np.pi, 0.0]), np.array([0.0, np.pi, np.pi])])
@pytest.mark.parametrize("method", ["jt", "pinv", "dls"])
@pytest.mark.parametrize("target", [[1.0, 0.5], [3.0, 0.0], [4.0, 0.0], [0.0, 0.0]])
def test_singular_starts_never_produce_nan(start, method, target):
    res = ik.solve(ARM, target, start, method=method, max_iter=200)
    assert np.all(np.isfinite(res.theta)) and np.isfinite(res.error)
    assert np.all(np.isfinite(res.trace.theta)) and np.all(np.isfinite(res.trace.error))


@given(st.lists(angles, min_size=3, max_size=3), st.sampled_from(["jt", "pinv", "dls"]))
def test_random_starts_never_produce_nan(start, method):
    res = ik.solve(ARM, [4.0, 1.0], np.array(start), method=method, max_iter=100)
    assert np.all(np.isfinite(res.theta)) and np.isfinite(res.error)
