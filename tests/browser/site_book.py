"""The book (make site) as a reader sees it: headless Chromium opens the home page, lecture 04
and an exercise from file:// (no server, no network needed), with no console error, the math
rendered by the site's own MathJax, and no serious or critical accessibility violation found by
axe-core (npm, node_modules/axe-core). The decks of `make slides` too: lecture 04's deck opens
with no console error and its slides fit 1280x720. Screenshots (1280x720) go to
$BROWSER_SHOTS (default /tmp/ikteach-browser)."""
import os
import time
from pathlib import Path

import pytest

from labdriver import chromium, wait_until

from ikteach.course import book, slides

ROOT = Path(__file__).resolve().parents[2]
AXE = ROOT / "node_modules" / "axe-core" / "axe.min.js"
SHOTS = Path(os.environ.get("BROWSER_SHOTS", "/tmp/ikteach-browser"))
LECTURE = "notebooks/04_damped_least_squares.html"
EXERCISE = "notebooks/exercises/04_dls_step.html"


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    return book.build(tmp_path_factory.mktemp("book") / "site")


@pytest.fixture(scope="module")
def driver():
    with chromium() as d:
        d.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                          {"width": 1280, "height": 720, "deviceScaleFactor": 1, "mobile": False})
        yield d


def open_page(driver, path):
    driver.get_log("browser")  # forget what earlier pages said
    driver.get(path.resolve().as_uri())
    wait_until(lambda: driver.execute_script("return document.readyState") == "complete",
               30, f"{path.name} loaded")


def console_errors(driver):
    return [entry["message"] for entry in driver.get_log("browser") if entry["level"] == "SEVERE"]


def math_rendered(driver):
    """(formulas typeset by MathJax, formulas it could not read)."""
    return driver.execute_script(
        "return [document.querySelectorAll('mjx-container svg').length,"
        " document.querySelectorAll('mjx-merror, [data-mjx-error]').length]")


def axe_violations(driver):
    driver.execute_script(AXE.read_text(encoding="utf-8"))
    violations = driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "axe.run(document, {resultTypes: ['violations']}).then(r => done(r.violations));")
    return [f"{v['id']} ({v['impact']}): {v['help']}, e.g. {v['nodes'][0]['html'][:120]}"
            for v in violations if v["impact"] in ("serious", "critical")]


def shoot(driver, name):
    SHOTS.mkdir(parents=True, exist_ok=True)
    driver.save_screenshot(str(SHOTS / name))


@pytest.mark.parametrize("page", ["index.html", LECTURE])
def test_page_opens_from_disk_with_no_console_error(site, driver, page):
    open_page(driver, site / page)
    time.sleep(1)
    assert console_errors(driver) == []


def test_math_is_rendered_on_lecture_04(site, driver):
    open_page(driver, site / LECTURE)
    wait_until(lambda: math_rendered(driver)[0] > 20, 60, "MathJax typeset the page")
    assert math_rendered(driver)[1] == 0
    shoot(driver, "site-lecture-04.png")


@pytest.mark.parametrize("page", ["index.html", LECTURE])
def test_no_serious_accessibility_violation(site, driver, page):
    open_page(driver, site / page)
    time.sleep(1)
    if driver.execute_script("return !!(window.MathJax && MathJax.startup)"):  # pages with math
        driver.execute_async_script("MathJax.startup.promise.then(arguments[arguments.length - 1])")
    assert axe_violations(driver) == []


def test_screenshots_of_home_and_an_exercise(site, driver):
    open_page(driver, site / "index.html")
    shoot(driver, "site-home.png")
    driver.execute_script("document.querySelector('#lectures').scrollIntoView()")
    shoot(driver, "site-home-lectures.png")
    open_page(driver, site / EXERCISE)
    shoot(driver, "site-exercise-04.png")
    assert console_errors(driver) == []


def test_lecture_04_slides_fit_and_load_nothing_else(tmp_path, driver):
    deck, = slides.build([ROOT / "notebooks" / "04_damped_least_squares.ipynb"], tmp_path)
    open_page(driver, deck)
    wait_until(lambda: driver.execute_script("return !!window.Reveal && Reveal.isReady()"),
               30, "reveal.js ready")
    driver.execute_script("Reveal.configure({transition: 'none'})")  # measure still slides
    off_screen = []
    for number, where in enumerate(driver.execute_script(
            "return Reveal.getSlides().map(s => Reveal.getIndices(s))")):
        h, v = where["h"], where["v"] or 0
        driver.execute_script(f"Reveal.slide({h}, {v});"
                              "Reveal.getCurrentSlide().querySelectorAll('.fragment')"
                              ".forEach(f => f.classList.add('visible'));")
        time.sleep(0.3)
        if (h, v) in [(1, 0), (2, 1), (4, 1)]:
            shoot(driver, f"slides-04-{h}-{v}.png")
        # every part of the slide, all fragments shown, is inside the 1280 x 720 window
        bottom, right = driver.execute_script(
            "let low = 0, far = 0; Reveal.getCurrentSlide().querySelectorAll('*').forEach(e => {"
            " const box = e.getBoundingClientRect();"
            " if (box.height) { low = Math.max(low, box.bottom); far = Math.max(far, box.right); }"
            "}); return [low, far];")
        if bottom > 722 or right > 1282:
            off_screen.append(f"slide {h}/{v}: ends at ({right:.0f}, {bottom:.0f}) px")
    assert number > 10 and off_screen == []
    assert console_errors(driver) == []
