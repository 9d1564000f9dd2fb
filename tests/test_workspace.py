"""Workspace maps: grids, boundaries against the analytic reach, tracking, image regression."""
import matplotlib
import numpy as np
import pytest

import ikteach as ik
from ikteach.pictures import workspace_maps as ws

from render_reference import MAP_ARM, MAP_PNG, map_image, read_png, ssim

# Same render: 1.0; middle link 0.5 -> 0.55: 0.89; colour map viridis -> magma: 0.76.
# matplotlib before 3.11 (make test-lowest) resamples the image a little differently: 0.946.
MAP_SSIM = 0.98 if tuple(int(v) for v in matplotlib.__version__.split(".")[:2]) >= (3, 11) else 0.92


def test_map_matches_the_reference_image():
    assert ssim(read_png(MAP_PNG), map_image()) > MAP_SSIM


def test_a_longer_link_or_other_colours_fail_the_comparison():
    ref = read_png(MAP_PNG)
    assert ssim(ref, map_image(lengths=(1.0, 0.55, 0.25))) < MAP_SSIM
    assert ssim(ref, map_image(cmap="magma")) < MAP_SSIM


def test_reach_radii():
    assert ws.reach_radii([1.0, 0.5, 0.25]) == (0.25, 1.75)
    assert ws.reach_radii([1.0, 1.0, 1.0]) == (0.0, 3.0)


def test_grid_layout_rows_are_y():
    arm = ik.planar_chain(MAP_ARM)
    g = ws.target_grid(arm, 8)
    img = g.image(g.points)
    assert img.shape == (8, 8, 2)
    assert np.all(np.diff(img[:, 0, 1]) > 0) and np.all(np.diff(img[0, :, 0]) > 0)
    with pytest.raises(ValueError, match="arm"):
        ws.target_grid(ik.core.robots.ur5(), 8)
    with pytest.raises(ValueError, match="n"):
        ws.target_grid(arm, 1)


def test_boundary_of_the_converged_set_matches_the_analytic_radii():
    arm = ik.planar_chain(MAP_ARM)
    g = ws.target_grid(arm, 96)
    m = ws.sweep(arm, g, [0.3, 0.6, 0.6], method="pinv", max_iter=30)
    radii = ws.contour_radii(ws.boundary(m.status == "converged", g))
    inner, outer = ws.reach_radii(MAP_ARM)
    pixel = g.xs[1] - g.xs[0]
    assert abs(radii[0][1] - inner) < 2 * pixel
    assert abs(radii[-1][1] - outer) < 2 * pixel


def test_boundary_of_a_disc():
    arm = ik.planar_chain([1.0])
    g = ws.target_grid(arm, 101)
    mask = g.image(np.linalg.norm(g.points, axis=1) < 0.8)
    (c,) = ws.boundary(mask, g)
    np.testing.assert_allclose(np.linalg.norm(c, axis=1), 0.8, atol=g.xs[1] - g.xs[0])


def test_horse_path_is_closed_and_fits_the_box():
    path = ws.horse_path(300, centre=(1.0, 0.0), width=1.0)
    assert path.shape == (300, 2)
    np.testing.assert_allclose(path[:, 0].max() - path[:, 0].min(), 1.0)
    np.testing.assert_allclose((path.max(0) + path.min(0)) / 2, [1.0, 0.0], atol=1e-12)
    steps = np.linalg.norm(np.diff(np.vstack([path, path[:1]]), axis=0), axis=1)
    assert steps.max() < 3 * np.median(steps)  # evenly spaced, and closed


def test_tracking_follows_a_slow_circle_and_reports_jitter():
    arm = ik.planar_chain(MAP_ARM)
    t = np.linspace(0, 2 * np.pi, 200)
    path = np.stack([1.2 + 0.2 * np.cos(t), 0.2 * np.sin(t)], axis=1)
    start = ik.solve(arm, path[0], [0.3, 0.6, 0.6], tol=1e-8, max_iter=500)
    for method in ["dls", "pinv", "jt"]:
        tr = ws.track(arm, path, start.theta, method=method, damping=0.1)
        assert tr.theta.shape == (200, 3) and np.all(np.isfinite(tr.theta))
        assert tr.error.max() < 0.02
        assert tr.jitter.shape == (198,)
    dls = ws.track(arm, path, start.theta, method="dls", damping=0.1)
    np.testing.assert_allclose(dls.error, np.linalg.norm(path - ws.end_path(arm, dls.theta), axis=1),
                               atol=1e-12)


def test_sigma_min_is_zero_when_stretched():
    arm = ik.planar_chain(MAP_ARM)
    s = ws.sigma_min(arm, np.array([[0.0, 0.0, 0.0], [0.3, 0.6, 0.6]]))
    assert s[0] < 1e-12 < s[1]
