"""The solver's specialised arithmetic equals the general path it replaces: the two-row
pseudoinverse (taught in lecture 03), e and J from one walk of the chain, and refilling slots
every few steps."""
import jax
import numpy as np
import pytest

import ikteach as ik
from ikteach._runtime import engine as batch
from ikteach.core.problem import Problem
from ikteach.core.tasks import PositionTask

RNG = np.random.default_rng(11)


def test_dls_step_equals_the_normal_equations():
    for lengths in ([1.0, 1.0, 1.0], [0.5, 1.2, 0.3, 0.9]):  # m = 2
        arm = ik.planar_chain(lengths)
        J = ik.jacobian(arm, RNG.normal(size=len(lengths)))
        e = RNG.normal(size=2)
        np.testing.assert_allclose(ik.dls_step(J, e, 0.5), ik.dls_step_normal(J, e, 0.5),
                                   atol=1e-12)
    J = np.asarray(ik.jacobian(ik.core.robots.ur5(), RNG.normal(size=6)))  # m = 3
    e = RNG.normal(size=3)
    np.testing.assert_allclose(ik.dls_step(J, e, 0.3), ik.dls_step_normal(J, e, 0.3), atol=1e-12)


@pytest.mark.parametrize("arm", [ik.planar_chain([1.0, 0.7, 0.4], base=(0.2, -0.1)), ik.core.robots.ur5()],
                         ids=["planar", "ur5"])
def test_one_walk_of_the_chain_gives_the_same_e_and_J_as_two(arm):
    task = PositionTask()
    for _ in range(5):
        theta = RNG.normal(scale=2.0, size=arm.n_joints)
        target = RNG.normal(size=arm.dim)
        e, J = jax.jit(lambda q: Problem(task, arm, target).error_and_jacobian(q))(theta)
        np.testing.assert_allclose(e, task.error(arm, target, theta), rtol=0, atol=1e-13)
        np.testing.assert_allclose(J, task.jacobian(arm, theta), rtol=0, atol=1e-13)


@pytest.mark.parametrize("steps", [1, 3])
def test_refilling_every_few_steps_changes_no_result(monkeypatch, steps):
    arm = ik.planar_chain([1.0, 1.0, 1.0])
    targets = RNG.uniform(-3.3, 3.3, size=(300, 2))
    kw = dict(method="dls", tol=1e-3, max_iter=60)
    default = ik.solve_batch(arm, targets, [0.3, 0.3, 0.3], **kw)
    monkeypatch.setattr(batch, "STEPS_PER_REFILL", steps)
    monkeypatch.setattr(batch, "SLOTS", 64)  # far fewer slots than targets: many refills
    batch._run_queue.clear_cache()
    other = ik.solve_batch(arm, targets, [0.3, 0.3, 0.3], **kw)
    batch._run_queue.clear_cache()
    np.testing.assert_array_equal(other.theta, default.theta)
    np.testing.assert_array_equal(other.iterations, default.iterations)
    np.testing.assert_array_equal(other.status, default.status)


def _two_row_jacobians():
    """Random 2 x n Jacobians: general, nearly rank one, badly scaled, and exactly degenerate."""
    rng = np.random.default_rng(5)
    for n in (1, 2, 3, 5, 10):
        for k in range(40):
            J = rng.normal(size=(2, n))
            if k % 3 == 1:
                J[1] = rng.uniform(-2, 2) * J[0] + 10.0 ** rng.uniform(-12, -3) * rng.normal(size=n)
            if k % 3 == 2:
                J *= 10.0 ** rng.uniform(-5, 5)
            yield J, rng.normal(size=2)
    for J in ([[0, 0, 0], [0, 0, 0]], [[1, 0, 0], [0, 0, 0]], [[0, 0, 0], [0, 2, 0]],
              [[1, 1, 0], [1, 1, 0]], [[1, 0, 0], [0, 1, 0]], [[3, 4, 0], [0, 0, 1e-9]]):
        yield np.array(J, float), np.array([1.0, -2.0])


def test_the_two_row_pseudoinverse_equals_the_svd_one():
    from ikteach.core.pinv import pinv_two_rows

    for J, e in _two_row_jacobians():
        want = np.asarray(ik.pinv_step(J, e))
        got = np.asarray(pinv_two_rows(J, e))
        np.testing.assert_allclose(got, want, rtol=1e-8, atol=1e-12 * np.abs(want).max(initial=1e-300))
        np.testing.assert_allclose(got, np.linalg.pinv(J, rcond=1e-6) @ e, rtol=1e-7,
                                   atol=1e-12 * np.abs(want).max(initial=1e-300))


@pytest.mark.parametrize("rcond", [1e-6, 0.5])
def test_the_two_row_pseudoinverse_drops_the_same_singular_values(rcond):
    from ikteach.core.pinv import pinv_two_rows

    J = np.array([[1.0, 0.0, 0.0], [0.0, 0.4, 0.0]])  # sigma 1 and 0.4
    e = np.array([1.0, 1.0])
    np.testing.assert_allclose(pinv_two_rows(J, e, rcond), ik.pinv_step(J, e, rcond), atol=1e-15)
