"""The priority step: the secondary task lives in the primary's null space."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import ikteach as ik


# (m1, m2, n): one joint; tasks that fit together (m1 + m2 <= n) or conflict (m1 + m2 > n);
# a primary that takes every joint (m1 >= n); a secondary taller than the arm (m2 > n).
# A fixed set of shapes (each compiles once); the entries are random.
SHAPES = [(1, 1, 1), (1, 2, 3), (2, 2, 3), (3, 3, 3), (2, 3, 7), (5, 4, 9), (4, 2, 2), (1, 5, 4)]


@st.composite
def two_tasks(draw):
    """Random J1 (m1, n), e1, J2 (m2, n), e2 and a damping lambda (0 included)."""
    m1, m2, n = draw(st.sampled_from(SHAPES))
    rng = np.random.default_rng(draw(st.integers(0, 2**31 - 1)))
    damping = draw(st.sampled_from([0.0, 0.01, 0.1, 1.0]))
    return rng.normal(size=(m1, n)), rng.normal(size=m1), rng.normal(size=(m2, n)), rng.normal(size=m2), damping


def primary_only(J1, e1, damping):
    return np.asarray(ik.damped_pinv(J1, damping) @ e1)


@settings(max_examples=40, deadline=None)
@given(two_tasks())
def test_secondary_leaves_primary_first_order_error_unchanged(case):
    """J1 delta = J1 J1+ e1 exactly (any damping): the secondary adds nothing J1 can see."""
    J1, e1, J2, e2, lam = case
    delta = np.asarray(ik.priority_step(J1, e1, J2, e2, lam))
    assert np.all(np.isfinite(delta))
    np.testing.assert_allclose(J1 @ delta, J1 @ primary_only(J1, e1, lam), atol=1e-9 * (1 + np.abs(e1).max()))


@settings(max_examples=40, deadline=None)
@given(two_tasks())
def test_correction_lies_in_primary_null_space(case):
    J1, e1, J2, e2, lam = case
    correction = np.asarray(ik.priority_step(J1, e1, J2, e2, lam)) - primary_only(J1, e1, lam)
    N = np.asarray(ik.null_projector(J1))
    np.testing.assert_allclose(N @ correction, correction, atol=1e-9)
    np.testing.assert_allclose(J1 @ N, 0.0, atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(two_tasks())
def test_undamped_compatible_tasks_give_the_stacked_minimum_norm_solution(case):
    """lambda = 0 and [J1; J2] of full row rank: both tasks are met exactly, with the least motion."""
    J1, e1, J2, e2, _ = case
    stacked = np.vstack([J1, J2])
    if stacked.shape[0] > stacked.shape[1] or np.linalg.svd(stacked, compute_uv=False).min() < 1e-3:
        return  # not full row rank: the tasks conflict, checked elsewhere
    delta = np.asarray(ik.priority_step(J1, e1, J2, e2, 0.0))
    np.testing.assert_allclose(J1 @ delta, e1, atol=1e-8)
    np.testing.assert_allclose(J2 @ delta, e2, atol=1e-8)
    np.testing.assert_allclose(delta, np.linalg.pinv(stacked) @ np.append(e1, e2), atol=1e-8)


def test_conflicting_secondary_is_sacrificed():
    """Both tasks pull the same joint different ways: the primary wins, the secondary gets nothing."""
    J1 = np.array([[1.0, 0.0]])
    J2 = np.array([[1.0, 0.0]])
    delta = np.asarray(ik.priority_step(J1, [1.0], J2, [-5.0], 0.0))
    np.testing.assert_allclose(delta, [1.0, 0.0], atol=1e-12)


def test_partial_conflict_uses_the_remaining_freedom():
    """Secondary wants x2 = 1 and x1 = -1: only the part along the free joint is served."""
    J1 = np.array([[1.0, 0.0, 0.0]])
    J2 = np.array([[1.0, 1.0, 0.0]])
    delta = np.asarray(ik.priority_step(J1, [0.5], J2, [2.0], 0.0))
    np.testing.assert_allclose(delta, [0.5, 1.5, 0.0], atol=1e-12)


def test_singular_jacobians_stay_finite():
    """A zero J1 (every direction singular) and a rank-one J2: damped and undamped are finite."""
    for lam in (0.0, 0.1):
        delta = np.asarray(ik.priority_step(np.zeros((2, 3)), [1.0, 1.0], [[1.0, 1.0, 0.0]], [1.0], lam))
        assert np.all(np.isfinite(delta))
        # a zero primary leaves all freedom to the secondary
        np.testing.assert_allclose([1.0, 1.0, 0.0] @ delta, 2 / (2 + lam**2), atol=1e-12)


def test_damping_shrinks_the_step_near_a_singular_primary():
    J1 = np.array([[1e-6, 0.0]])
    undamped = np.asarray(ik.priority_step(J1, [1.0], [[0.0, 1.0]], [0.0], 0.0))
    damped = np.asarray(ik.priority_step(J1, [1.0], [[0.0, 1.0]], [0.0], 0.1))
    assert abs(undamped[0]) > 1e5 and abs(damped[0]) < 1e-3


def test_multilevel_with_two_levels_is_the_priority_step():
    rng = np.random.default_rng(3)
    J1, J2, e1, e2 = rng.normal(size=(2, 6)), rng.normal(size=(3, 6)), rng.normal(size=2), rng.normal(size=3)
    np.testing.assert_allclose(ik.core.priority.multilevel_step([(J1, e1), (J2, e2)], 0.2),
                               ik.priority_step(J1, e1, J2, e2, 0.2), atol=1e-12)


def test_third_level_does_not_disturb_the_first_two():
    rng = np.random.default_rng(4)
    J1, J2, J3 = rng.normal(size=(2, 7)), rng.normal(size=(2, 7)), np.eye(7)
    e1, e2, e3 = rng.normal(size=2), rng.normal(size=2), rng.normal(size=7)
    two = np.asarray(ik.core.priority.multilevel_step([(J1, e1), (J2, e2)], 0.0))
    three = np.asarray(ik.core.priority.multilevel_step([(J1, e1), (J2, e2), (J3, e3)], 0.0))
    np.testing.assert_allclose(J1 @ three, J1 @ two, atol=1e-10)
    np.testing.assert_allclose(J2 @ three, J2 @ two, atol=1e-10)
    assert not np.allclose(three, two)


@pytest.mark.parametrize("args, name", [
    ((np.ones((2, 3)), np.ones(2), np.ones((1, 4)), np.ones(1), 0.1), "J2"),
    ((np.ones((2, 3)), np.ones(3), np.ones((1, 3)), np.ones(1), 0.1), "e1"),
    ((np.ones((2, 3)), np.ones(2), np.ones((1, 3)), np.ones(2), 0.1), "e2"),
    ((np.ones(3), np.ones(2), np.ones((1, 3)), np.ones(1), 0.1), "J1"),
    ((np.ones((2, 3)), np.ones(2), np.ones((1, 3)), np.ones(1), -0.1), "damping"),
    ((np.ones((2, 3)), [np.nan, 1.0], np.ones((1, 3)), np.ones(1), 0.1), "e1"),
    ((np.ones((2, 3)), np.ones(2), [[np.inf, 0, 0]], np.ones(1), 0.1), "J2"),
    ((np.ones((2, 3)), np.ones(2), np.ones((1, 3)), np.ones(1), "big"), "damping"),
])
def test_bad_input_names_the_parameter(args, name):
    with pytest.raises(ValueError, match=f"^{name}:"):
        ik.priority_step(*args)


def test_works_under_jit():
    import jax
    rng = np.random.default_rng(5)
    J1, J2, e1, e2 = rng.normal(size=(2, 5)), rng.normal(size=(2, 5)), rng.normal(size=2), rng.normal(size=2)
    jitted = jax.jit(ik.priority_step)(J1, e1, J2, e2, 0.1)
    np.testing.assert_allclose(jitted, ik.priority_step(J1, e1, J2, e2, 0.1), atol=1e-12)
