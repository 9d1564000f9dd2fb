import html

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


def test_every_status_has_its_own_colour_and_a_word_in_the_live_legend():
    finished = ik.STATUSES[1:]  # every status a solve can end with ("running" never does)
    assert ik.STATUSES[0] == "running"
    assert set(ws.STATUS_COLORS) == set(ws.STATUS_COLOR_NAMES) == set(finished)
    assert len(set(ws.STATUS_COLORS.values())) == len(finished)  # none drawn like another
    status = np.array([finished, finished])
    rgb = ws.status_image(status)
    assert not np.any(np.all(rgb == 1.0, axis=-1))  # white only where no target is
    legend = " ".join(live_map._label("status", 100).split())
    assert all(f"{ws.STATUS_COLOR_NAMES[s]} {s}" in legend for s in finished)


def test_the_live_map_counts_are_the_batch_solves_at_the_default_tol():
    arm = ik.planar_chain([1.0, 0.5, 0.25])  # L/3000 = 5.8e-4, not 1e-3
    live = live_map.LiveMap(arm, grid_n=12, max_iter=50, damping=0.2, prefetch=False)
    batch = ik.solve_batch(arm, live.grid.points, live.theta0, method="dls", damping=0.2, max_iter=50)
    assert live.result.counts() == batch.counts()
    np.testing.assert_array_equal(live.result.iterations.ravel(), batch.iterations)
    at_1e3 = ik.solve_batch(arm, live.grid.points, live.theta0, method="dls", damping=0.2,
                            max_iter=50, tol=1e-3)
    assert not np.array_equal(live.result.iterations.ravel(), at_1e3.iterations)


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
    assert ik.pictures.live_map is live_map  # lazy attribute of the package


@pytest.fixture
def counted(monkeypatch):
    """LiveMap on a small grid, counting the grid solves it runs."""
    calls = []
    real = live_map.sweep

    def sweep(*args, **kwargs):
        calls.append(kwargs["method"])
        return real(*args, **kwargs)

    monkeypatch.setattr(live_map, "sweep", sweep)
    return live_map.LiveMap(ARM, grid_n=12, max_iter=50, prefetch=False), calls


def test_lambda_under_jt_and_a_new_quantity_re_solve_nothing(counted):
    live, calls = counted
    live.update(method="jt")
    jt = live.result
    assert calls == ["dls", "jt"]
    live.damping.value = 1.3  # JT ignores lambda: the same map, redrawn
    live.update(quantity="status")
    assert calls == ["dls", "jt"] and live.result is jt
    assert "no λ" in live.summary
    live.update(method="dls", damping=0.5)  # the first map: kept
    assert calls == ["dls", "jt"]
    live.damping.value = 0.1  # dls with a new lambda: solved
    assert calls == ["dls", "jt", "dls"]


def test_the_maps_one_step_either_side_are_prefetched_and_a_step_solves_nothing(monkeypatch):
    calls = []
    real = live_map.sweep

    def sweep(*args, **kwargs):
        calls.append((kwargs["method"], kwargs["damping"]))
        return real(*args, **kwargs)

    monkeypatch.setattr(live_map, "sweep", sweep)
    live = live_map.LiveMap(ARM, grid_n=12, max_iter=50, damping=0.5)
    assert calls == [("dls", 0.5)]  # displayed only (a Run All): nothing prefetched
    live.damping.value = 0.55  # a move: solved, then 0.6 prefetched (0.5 is kept)
    live._maps[("dls", 0.6)].result()  # the background thread solved it
    assert calls == [("dls", 0.5), ("dls", 0.55), ("dls", 0.6)]
    live.damping.value = 0.6  # one step: solved already
    assert calls.count(("dls", 0.6)) == 1
    ref = real(ARM, live.grid, live.theta0, method="dls", damping=0.6, max_iter=50)
    np.testing.assert_array_equal(live.result.iterations, ref.iterations)
    live.method.value = "jt"  # lambda unused: nothing prefetched
    live.damping.value = 1.0
    assert [c for c in calls if c[0] == "jt"] == [("jt", 0.6)]


def test_the_map_has_a_fixed_css_size_rendered_at_hidpi_and_a_still():
    import base64
    import io

    from PIL import Image

    live = live_map.LiveMap(ARM, grid_n=12, max_iter=50)
    assert Image.open(io.BytesIO(live.png)).size == (live_map.HIDPI * live_map.SIZE,) * 2
    # a fixed width (never stretched to the page), at most the page's width
    assert live.image.layout.width == f"{live_map.SIZE}px"
    assert live.image.layout.max_width == "calc(100% - 4px)"
    data, meta = live.widget._repr_mimebundle_()
    assert "application/vnd.jupyter.widget-view+json" in data
    assert base64.b64decode(data["image/png"]) == live.png
    assert meta["image/png"]["alt"] == live.alt and not live.image.tooltip  # see test_demo
    # the browser's picture: an <img> with the alt text (an Image widget has no alt)
    assert live.image.value.startswith("<img") and f'alt="{html.escape(live.alt)}"' in live.image.value
    assert base64.b64encode(live.png).decode() in live.image.value
    assert "Workspace map" in live.alt and live.summary in live.alt
    assert 'alt="Workspace map' in data["text/html"]
    for control in (live.method, live.quantity):
        assert control.description.strip()
    number, slider = live.widget.children[0].children[0].children  # the lambda row
    assert slider is live.damping and number.description == "λ (dls)"
