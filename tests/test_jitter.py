import numpy as np
import pytest

import ikteach as ik


def test_steady_motion_has_no_jitter_and_a_reversal_counts_every_joint():
    steady = np.outer(np.arange(6), [0.1, -0.2, 0.3])
    assert ik.core.jitter.jitter(steady) == pytest.approx(0.0, abs=1e-12)
    zigzag = np.array([[0.0, 0.0], [1.0, -1.0], [0.0, 0.0]])
    np.testing.assert_allclose(ik.core.jitter.jitter_per_step(zigzag), [4.0])  # |0 - 2 + 0| + |0 + 2 + 0|


def test_tracking_and_the_maps_use_the_same_jitter():
    arm = ik.planar_chain([1.0, 1.0, 1.0])
    path = np.stack([2.0 + 0.3 * np.cos(np.linspace(0, 6, 40)), 0.3 * np.sin(np.linspace(0, 6, 40))], 1)
    res = ik.track(arm, path, np.array([0.1, 0.2, 0.3]), method="dls", damping=0.1)
    assert res.jitter == pytest.approx(ik.core.jitter.jitter(res.theta))
    tr = ik.pictures.workspace_maps.track(arm, path, np.array([0.1, 0.2, 0.3]), method="dls", damping=0.1)
    np.testing.assert_allclose(tr.jitter, ik.core.jitter.jitter_per_step(tr.theta))


def test_jitter_names_a_bad_shape():
    with pytest.raises(ValueError, match="theta"):
        ik.core.jitter.jitter(np.zeros(5))
