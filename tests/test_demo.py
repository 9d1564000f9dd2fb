"""The interactive demo, driven without a browser through its update function."""
import matplotlib

matplotlib.use("Agg")

import base64  # noqa: E402
import html  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import ikteach as ik  # noqa: E402

pytest.importorskip("ipywidgets")
from ikteach.pictures import demo as ikdemo  # noqa: E402

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
    assert demo.image.value == demo.svg and demo.svg.startswith("<svg")


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


def test_a_preset_button_acts_on_every_click_even_the_same_one_twice(demo):
    unreachable = next(b for b in demo.preset.children if b.description == "unreachable")
    unreachable.click()
    assert (demo.x.value, demo.y.value) == ikdemo.PRESETS["unreachable"]
    demo.update(x=1.0, y=1.0)
    unreachable.click()  # the last preset chosen, clicked again: still applies
    assert (demo.x.value, demo.y.value) == ikdemo.PRESETS["unreachable"]
    assert demo.result.status == "stalled"


def test_an_unknown_preset_name_is_a_value_error_naming_the_presets(demo):
    with pytest.raises(ValueError, match="preset must be one of"):
        demo.preset.value = "far away"


def test_the_still_is_rendered_at_twice_its_css_size_and_changes_with_the_target(demo):
    from PIL import Image
    import io

    demo.update(x=2.5, y=0.5, method="dls")
    before = demo.png
    image = Image.open(io.BytesIO(before))
    assert image.size == (ikdemo.HIDPI * ikdemo.SIZE,) * 2
    assert demo.image.layout.width == f"{ikdemo.SIZE}px"
    demo.update(x=1.0, y=1.5)
    assert demo.png != before
    assert "(1.00, 1.50)" in demo.alt and demo.summary in demo.alt


def test_the_live_picture_is_an_svg_of_the_solved_arm_named_by_its_alt_text(demo):
    import xml.etree.ElementTree as ET

    res = demo.update(x=1.0, y=1.5, method="pinv")
    svg = ET.fromstring(demo.image.value)
    ns = "{http://www.w3.org/2000/svg}"
    assert svg.get("role") == "img" and svg.get("aria-label") == demo.alt
    assert svg.find(f"{ns}title").text == demo.alt
    # the arm: a polyline in the method's colour from the base (the picture's centre) to the
    # end effector, |F(theta)| from the base at the picture's scale (98 % of SIZE is 2.6 reach)
    arm = [p for p in svg.iter(f"{ns}polyline") if p.get("stroke") == "#d62728"]
    assert len(arm) == 1
    points = np.array([xy.split(",") for xy in arm[0].get("points").split()], dtype=float)
    assert len(points) == ARM.n_joints + 1
    np.testing.assert_allclose(points[0], [ikdemo.SIZE / 2] * 2, atol=0.06)
    scale = 0.98 * ikdemo.SIZE / (2 * 1.3 * 3.0)
    end = np.asarray(ik.fk(ARM, res.theta))[:2]
    np.testing.assert_allclose(points[-1], [200 + end[0] * scale, 200 - end[1] * scale], atol=0.06)
    assert len(demo.svg) < 8000  # a few kB per move, not a PNG


def test_png_writer_round_trips_pixels():
    from PIL import Image
    import io

    rgba = np.random.default_rng(0).integers(0, 256, (7, 5, 4), dtype=np.uint8)
    back = np.asarray(Image.open(io.BytesIO(ikdemo.png(rgba))).convert("RGB"))
    np.testing.assert_array_equal(back, rgba[..., :3])


def test_displayed_widget_carries_a_still_for_static_pages(demo):
    demo.update(x=2.9, y=0.6, method="pinv")
    data, meta = demo.widget._repr_mimebundle_()
    assert "application/vnd.jupyter.widget-view+json" in data  # live: the widget
    assert data["text/plain"] == demo.summary                  # static: image + status line
    assert base64.b64decode(data["image/png"]) == demo.png
    assert meta["image/png"]["width"] == ikdemo.SIZE
    page = data["text/html"]
    assert f'alt="{html.escape(demo.alt)}"' in page and html.escape(demo.summary) in page


def test_padded_repeats_the_last_row():
    out = ikdemo.padded(np.arange(6.0).reshape(3, 2), 5)
    np.testing.assert_array_equal(out, [[0, 1], [2, 3], [4, 5], [4, 5], [4, 5]])


# what each preset is for, with the demo's defaults (dls, lambda 0.5): lectures 04 and 05
PRESET_STATUS = {"reachable": "converged", "near the edge": "converged", "unreachable": "stalled"}


@pytest.mark.parametrize("name", list(ikdemo.PRESETS))
def test_each_preset_lies_on_the_slider_grid_and_shows_what_it_was_chosen_for(demo, name):
    demo.update(method="dls", damping=0.5)
    for v in ikdemo.PRESETS[name]:  # where the browser's slider snaps it: min + k * step
        snapped = demo.x.min + round((v - demo.x.min) / demo.x.step) * demo.x.step
        assert abs(snapped - v) < 1e-9, (name, v, snapped)
    demo.preset.value = name
    assert (demo.x.value, demo.y.value) == ikdemo.PRESETS[name]
    assert demo.result.status == PRESET_STATUS[name]
    ref = ik.solve(ARM, ikdemo.PRESETS[name], START, method="dls", damping=0.5, max_iter=300)
    assert (demo.result.status, demo.result.iterations) == (ref.status, ref.iterations)


def test_a_browser_echo_of_the_same_value_re_solves_nothing(demo):
    demo.preset.value = "near the edge"
    solved = demo.result
    demo.x.value = ikdemo.PRESETS["near the edge"][0] + 4e-16  # the slider's float, sent back
    assert demo.result is solved
    demo.x.value = 2.5  # a real move still re-solves
    assert demo.result is not solved


def test_targets_given_off_the_grid_are_rounded_to_it_like_the_slider(demo):
    demo.update(x=2.987, y=0.4449)
    assert (demo.x.value, demo.y.value) == (2.99, 0.44)


def test_every_control_has_a_label_a_screen_reader_reads(demo):
    import ipywidgets as w

    demo.update(x=1.0, y=1.5)
    for control in (demo.method, *demo.preset.children):  # <select> with <label for>; buttons
        assert control.description.strip()
    rows = demo.widget.children[1].children[:3]
    for row, (name, label) in zip(rows, demo.labels.items()):
        number, slider = row.children
        assert slider is getattr(demo, name) and not slider.readout
        # the number box carries the label (<label for> its <input>) and follows the slider
        assert isinstance(number, w.BoundedFloatText) and number.description == label
        assert (number.min, number.max, number.step) == (slider.min, slider.max, slider.step)
        assert (row.link.source, row.link.target) == ((slider, "value"), (number, "value"))
    demo.x.value = 3.5000000000000013  # as the browser's slider sends it: the box shows 3.5
    assert rows[0].children[0].value == 3.5
    rows[1].children[0].value = 0.25  # typed into the box: the slider moves, the demo solves
    assert demo.y.value == 0.25 and "(3.50, 0.25)" in demo.alt
