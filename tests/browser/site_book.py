"""The book (make site) as a reader sees it, in headless Chromium from file:// (no server, no
network): every page at a phone's width (375 px) and a laptop's (1280 px) with its math typeset
(no raw TeX, no MathJax error), no console error, no serious or critical accessibility violation
found by axe-core (npm, node_modules/axe-core), no heading larger than one of higher rank,
nothing wider than the screen and no word in a table wider than its cell; the menu and
the page's contents open at 375, 768 and 1280 px; search finds pages with no console error from
disk, and with snippets when served. Screenshots go to $BROWSER_SHOTS (default
/tmp/ikteach-browser). The decks are tests/browser/site_slides.py.

`-m smoke` (CI, .ci/run) keeps the per-page checks and the menus."""
import http.server
import os
import threading
import time
from functools import partial
from pathlib import Path

import pytest

from labdriver import chromium, wait_until

ROOT = Path(__file__).resolve().parents[2]
AXE = ROOT / "node_modules" / "axe-core" / "axe.min.js"
SHOTS = Path(os.environ.get("BROWSER_SHOTS", "/tmp/ikteach-browser"))
WIDTHS = {"phone": (375, 812), "tablet": (768, 1024), "laptop": (1280, 720)}
SHOT_PAGES = {"index.html": "home", "notebooks/04_damped_least_squares.html": "04",
              "notebooks/08_methods_compared.html": "08",
              "notebooks/exercises/04_dls_step.html": "exercise-04"}

# TeX left as text: a $ or a \command in what the page shows, outside typeset math and code.
RAW_TEX = """
const skip = "mjx-container, pre, code, script, style, textarea, .MathJax";
const walker = document.createTreeWalker(document.querySelector("main") || document.body,
                                         NodeFilter.SHOW_TEXT);
const found = [];
for (let node = walker.nextNode(); node; node = walker.nextNode()) {
  const parent = node.parentElement;
  if (!parent || parent.closest(skip) || !parent.getClientRects().length) continue;
  const match = node.textContent.match(/.{0,30}(\\$|\\\\[a-zA-Z]+).{0,30}/);
  if (match) found.push(match[0]);
}
return found;"""


def site_pages(site):
    return sorted(p.relative_to(site).as_posix() for p in site.rglob("*.html")
                  if not {"_static", "slides"} & set(p.relative_to(site).parts))


@pytest.fixture(scope="module")
def driver(book_browser):
    return book_browser


@pytest.fixture(scope="module")
def second_browser():
    with chromium() as d:
        yield d


def use_width(driver, name):
    width, height = WIDTHS[name]
    driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                           {"width": width, "height": height, "deviceScaleFactor": 1,
                            "mobile": width < 500})


def open_page(driver, url):
    driver.get_log("browser")  # forget what earlier pages said
    driver.get(url)
    wait_until(lambda: driver.execute_script("return document.readyState") == "complete",
               30, f"{url} loaded")
    if driver.execute_script("return !!(window.MathJax && MathJax.startup)"):  # pages with math
        wait_until(lambda: driver.execute_script("return !!MathJax.startup.promise"), 30,
                   "MathJax started")
        driver.execute_async_script("MathJax.startup.promise.then(arguments[arguments.length - 1])")


def console_errors(driver):
    return [entry["message"] for entry in driver.get_log("browser") if entry["level"] == "SEVERE"]


def math_errors(driver):
    return driver.execute_script(
        "return [...document.querySelectorAll('mjx-merror, [data-mjx-error]')]"
        ".map(e => e.getAttribute('data-mjx-error') || e.textContent)")


# A heading set larger than one of higher rank on its page (on a phone the theme's h2 and h3
# outgrew the page's title, and the home page's lecture titles filled the screen).
HEADINGS_OUT_OF_RANK = """
const size = h => parseFloat(getComputedStyle(h).fontSize);
const heads = [...document.querySelectorAll('.bd-article :is(h1, h2, h3, h4)')];
return heads.filter(h => heads.some(g => g.tagName < h.tagName && size(g) < size(h)))
            .map(h => `${h.tagName} ${size(h)}px ${h.innerText.slice(0, 40)}`);"""


# A word in a table cell wider than the cell: broken across lines (overflow-wrap: anywhere let a
# column shrink to one letter, "s/y/m/b/ol") or running past the cell's edge. Words are runs of
# letters, digits and underscores, outside typeset math.
TABLE_WORDS_TOO_WIDE = """
const found = [];
for (const cell of document.querySelectorAll('.bd-article td, .bd-article th')) {
  const box = cell.getBoundingClientRect();
  const walker = document.createTreeWalker(cell, NodeFilter.SHOW_TEXT);
  for (let node = walker.nextNode(); node; node = walker.nextNode()) {
    if (node.parentElement.closest('mjx-container')) continue;
    for (const word of node.textContent.matchAll(/[\\p{L}\\p{N}_]+/gu)) {
      const range = document.createRange();
      range.setStart(node, word.index);
      range.setEnd(node, word.index + word[0].length);
      const rects = [...range.getClientRects()].filter(r => r.width > 0);
      const lines = new Set(rects.map(r => Math.round(r.bottom))).size;
      const past = rects.some(r => r.right > box.right + 1 || r.left < box.left - 1);
      if (lines > 1 || past) found.push(`${word[0].slice(0, 24)} (${Math.round(box.width)} px cell)`);
    }
  }
}
return found;"""


# Typeset math in the page's contents column (the headings) shrunk below readable size: a long
# formula in a heading is scaled to the column's width (lecture 04's identity was 6 px tall).
TINY_CONTENTS_MATH = """
return [...document.querySelectorAll('.bd-sidebar-secondary mjx-container svg')]
  .filter(s => s.getClientRects().length && s.getBoundingClientRect().height < 9)
  .map(s => `${Math.round(s.getBoundingClientRect().height)} px: ${s.closest('a')?.innerText.slice(0, 30)}`);"""

# More than one search field on screen (the header's and the menu's).
SEARCH_FIELDS = """
return [...document.querySelectorAll('.search-button-field')]
  .filter(e => e.getClientRects().length && !e.closest('dialog:not([open])')).length;"""


def overflow(driver):
    """How many CSS pixels the page is wider than the screen (0: it fits)."""
    return driver.execute_script(
        "return Math.max(0, document.documentElement.scrollWidth - window.innerWidth)")


def axe_violations(driver):
    if not driver.execute_script("return !!window.axe"):
        driver.execute_script(AXE.read_text(encoding="utf-8"))
    violations = driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "axe.run(document, {resultTypes: ['violations']}).then(r => done(r.violations));")
    return [f"{v['id']} ({v['impact']}): {v['help']}, e.g. {v['nodes'][0]['html'][:120]}"
            for v in violations if v["impact"] in ("serious", "critical")]


def shoot(driver, name):
    SHOTS.mkdir(parents=True, exist_ok=True)
    driver.save_screenshot(str(SHOTS / name))


def check_pages(driver, site, pages, width):
    """Problems found on each of `pages` at `width`: math typeset, no console error, no serious
    axe violation, headings in rank, nothing wider than the screen."""
    use_width(driver, width)
    problems = []
    for page in pages:
        open_page(driver, (site / page).as_uri())
        found = {"raw TeX": driver.execute_script(RAW_TEX)[:2],
                 "MathJax errors": math_errors(driver)[:2],
                 "console errors": console_errors(driver)[:2],
                 "axe": axe_violations(driver)[:2],
                 "headings larger than a higher rank": driver.execute_script(HEADINGS_OUT_OF_RANK)[:2],
                 "wider than the screen by (px)": overflow(driver),
                 "table words wider than their cell": driver.execute_script(TABLE_WORDS_TOO_WIDE)[:3],
                 "formulas in the contents under 9 px": driver.execute_script(TINY_CONTENTS_MATH)[:2],
                 "search fields on screen beyond one": max(0, driver.execute_script(SEARCH_FIELDS) - 1)}
        problems += [f"{page} at {width}: {what}: {value}" for what, value in found.items() if value]
        if page in SHOT_PAGES:
            shoot(driver, f"site-{SHOT_PAGES[page]}-{width}.png")
    return problems


@pytest.mark.parametrize("width", [pytest.param("phone", marks=pytest.mark.smoke), "laptop"])
def test_every_page_reads_right(site, driver, second_browser, width):
    """Every page checked (check_pages), half of them in a second Chromium at the same time (axe
    takes most of the time, one core a page: a 2-core machine checks two pages at once)."""
    from concurrent.futures import ThreadPoolExecutor

    pages = site_pages(site)
    with ThreadPoolExecutor(2) as pool:
        halves = [pool.submit(check_pages, d, site, pages[i::2], width)
                  for i, d in enumerate((driver, second_browser))]
        problems = [problem for half in halves for problem in half.result()]
    assert problems == []


def menu_state(driver):
    """(the site menu dialog open, the contents dialog open, the wide menu hidden)."""
    return tuple(driver.execute_script(
        "return [document.querySelector('#pst-primary-sidebar-modal').open,"
        " document.querySelector('#pst-secondary-sidebar-modal').open,"
        " document.querySelector('#pst-primary-sidebar').classList.contains('pst-sidebar-hidden')]"))


def visible_button(driver, name):
    from selenium.webdriver.common.by import By

    buttons = [b for b in driver.find_elements(By.CSS_SELECTOR, f"button.{name}") if b.is_displayed()]
    assert len(buttons) == 1, f"{name}: {len(buttons)} visible buttons"
    return buttons[0]


@pytest.mark.smoke
@pytest.mark.parametrize("width", ["phone", "tablet", "laptop"])
def test_the_menu_and_the_contents_open(site, driver, width):
    from selenium.webdriver.common.keys import Keys

    use_width(driver, width)
    open_page(driver, (site / "notebooks" / "04_damped_least_squares.html").as_uri())
    visible_button(driver, "primary-toggle").click()
    if width == "laptop":  # the menu is a column: the button hides it, and shows it again
        wait_until(lambda: menu_state(driver) == (False, False, True), 5, "the menu column to hide")
        visible_button(driver, "primary-toggle").click()
        wait_until(lambda: menu_state(driver) == (False, False, False), 5, "the menu column back")
        assert driver.execute_script(  # the contents column is there, nothing in it cut off
            "const toc = document.querySelector('#pst-secondary-sidebar');"
            "const box = toc.getBoundingClientRect();"
            "const inside = [...toc.querySelectorAll('*')].every(e => e.closest('mjx-assistive-mml')"
            "  || e.getBoundingClientRect().right <= box.right + 1);"  # (MathML for screen readers)
            "return box.width > 100 && box.right <= window.innerWidth + 1 && inside")
        return
    wait_until(lambda: menu_state(driver)[0], 5, "the site menu to open")
    shoot(driver, f"site-menu-{width}.png")
    assert "Damped least squares" in driver.execute_script(
        "return document.querySelector('#pst-primary-sidebar-modal').innerText")
    driver.switch_to.active_element.send_keys(Keys.ESCAPE)
    wait_until(lambda: not any(menu_state(driver)), 5, "the menu to close")
    visible_button(driver, "secondary-toggle").click()
    wait_until(lambda: menu_state(driver)[1], 5, "the page's contents to open")
    assert driver.execute_script(
        "return document.querySelector('#pst-secondary-sidebar-modal a[href^=\"#\"]') !== null")
    shoot(driver, f"site-contents-{width}.png")


def search_results(driver, url):
    open_page(driver, url)
    wait_until(lambda: driver.execute_script(
        "return document.querySelectorAll('#search-results li').length"), 30, "search results")
    time.sleep(1)  # snippets, where they are fetched, arrive after the titles
    return driver.execute_script(
        "return [...document.querySelectorAll('#search-results li')]"
        ".map(li => li.querySelector('p.context') ? li.innerText : '')")


def test_search_from_disk_finds_pages_without_console_errors(site, driver):
    use_width(driver, "laptop")
    results = search_results(driver, (site / "search.html").as_uri() + "?q=damping")
    assert len(results) >= 3 and console_errors(driver) == []


def test_search_on_a_served_site_shows_snippets(site, driver):
    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), partial(Quiet, directory=str(site)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        use_width(driver, "laptop")
        url = f"http://127.0.0.1:{server.server_address[1]}/search.html?q=damping"
        results = search_results(driver, url)
        assert sum(bool(r) for r in results) >= 3, results
        assert console_errors(driver) == []
    finally:
        server.shutdown()
