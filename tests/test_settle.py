"""The stretched-pose linearisation predicts whether DLS stops on an out-of-reach target."""
import jax
import numpy as np
import pytest

import ikteach as ik
from ikteach.core import settle

ARM = ik.planar_chain([1.0, 1.0, 1.0])
START = np.array([0.1, 0.2, 0.3])


@pytest.mark.parametrize("target", [[3.2, 0.0], [3.5, 1.0], [4.0, 0.5], [5.0, 2.0]])
@pytest.mark.parametrize("clamp", [None, 0.3])
def test_prediction_matches_the_solver_away_from_the_threshold(target, clamp):
    d = np.linalg.norm(target) - 3.0
    lam_star = settle.smallest_settling_damping(ARM, d, clamp)
    for lam in (0.8 * lam_star, 1.2 * lam_star):
        res = ik.solve(ARM, target, START, method="dls", damping=lam, clamp=clamp)
        assert (res.status == "stalled") == (lam > lam_star), (target, clamp, lam, res)


def test_the_threshold_grows_with_distance_and_the_clamp_caps_it():
    lams = [settle.smallest_settling_damping(ARM, d) for d in (0.2, 0.6, 1.0, 2.0)]
    assert lams == sorted(lams)
    clamped = [settle.smallest_settling_damping(ARM, d, clamp=0.3) for d in (0.3, 0.64, 1.03, 2.39)]
    assert clamped == sorted(clamped, reverse=True)  # the clamp sees D / d of J^T e: a little less
    assert clamped[0] - clamped[-1] < 1e-3  # capped: within 0.001 of lambda*(D_max) at every d


def dls_update(q, target, damping, clamp):
    """One DLS step with Buss's clamp, the map whose derivative settle_matrix predicts."""
    e = ik.clamp_error(target - ik.fk(ARM, q), clamp)
    return q + ik.dls_step(ik.jacobian(ARM, q), e, damping)


@pytest.mark.parametrize("target", [[3.2, 0.0], [3.5, 1.0], [5.0, 2.0]])
@pytest.mark.parametrize("clamp", [None, 0.3])
def test_the_model_is_the_derivative_of_the_real_dls_step(target, clamp):
    """settle_matrix is the Jacobian of the DLS update (clamp included) at the stretched pose."""
    target = np.asarray(target)
    d, phi = np.linalg.norm(target) - 3.0, np.arctan2(target[1], target[0])
    for lam in (0.3, 0.5, 1.0):
        real = jax.jacfwd(dls_update)(np.array([phi, 0.0, 0.0]), target, lam,
                                      np.inf if clamp is None else clamp)
        np.testing.assert_allclose(real, settle.settle_matrix(ARM, d, lam, clamp), atol=1e-12)


def test_settle_takes_planar_chains_only():
    with pytest.raises(ValueError, match="arm"):
        settle.settle_factor(ik.core.robots.ur5(), 0.5, 0.5)
