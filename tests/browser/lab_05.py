"""A real browser drives JupyterLab through notebook 05: run all, drag the demo, play an animation.

Run with `make test-browser` (it installs Debian's chromium + chromium-driver and selenium);
not collected by `make test` (the file name does not start with test_). Selenium drives
/usr/bin/chromium through /usr/bin/chromedriver: nothing is downloaded at run time.
Screenshots (1280x720) go to $BROWSER_SHOTS (default /tmp/ikteach-browser).
"""
import os
import re
from pathlib import Path

import pytest

pytest.importorskip("selenium.webdriver")
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402

from ikteach.pictures.demo import PRESETS  # noqa: E402
from labdriver import (HEIGHT, ROOT, WIDTH, chromium, code_cell_count,  # noqa: E402
                       jupyterlab, run_all, wait_until as _wait_until)

NOTEBOOK = "05_singularities_out_of_reach.ipynb"
SHOTS = Path(os.environ.get("BROWSER_SHOTS", "/tmp/ikteach-browser"))
RUN_ALL_TIMEOUT = 600  # s: the whole notebook on a busy 2-core machine


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """JupyterLab on a free port with a token, serving a copy of notebook 05 (never the repo's)."""
    with jupyterlab(tmp_path_factory.mktemp("lab"), [ROOT / "notebooks" / NOTEBOOK]) as url:
        yield url


@pytest.fixture(scope="module")
def browser():
    SHOTS.mkdir(parents=True, exist_ok=True)
    for stale in (*SHOTS.glob("failed-*"), *SHOTS.glob("demo*.png"), *SHOTS.glob("animation*.png")):
        stale.unlink()
    with chromium() as driver:
        yield driver


def _shot(driver, name):
    driver.save_screenshot(str(SHOTS / f"{name}.png"))


def _js(driver, script, *args):
    return driver.execute_script(script, *args)


@pytest.fixture(scope="module")
def notebook(lab, browser):
    """Notebook 05 open in JupyterLab, all cells run, and every change the cells made to the
    demo drawn: a cell's prompt is numbered on the kernel's reply, while the demo's picture is
    drawn from widget messages that may still be on their way (the last cell sets each preset in
    turn): a picture found before they land is replaced under the test (a stale element)."""
    try:
        _run_all(lab, browser)
        last = _wait_until(lambda: _printed_last(browser), 60, "the presets cell's output")
        _wait_settled(browser, f"the demo to show the last preset ({last})",
                      lambda state: state["status"] == last)
        return browser
    except Exception:
        _shot(browser, "failed-run-all")
        raise


def _printed_last(driver):
    """The demo's status line for the last preset, as the presets cell printed it."""
    text = _js(driver, "const cell = [...document.querySelectorAll('.jp-CodeCell')]"
                       ".find(c => c.innerText.includes('demo.preset.value = preset'));"
                       " const out = cell && cell.querySelector('.jp-OutputArea-output"
                       "[data-mime-type=\"application/vnd.jupyter.stdout\"]');"
                       " return out ? out.innerText : ''")
    lines = text.strip().splitlines()
    return len(lines) == len(PRESETS) and lines[-1].split(": ", 1)[1].strip()


def _run_all(lab, browser):
    run_all(browser, lab, NOTEBOOK, code_cell_count(ROOT / "notebooks" / NOTEBOOK), RUN_ALL_TIMEOUT)
    errors = browser.find_elements(By.CSS_SELECTOR, "[data-mime-type='application/vnd.jupyter.stderr']")
    tracebacks = [e.text for e in errors if "Traceback" in e.text or "Error" in e.text]
    assert not tracebacks, tracebacks[0][:2000]
    return browser


PICTURE = ".widget-html svg[role=img]"  # the demo's picture (an SVG in an HTML widget)

# The demo as the page shows it now, read in one go (nothing can go stale between two reads):
# each solve replaces the picture's <svg> (the HTML widget's value is new markup), while the box,
# the status line, the sliders and the number boxes stay the same elements.
STATE = """
const svg = document.querySelector(arguments[0]);
const box = svg && svg.closest('.widget-hbox');
if (!box) return null;
const status = [...box.querySelectorAll('.widget-label')].find(l => l.innerText.includes('iterations'));
const slider = box.querySelector('.widget-slider .noUi-target');
return {picture: svg.outerHTML, name: svg.getAttribute('aria-label') || '',
        status: status ? status.innerText : '', readout: box.querySelector('input[type=number]').value,
        slider: slider && slider.noUiSlider ? String(slider.noUiSlider.get()) : null};"""


def _state(driver):
    return _js(driver, STATE, PICTURE)


def _settled(state):
    """The kernel has solved for where the x slider is, and the page shows that solve: the number
    box follows the slider, and the picture is named for that target and that status line (a
    drag sends many values; each solve redraws the picture, the last one wins)."""
    target = state and re.search(r"at \((-?[\d.]+), (-?[\d.]+)\)", state["name"])
    if not target or not state["status"] or not state["slider"] or not state["readout"]:
        return False  # not drawn yet
    x = float(state["slider"])
    return (abs(float(target[1]) - x) < 0.005 and abs(float(state["readout"]) - x) < 0.005
            and state["status"] in state["name"])


def _wait_settled(driver, what, extra=lambda state: True, timeout=60):
    return _wait_until(lambda: (lambda s: s if _settled(s) and extra(s) else None)(_state(driver)),
                       timeout, what)


def _demo(driver):
    """The demo, settled, scrolled to the top: its box, status line and x slider handle (elements
    a solve keeps; the picture, which a solve replaces, is looked up when read: _picture)."""
    try:
        _wait_settled(driver, "the demo widget, drawn for its sliders")
    except AssertionError:
        cell = _js(driver, "return [...document.querySelectorAll('.jp-CodeCell')]"
                           ".find(c => c.innerText.includes('ik.pictures.demo.Demo()'))")
        _js(driver, "arguments[0].scrollIntoView({block: 'start'})", cell)
        _shot(driver, "failed-demo")
        for error in cell.find_elements(By.CSS_SELECTOR, ".jupyter-widgets-error-widget"):
            error.click()  # shows the JavaScript error in place
        (SHOTS / "failed-demo.html").write_text(cell.get_attribute("outerHTML"))
        raise
    box = _js(driver, "const box = document.querySelector(arguments[0]).closest('.widget-hbox');"
                      " box.scrollIntoView({block: 'start'}); return box", PICTURE)
    status = next(lab for lab in box.find_elements(By.CSS_SELECTOR, ".widget-label")
                  if "iterations" in lab.text)
    handle = box.find_elements(By.CSS_SELECTOR, ".widget-slider .noUi-handle")[0]
    return box, status, handle


def _picture(box):
    return box.find_element(By.CSS_SELECTOR, PICTURE)


def _readout(box):  # the x slider's number box
    return box.find_elements(By.CSS_SELECTOR, "input[type=number]")[0].get_property("value")


def test_demo_is_crisp_and_fits_a_1280x720_screen(notebook):
    box, _, _ = _demo(notebook)
    _shot(notebook, "demo")
    tag, css_w = _js(notebook, "const p = arguments[0].querySelector(arguments[1]);"
                               " return [p.tagName, p.getBoundingClientRect().width]", box, PICTURE)
    assert css_w == 400 and tag == "svg"  # vector: sharp at any zoom
    top, bottom, right = _js(notebook, "const r = arguments[0].getBoundingClientRect();"
                                       " return [r.top, r.bottom, r.right]", box)
    panel_bottom = _js(notebook, "return document.querySelector('.jp-NotebookPanel .jp-Notebook')"
                                 ".getBoundingClientRect().bottom")
    assert 0 <= top and bottom <= panel_bottom <= HEIGHT and right <= WIDTH, (top, bottom, right)


def test_moving_the_x_slider_changes_the_status_line_and_the_image(notebook):
    box, status, handle = _demo(notebook)
    before, png = _state(notebook), _picture(box).screenshot_as_png
    ActionChains(notebook).click_and_hold(handle).move_by_offset(-90, 0).pause(0.3).release().perform()
    # the slider moved, and the page shows the kernel's solve for where it stopped
    after = _wait_settled(notebook, "the demo to show the solve for the slider's new place",
                          lambda s: s["slider"] != before["slider"])
    _shot(notebook, "demo-after-slider")
    assert after["readout"] != before["readout"]  # the number box follows the slider
    assert after["status"] != before["status"] and "iterations" in after["status"]
    assert after["picture"] != before["picture"]
    assert _picture(box).screenshot_as_png != png


def _ax(driver, expression):
    """(role, name) of the element `expression` yields, from Chromium's accessibility tree."""
    found = driver.execute_cdp_cmd("Runtime.evaluate", {"expression": expression})["result"]
    nodes = driver.execute_cdp_cmd("Accessibility.getPartialAXTree",
                                   {"objectId": found["objectId"], "fetchRelatives": False})
    node = nodes["nodes"][0]
    return node.get("role", {}).get("value"), node.get("name", {}).get("value", "")


def test_a_screen_reader_names_every_control_and_the_picture(notebook):
    _demo(notebook)
    driver = notebook
    notebook.execute_cdp_cmd("Accessibility.enable", {})
    box = f"document.querySelector('{PICTURE}').closest('.widget-hbox')"
    spins = [_ax(driver, f"{box}.querySelectorAll('input[type=number]')[{i}]") for i in range(3)]
    handles = [_ax(driver, f"{box}.querySelectorAll('.noUi-handle')[{i}]") for i in range(3)]
    method = _ax(driver, f"{box}.querySelector('select')")
    buttons = [_ax(driver, f"{box}.querySelectorAll('button')[{i}]") for i in range(3)]
    picture = _ax(driver, f"{box}.querySelector('svg')")
    print("\naccessibility tree:", spins, handles, method, buttons, picture[:1], picture[1][:60])
    assert spins == [("spinbutton", "target x"), ("spinbutton", "target y"),
                     ("spinbutton", "λ (dls)")]
    # ipywidgets 8.1's noUiSlider handle: role slider, no name (nothing public sets one); its
    # named number box comes just before it in the reading and tab order
    assert [role for role, _ in handles] == ["slider"] * 3
    assert method == ("combobox", "method")
    assert buttons == [("button", "reachable"), ("button", "near the edge"),
                       ("button", "unreachable")]
    assert picture[0] == "image" and picture[1].startswith("Planar 3-link arm")


def test_a_preset_button_acts_on_its_first_click(notebook):
    box, _, _ = _demo(notebook)
    button = box.find_element(By.XPATH, ".//button[normalize-space()='unreachable']")
    button.click()
    _wait_settled(notebook, "the unreachable preset to apply", lambda s: "stalled" in s["status"])
    assert _readout(box) == "3.5"


def test_the_animation_play_button_advances_frames(notebook):
    slider = _wait_until(lambda: notebook.find_elements(By.CSS_SELECTOR, "input.anim-slider"), 30,
                         "a jshtml animation")[0]
    controls = slider.find_element(By.XPATH, "./ancestor::div[contains(@class,'animation')][1]")
    _js(notebook, "arguments[0].scrollIntoView({block: 'center'})", slider)
    controls.find_element(By.CSS_SELECTOR, "button[title='First frame']").click()
    frame0 = int(slider.get_attribute("value"))
    picture = controls.find_element(By.TAG_NAME, "img").get_attribute("src")
    controls.find_element(By.CSS_SELECTOR, "button[title='Play']").click()
    _wait_until(lambda: int(slider.get_attribute("value")) > frame0, 10, "the animation to advance")
    _shot(notebook, "animation-playing")
    assert controls.find_element(By.TAG_NAME, "img").get_attribute("src") != picture


def _overflowing(driver, box):
    """Boxes inside the demo wider than they show (a horizontal scrollbar), as [scroll, client]."""
    return _js(driver, "return [arguments[0], ...arguments[0].querySelectorAll('.widget-box')]"
                       ".filter(b => b.scrollWidth > b.clientWidth + 1)"
                       ".map(b => [b.className, b.scrollWidth, b.clientWidth])", box)


def test_no_stray_scrollbar_and_the_demo_fits_at_200_percent_zoom(notebook):
    box, _, _ = _demo(notebook)
    assert not _overflowing(notebook, box)  # D6: no horizontal scrollbar at 100 %
    # 200 % zoom of a 1280x720 window: a 640x360 CSS-pixel page at 2 device pixels each
    notebook.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                             {"width": WIDTH // 2, "height": HEIGHT // 2, "deviceScaleFactor": 2,
                              "mobile": False})
    try:
        # JupyterLab lays itself out again for the narrower window (on its resize event)
        panel = _wait_until(lambda: _js(
            notebook, "const r = document.querySelector('.jp-NotebookPanel .jp-Notebook')"
                      ".getBoundingClientRect();"
                      " return window.innerWidth === arguments[0] && r.right <= arguments[0]"
                      " && r.width > 0 ? [r.left, r.right] : null", WIDTH // 2),
            30, "JupyterLab laid out at 640 px")
        left, right = _js(notebook, "const p = arguments[0].querySelector(arguments[1]);"
                                    " p.scrollIntoView({block: 'start'});"
                                    " const r = p.getBoundingClientRect(); return [r.left, r.right]",
                          box, PICTURE)
        _shot(notebook, "demo-200-percent")
        assert panel[0] <= left and right <= panel[1], (left, right, panel)  # not clipped
        assert not _overflowing(notebook, box)
    finally:
        notebook.execute_cdp_cmd("Emulation.clearDeviceMetricsOverride", {})
