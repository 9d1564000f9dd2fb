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


@pytest.mark.parametrize("label", ["DLS", "SDLS", "DLS + clamp"])
def test_several_paths_at_once_follow_each_path_as_alone(label):
    """targets (P, T, ...): every path tracked side by side in one program, the same steps as alone
    up to the last bits (vectorised arithmetic may round them differently; a chaotic run grows them)."""
    tree, kw = bt.y_tree(), bt.demo_methods("y")[label]
    paths = np.stack([bt.y_targets(t0 + bt.times(200)) for t0 in (0.0, 10.0, 20.0)])
    starts = np.random.default_rng(2).uniform(-0.1, 0.1, (3, tree.n_joints))
    both = ik.track(tree, paths, starts, **kw)
    assert both.theta.shape == (3, 201, tree.n_joints) and both.error.shape == (3, 200)
    for path, start, theta, error in zip(paths, starts, both.theta, both.error):
        alone = ik.track(tree, path, start, **kw)
        np.testing.assert_allclose(theta, alone.theta, rtol=0, atol=1e-9)
        np.testing.assert_allclose(error, alone.error, rtol=0, atol=1e-9)
    np.testing.assert_allclose(both.mean_error, both.error.mean(axis=1))
    np.testing.assert_allclose(both.jitter, [ik.core.jitter.jitter(q) for q in both.theta])
    shared = ik.track(tree, paths, starts[0], **kw)  # one start for every path
    np.testing.assert_array_equal(shared.theta[:, 0], np.broadcast_to(starts[0], (3, tree.n_joints)))


def test_paths_of_a_wrong_shape_are_named():
    tree = bt.y_tree()
    with pytest.raises(ValueError, match=r"targets: expected shape \(T, \*target\).*\(P, T, \*target\)"):
        ik.track(tree, np.zeros((2, 5, 3, 3)))
    with pytest.raises(ValueError, match="theta0"):
        ik.track(tree, np.zeros((2, 5, 2, 3)), np.zeros((3, tree.n_joints)))
