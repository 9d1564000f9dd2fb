import numpy as np
import pytest

import ikteach as ik
from ikteach.pictures import live_map
from ikteach.pictures import workspace_maps as ws

ARM = ik.planar_chain([1.0, 1.0, 1.0])
GRID = ws.target_grid(ARM, 12)
START = (0.3, 0.3, 0.3)


def test_map_is_the_sweep_of_the_grid_as_an_image():
    res, img = live_map.compute_map(ARM, GRID, START, method="dls", damping=0.3, max_iter=50)
    batch = ik.solve_batch(ARM, GRID.points, START, method="dls", damping=0.3, max_iter=50)
    assert img.shape == (12, 12)
    np.testing.assert_array_equal(img.ravel(), batch.iterations)
    assert res.counts() == batch.counts()


def test_error_and_status_pictures():
    res, err = live_map.compute_map(ARM, GRID, START, quantity="error", max_iter=50)
    np.testing.assert_allclose(10**err, np.maximum(res.error, 1e-16))
    _, rgb = live_map.compute_map(ARM, GRID, START, quantity="status", max_iter=50)
    assert rgb.shape == (12, 12, 3)
    far = GRID.image(np.linalg.norm(GRID.points, axis=1)) > 3.05  # out of reach: never converged
    assert not np.any(np.all(rgb[far] == np.array([0x55, 0xA8, 0x68]) / 255, axis=-1))


def test_an_unknown_quantity_is_a_value_error():
    with pytest.raises(ValueError, match="quantity"):
        live_map.compute_map(ARM, GRID, START, quantity="speed", max_iter=5)


def test_live_map_recomputes_on_a_new_lambda_and_keeps_a_png():
    live = live_map.LiveMap(ARM, grid_n=12, max_iter=50)
    assert live.png.startswith(b"\x89PNG")
    before = live.result.iterations.copy()
    live.damping.value = 0.05  # what the slider does
    assert live.summary.startswith("dls, λ = 0.05")
    assert not np.array_equal(live.result.iterations, before)
    live.update(method="jt", quantity="status")
    assert live.result.method == "jt"
    assert ik.live_map is live_map  # lazy attribute of the package
