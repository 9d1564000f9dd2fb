"""Buss's demo settings as his Jacobian.cpp has them: soft-rescaled SDLS, the growing clamp."""
import numpy as np
import pytest

import ikteach as ik
from ikteach.core import buss_trees as bt
from ikteach.core.sdls import GAMMA_MAX


def test_the_constants_are_his():
    assert np.degrees([bt.MAX_STEP["jt"], bt.MAX_STEP["pinv"], bt.MAX_STEP["dls"]]).round(9).tolist() == [30, 5, 45]
    assert bt.DAMPING == {"y": 0.6, "double_y": 1.1, "clamped": 0.7}
    assert (bt.PINV_RCOND, bt.D_MAX, np.degrees(GAMMA_MAX)) == (0.01, 0.4, 45.0)
    assert bt.demo_methods("double_y")["DLS + clamp"]["damping"] == 0.7


def test_soft_sdls_rescales_every_direction_by_gamma_over_gamma_plus_max():
    rng = np.random.default_rng(1)
    J, e = rng.normal(size=(6, 7)), rng.normal(size=6)
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    gamma = np.asarray(ik.core.sdls.sdls_gamma(U, s, Vt, J, GAMMA_MAX, 3))
    total = np.zeros(7)
    for i in range(6):  # Jacobian.cpp's loop, written out
        w = (U[:, i] @ e) / s[i] * Vt[i]
        total += w * gamma[i] / (gamma[i] + np.max(np.abs(w)))
    big = np.max(np.abs(total))
    want = total * (GAMMA_MAX / (GAMMA_MAX + big)) if big > GAMMA_MAX else total
    np.testing.assert_allclose(ik.sdls_step(J, e, GAMMA_MAX, 3, soft=True), want, rtol=1e-10, atol=1e-14)
    assert not np.allclose(ik.sdls_step(J, e, GAMMA_MAX, 3), want)  # the paper's hard clamps differ


def test_the_clamp_grows_by_how_much_farther_the_step_left_the_effector():
    tree = bt.y_tree()
    targets = bt.y_targets(bt.times(300))
    fixed = ik.track(tree, targets, method=bt.sdls_demo, clamp=bt.D_MAX)
    grown = ik.track(tree, targets, method=bt.sdls_demo, clamp=bt.D_MAX, clamp_growth=True)
    assert not np.array_equal(fixed.theta, grown.theta)
    huge = ik.track(tree, targets, method=bt.sdls_demo, clamp=1e9, clamp_growth=True)
    free = ik.track(tree, targets, method=bt.sdls_demo)
    np.testing.assert_array_equal(huge.theta, free.theta)  # a clamp never reached changes nothing


def test_clamp_growth_needs_a_clamp_and_a_bool():
    tree, targets = bt.y_tree(), bt.y_targets(bt.times(3))
    with pytest.raises(ValueError, match="clamp_growth"):
        ik.track(tree, targets, clamp_growth=True)
    with pytest.raises(ValueError, match="clamp_growth"):
        ik.track(tree, targets, clamp=0.4, clamp_growth="yes")
