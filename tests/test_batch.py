import numpy as np
import pytest

import ikteach as ik

ARM = ik.planar_chain([1.0, 1.0, 1.0])
START = np.array([0.1, 0.2, 0.3])


@pytest.mark.parametrize("method", ["jt", "pinv", "dls"])
def test_batch_matches_solve_target_by_target(method):
    rng = np.random.default_rng(7)
    targets = rng.uniform(-3.5, 3.5, size=(12, 2))
    batch = ik.solve_batch(ARM, targets, START, method=method, clamp=0.5, max_iter=300)
    for k, target in enumerate(targets):
        one = ik.solve(ARM, target, START, method=method, clamp=0.5, max_iter=300)
        assert batch.status[k] == one.status
        assert batch.iterations[k] == one.iterations
        np.testing.assert_allclose(batch.theta[k], one.theta, atol=1e-9)
        assert batch.error[k] == pytest.approx(one.error, abs=1e-9)


def test_batch_takes_one_start_per_target_and_counts_statuses():
    targets = np.array([[1.0, 1.0], [5.0, 0.0]])
    starts = np.array([[0.1, 0.2, 0.3], [0.3, 0.2, 0.1]])
    res = ik.solve_batch(ARM, targets, starts, clamp=0.3)
    assert len(res) == 2
    assert list(res.status) == ["converged", "stalled"]
    assert res.counts() == {"converged": 1, "stalled": 1, "max_iter": 0, "diverged": 0, "slow": 0}


def test_batch_accepts_a_jax_step_function():
    targets = np.array([[1.0, 1.0], [2.0, 0.5]])
    res = ik.solve_batch(ARM, targets, START, method=lambda J, e: ik.dls_step(J, e, 0.3))
    assert list(res.status) == ["converged", "converged"]
