"""The stretched-pose linearisation predicts whether DLS stops on an out-of-reach target."""
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
    assert settle.smallest_settling_damping(ARM, 2.0, clamp=0.3) == pytest.approx(
        settle.smallest_settling_damping(ARM, 0.3))


def test_settle_takes_planar_chains_only():
    with pytest.raises(ValueError, match="arm"):
        settle.settle_factor(ik.core.robots.ur5(), 0.5, 0.5)
