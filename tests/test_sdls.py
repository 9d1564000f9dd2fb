import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import ikteach as ik
from strategies import matrices

ARM = ik.planar_chain([1.0, 1.0, 1.0])
START = np.array([0.1, 0.2, 0.3])


@given(matrices(), st.floats(1e-3, 1e3), st.floats(0.01, 1.5))
def test_sdls_never_turns_a_joint_more_than_gamma_max(case, scale, gamma_max):
    J, e = case
    delta = np.asarray(ik.sdls_step(J, scale * e, gamma_max))
    assert np.all(np.isfinite(delta))
    assert np.max(np.abs(delta)) <= gamma_max * (1 + 1e-12)


@given(matrices(max_rows=3, max_cols=6))
def test_small_errors_give_the_pseudoinverse_step(case):
    # far from any clamp, every term is the pseudoinverse's (alpha_i / sigma_i) v_i
    J, e = case
    sigma = np.linalg.svd(J, compute_uv=False)
    if sigma.min() < 1e-2:
        return
    e = 1e-6 * e
    np.testing.assert_allclose(ik.sdls_step(J, e), np.linalg.pinv(J) @ e, atol=1e-12)


def test_singular_direction_is_damped_not_blown_up():
    # nearly straight arm, target straight ahead: J has a small sigma (about 0.012) along x
    theta = np.array([0.0, 0.02, 0.0])
    J = np.asarray(ik.jacobian(ARM, theta))
    e = np.array([0.5, 0.0])
    assert np.max(np.abs(ik.pinv_step(J, e))) > 10
    assert np.max(np.abs(ik.sdls_step(J, e))) <= ik.core.sdls.GAMMA_MAX


def test_solve_trace_respects_gamma_max():
    res = ik.solve(ARM, [-1.0, -1.5], START, method="sdls", gamma_max=0.2, tol=1e-5)
    assert res.converged
    assert np.max(np.abs(np.diff(res.trace.theta, axis=0))) <= 0.2 + 1e-12


@pytest.mark.parametrize("target", [[2.5, 0.5], [0.3, 1.2], [-1.0, -1.5]])
def test_sdls_converges_on_reachable_targets(target):
    res = ik.solve(ARM, target, START, method="sdls", tol=1e-5, max_iter=500)
    assert res.status == "converged", res
    assert np.linalg.norm(np.asarray(ik.fk(ARM, res.theta)) - target) < 1e-5


def test_sdls_on_a_spatial_chain():
    rng = np.random.default_rng(5)
    arm = ik.serial_chain(rng.normal(size=(6, 3)), rng.uniform(-1, 1, size=(6, 3)))
    target = np.asarray(ik.fk(arm, rng.uniform(-1, 1, 6)))
    res = ik.solve(arm, target, np.zeros(6), method="sdls", tol=1e-5, max_iter=2000)
    assert res.status == "converged", res


@pytest.mark.parametrize("target", [[3.5, 1.0], [0.0, -4.0], [3.001, 0.0]])
def test_sdls_stalls_out_of_reach_without_nan(target):
    # tol well below the 1e-3 by which [3.001, 0] is out of reach (with tol = 1e-3, ||e||
    # still closes in on tol: "slow")
    res = ik.solve(ARM, target, START, method="sdls", max_iter=3000, tol=1e-5)
    assert res.status == "stalled", res
    assert np.all(np.isfinite(res.theta))
    assert res.error == pytest.approx(np.linalg.norm(target) - 3.0, abs=1e-3)


def test_gamma_max_must_be_positive():
    with pytest.raises(ValueError, match="gamma_max"):
        ik.solve(ARM, [1.0, 1.0], START, method="sdls", gamma_max=0.0)
    with pytest.raises(ValueError, match="gamma_max"):
        ik.solve_batch(ARM, [[1.0, 1.0]], START, method="sdls", gamma_max=-1.0)
