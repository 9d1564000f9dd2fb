"""The decks of `make slides` in headless Chromium at 1280 x 720, from file://: every slide, all
its fragments shown, at 75 % of its size or more (slides_template shrinks one that overflows),
nothing inside the window's edges cut off and no output hidden in a scroll box; the first slide
links the notebook live (Colab, Binder, `make lab`); no console error. Screenshots of three
slides of lecture 04 go to $BROWSER_SHOTS (default /tmp/ikteach-browser).

`-m smoke` (CI) checks lecture 04's deck."""
import os
from pathlib import Path

import pytest

from labdriver import wait_until

ROOT = Path(__file__).resolve().parents[2]
SHOTS = Path(os.environ.get("BROWSER_SHOTS", "/tmp/ikteach-browser"))
LECTURES = sorted((ROOT / "notebooks").glob("*.ipynb"))
SMOKE = "04_damped_least_squares"
MIN_SCALE = 0.75

MEASURE = """
const slide = Reveal.getCurrentSlide();
const scale = slide.style.transform.match(/scale\\(([\\d.]+)\\)/);
const hidden = [];
slide.querySelectorAll('*').forEach(e => {
  const style = getComputedStyle(e);
  if (/(auto|scroll)/.test(style.overflowY + style.overflowX) && !e.closest('mjx-container')
      && (e.scrollHeight > e.clientHeight + 4 || e.scrollWidth > e.clientWidth + 4)
      && e.clientHeight > 0)
    hidden.push(e.tagName + '.' + e.className + ': ' + e.innerText.slice(0, 60));
});
let low = 0, far = 0;
slide.querySelectorAll('*').forEach(e => {
  const box = e.getBoundingClientRect();
  if (box.height) { low = Math.max(low, box.bottom); far = Math.max(far, box.right); }
});
return [scale ? parseFloat(scale[1]) : 1, hidden, low, far];"""


@pytest.fixture(scope="module")
def decks(site):
    """The book's decks (make site builds them into build/site/slides)."""
    return {path.stem: site / "slides" / f"{path.stem}.slides.html" for path in LECTURES}


@pytest.fixture(scope="module")
def driver(book_browser):
    book_browser.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                                 {"width": 1280, "height": 720, "deviceScaleFactor": 1,
                                  "mobile": False})
    return book_browser


def open_deck(driver, deck):
    driver.get_log("browser")
    driver.get(deck.as_uri())
    wait_until(lambda: driver.execute_script("return !!window.Reveal && Reveal.isReady()"),
               30, "reveal.js ready")
    driver.execute_async_script("MathJax.startup.promise.then(arguments[arguments.length - 1])")
    driver.execute_script("Reveal.configure({transition: 'none'})")  # measure still slides


def check_deck(driver, deck, shots=()):
    """Problems found on every slide of a deck (all fragments shown)."""
    open_deck(driver, deck)
    problems = []
    first = driver.execute_script("return Reveal.getSlides()[0].innerText")
    for needed in ("Colab", "Binder", "make lab"):
        if needed not in first:
            problems.append(f"the first slide does not say {needed!r}")
    indices = driver.execute_script("return Reveal.getSlides().map(s => Reveal.getIndices(s))")
    for where in indices:
        h, v = where["h"], where["v"] or 0
        # reveal.js moves to the slide and lays it out (the deck's shrink-to-fit too) before
        # Reveal.slide returns (no transition); the fragments only fade in: measured at once
        scale, hidden, bottom, right = driver.execute_script(
            f"Reveal.slide({h}, {v});"
            "Reveal.getCurrentSlide().querySelectorAll('.fragment')"
            ".forEach(f => f.classList.add('visible'));"
            "Reveal.layout();" + MEASURE)
        if scale < MIN_SCALE:
            problems.append(f"slide {h}/{v}: shrunk to {scale:.0%}")
        if hidden:
            problems.append(f"slide {h}/{v}: hidden in a scroll box: {hidden[:1]}")
        if bottom > 722 or right > 1282:
            problems.append(f"slide {h}/{v}: ends at ({right:.0f}, {bottom:.0f}) px")
        if (h, v) in shots:
            SHOTS.mkdir(parents=True, exist_ok=True)
            driver.save_screenshot(str(SHOTS / f"slides-{deck.name.split('.')[0]}-{h}-{v}.png"))
    errors = [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    return problems + [f"console: {e}" for e in errors], len(indices)


@pytest.mark.smoke
def test_lecture_04_deck_reads_in_a_hall(decks, driver):
    problems, count = check_deck(driver, decks[SMOKE], shots=[(0, 0), (2, 1), (4, 1)])
    assert count > 10 and problems == []


@pytest.mark.parametrize("name", [p.stem for p in LECTURES if p.stem != SMOKE])
def test_every_deck_reads_in_a_hall(decks, driver, name):
    problems, count = check_deck(driver, decks[name])
    assert count > 5 and problems == []


def test_the_index_lists_every_deck(decks, driver):
    index = next(iter(decks.values())).parent / "index.html"
    driver.get(index.as_uri())
    assert driver.execute_script("return document.querySelector('a[href=\"../index.html\"]') !== null")
    links = driver.execute_script("return [...document.querySelectorAll('a')].map(a => a.href)")
    for deck in decks.values():
        assert deck.as_uri() in links, deck.name
