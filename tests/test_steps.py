import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import ikteach as ik
from strategies import matrices


@given(matrices(), st.floats(-3, 3))
def test_optimal_alpha_minimises_the_residual(Je, other):
    J, e = Je
    alpha = float(ik.optimal_alpha(J, e))
    v = J @ J.T @ e
    residual = lambda a: np.linalg.norm(e - a * v)
    assert residual(alpha) <= residual(other) + 1e-9
    assert residual(alpha) <= residual(alpha * 1.01) + 1e-12
    assert residual(alpha) <= residual(alpha * 0.99) + 1e-12
    np.testing.assert_allclose(ik.jt_step(J, e), alpha * J.T @ e, atol=1e-12)


def test_jt_step_is_zero_not_nan_when_jjte_vanishes():
    J = np.array([[0.0, 0.0], [1.0, 1.0]])
    e = np.array([1.0, 0.0])  # orthogonal to every column
    step = np.asarray(ik.jt_step(J, e))
    assert np.all(np.isfinite(step)) and np.allclose(step, 0)
    assert np.allclose(ik.jt_step(J, np.zeros(2)), 0)


@given(matrices())
def test_pinv_step_is_the_minimum_norm_least_squares_answer(Je):
    J, e = Je
    expected = np.linalg.lstsq(J, e, rcond=1e-6)[0]
    np.testing.assert_allclose(ik.pinv_step(J, e, rcond=1e-6), expected, atol=1e-8)


def test_pinv_cutoff_drops_small_singular_values():
    J = np.diag([1.0, 1e-5])
    e = np.array([1.0, 1.0])
    np.testing.assert_allclose(ik.pinv_step(J, e, rcond=1e-3), [1.0, 0.0])
    np.testing.assert_allclose(ik.pinv_step(J, e, rcond=1e-8), [1.0, 1e5])


def test_pinv_of_zero_jacobian_is_zero():
    assert np.allclose(ik.pinv_step(np.zeros((2, 3)), np.ones(2)), 0)


@given(matrices(), st.floats(0.01, 5.0))
def test_both_dls_forms_agree(Je, damping):
    J, e = Je
    np.testing.assert_allclose(ik.dls_step(J, e, damping), ik.dls_step_normal(J, e, damping),
                               rtol=1e-8, atol=1e-10)


@given(matrices(), st.floats(0.01, 5.0))
def test_dls_solves_the_damped_normal_equations(Je, damping):
    J, e = Je
    step = np.asarray(ik.dls_step(J, e, damping))
    lhs = (J.T @ J + damping**2 * np.eye(J.shape[1])) @ step
    np.testing.assert_allclose(lhs, J.T @ e, rtol=1e-8, atol=1e-10)


def test_dls_uses_lambda_squared():
    J, e = np.array([[2.0]]), np.array([1.0])
    # sigma / (sigma^2 + lambda^2) with sigma = 2, lambda = 3
    assert float(ik.dls_step(J, e, 3.0)[0]) == pytest.approx(2 / 13)


def test_clamp_error_and_cap_step():
    e = np.array([3.0, 4.0])
    np.testing.assert_allclose(ik.clamp_error(e, 1.0), [0.6, 0.8])
    np.testing.assert_allclose(ik.clamp_error(e, 10.0), e)
    np.testing.assert_allclose(ik.clamp_error(e, np.inf), e)
    np.testing.assert_allclose(ik.cap_step(np.array([0.2, -1.0]), 0.5), [0.1, -0.5])
    np.testing.assert_allclose(ik.cap_step(np.array([0.2, -0.3]), 0.5), [0.2, -0.3])


@pytest.mark.parametrize("m", [1, 2, 3])
def test_the_small_dls_step_is_dls_step(m):
    """Cramer's rule (lecture 04) gives the LU solve's step to rounding, for m <= 3 rows."""
    rng = np.random.default_rng(m)
    for _ in range(20):
        J, e = rng.normal(size=(m, 6)), rng.normal(size=m)
        for lam in (0.01, 0.5):
            np.testing.assert_allclose(ik.core.dls.dls_step_small(J, e, lam), ik.dls_step(J, e, lam),
                                       rtol=1e-9, atol=1e-12)
    singular = np.zeros((m, 6))
    assert not np.all(np.isfinite(ik.core.dls.dls_step_small(singular, np.ones(m), 0.0)))
