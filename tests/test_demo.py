"""The interactive demo, driven without a browser through its update function."""
import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import ikteach as ik  # noqa: E402

pytest.importorskip("ipywidgets")
from ikteach import demo as ikdemo  # noqa: E402

ARM = ik.planar_chain([1.0, 1.0, 1.0])
START = np.array([0.1, 0.2, 0.3])


@pytest.fixture(scope="module")
def demo():
    return ikdemo.Demo()


def test_update_solves_like_ik_solve_and_prints_method_status_iterations(demo):
    res = demo.update(x=2.5, y=0.5, method="jt", damping=0.5)
    ref = ik.solve(ARM, [2.5, 0.5], START, method="jt", max_iter=300)
    assert (res.status, res.iterations) == (ref.status, ref.iterations)
    assert demo.text.value == demo.summary
    assert demo.summary.startswith("jt: converged after") and str(ref.iterations) in demo.summary
    assert demo.image.value[:4] == b"\x89PNG"


def test_moving_a_slider_re_solves(demo):
    demo.update(x=2.5, y=0.5, method="dls")
    before = demo.result
    demo.x.value = 1.0  # what dragging does
    assert demo.result is not before
    np.testing.assert_allclose(np.asarray(ik.fk(ARM, demo.result.theta)), [1.0, 0.5], atol=1e-3)


def test_unreachable_preset_stalls_with_dls(demo):
    demo.update(method="dls", damping=0.5)
    demo.preset.value = "unreachable"
    assert (demo.x.value, demo.y.value) == ikdemo.PRESETS["unreachable"]
    assert demo.result.status == "stalled"
    assert "stalled" in demo.summary


def test_damping_slider_changes_the_dls_solve(demo):
    a = demo.update(x=2.9, y=0.6, method="dls", damping=0.1)
    b = demo.update(damping=1.0)
    assert a.iterations != b.iterations
