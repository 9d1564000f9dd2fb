"""Every lecture notebook (notebooks/01-10) opened in JupyterLab in headless Chromium, Run All,
then checked as the room sees it: no error output, no clipped figure or widget, every <img>
with alt text that says something (not empty, not "Image"), every SVG picture named.

Run with `make test-browser` (with lab_05.py); not collected by `make test`. One notebook at a
time: its kernel is shut down before the next opens. Two screenshots per notebook
(1280x720: scrolled to its first picture, and to its last) go to $BROWSER_SHOTS
(default: a new temporary folder, printed at the end of the run).
"""
import os
import tempfile
import time
from pathlib import Path

import pytest

pytest.importorskip("selenium.webdriver")
from selenium.webdriver.common.by import By  # noqa: E402

from labdriver import (ROOT, chromium, code_cell_count, jupyterlab,  # noqa: E402
                       run_all, shut_down_kernels, wait_until)

NOTEBOOKS = sorted(p.name for p in (ROOT / "notebooks").glob("[01][0-9]_*.ipynb"))
RUN_ALL_TIMEOUT = 900  # s: the longest notebook on a busy 2-core machine


@pytest.fixture(scope="module")
def shots():
    folder = os.environ.get("BROWSER_SHOTS")
    folder = Path(folder) if folder else Path(tempfile.mkdtemp(prefix="ikteach-notebooks-"))
    folder.mkdir(parents=True, exist_ok=True)
    yield folder
    print(f"\nscreenshots of every notebook: {folder}")


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    with jupyterlab(tmp_path_factory.mktemp("lab"),
                    [ROOT / "notebooks" / name for name in NOTEBOOKS]) as url:
        yield url


@pytest.fixture(scope="module")
def browser():
    with chromium() as driver:
        yield driver


# Widgets are drawn after their cell has run (the page asks the kernel for their state): every
# widget output holds its view, or the error view that PROBLEMS reports.
WIDGETS_DRAWN = """
return [...document.querySelectorAll('.jp-NotebookPanel:not(.lm-mod-hidden) .jp-OutputArea-output'
                                     + '[data-mime-type="application/vnd.jupyter.widget-view+json"]')]
  .every(o => o.querySelector('.jupyter-widgets, .jupyter-widgets-error-widget'));"""

# Checks run in the page over the open notebook's outputs.
PROBLEMS = """
const panel = document.querySelector('.jp-NotebookPanel:not(.lm-mod-hidden)');
const outputs = [...panel.querySelectorAll('.jp-OutputArea-output')];
const where = el => {
  const cell = el.closest('.jp-CodeCell');
  const prompt = cell && cell.querySelector('.jp-InputPrompt');
  return prompt ? prompt.innerText.trim() : '?';
};
const errors = outputs
  .filter(o => o.dataset.mimeType === 'application/vnd.jupyter.stderr'
               && /Traceback|Error\\b/.test(o.innerText))
  .map(o => where(o) + ' ' + o.innerText.slice(0, 300));
for (const w of panel.querySelectorAll('.jupyter-widgets-error-widget'))
  errors.push(where(w) + ' widget error: ' + w.innerText.slice(0, 200));
const clipped = [];
for (const o of outputs) {
  const box = o.getBoundingClientRect();
  if (o.scrollWidth > o.clientWidth + 1)
    clipped.push(where(o) + ` output wider than it shows: ${o.scrollWidth} > ${o.clientWidth}`);
  for (const p of o.querySelectorAll('img, svg[role=img], canvas')) {
    const r = p.getBoundingClientRect();
    if (r.width === 0) continue;  // not shown (a hidden animation frame)
    if (r.left < box.left - 1 || r.right > box.right + 1)
      clipped.push(where(p) + ` ${p.tagName} ${r.left}-${r.right} outside ${box.left}-${box.right}`);
  }
}
const unnamed = [];
for (const img of panel.querySelectorAll('.jp-OutputArea img')) {
  const alt = (img.getAttribute('alt') || '').trim();
  if (!alt || alt.toLowerCase() === 'image') unnamed.push(where(img) + ` img alt=${JSON.stringify(alt)}`);
}
for (const svg of panel.querySelectorAll('.jp-OutputArea svg[role=img]'))
  if (!(svg.getAttribute('aria-label') || '').trim()) unnamed.push(where(svg) + ' svg without aria-label');
const pictures = panel.querySelectorAll('.jp-OutputArea img, .jp-OutputArea svg[role=img]').length;
return {errors, clipped, unnamed, pictures};
"""


def _screenshots(driver, shots, stem):
    """Two 1280x720 views: the notebook's first picture (or widget) and its last."""
    for which, suffix in ((0, ""), (-1, "-last")):
        picture = driver.execute_script(
            "const all = document.querySelectorAll('.jp-NotebookPanel:not(.lm-mod-hidden) "
            ".jp-OutputArea :is(img, svg[role=img], .widget-box)');"
            " return all.length ? all[arguments[0] < 0 ? all.length - 1 : 0] : null", which)
        if picture is not None:
            driver.execute_script("arguments[0].scrollIntoView({block: 'start'})", picture)
            time.sleep(0.5)
        driver.save_screenshot(str(shots / f"{stem}{suffix}.png"))


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_notebook_runs_in_jupyterlab_unclipped_with_alt_text(lab, browser, shots, name):
    stem = Path(name).stem
    shut_down_kernels(lab)  # the previous notebook's kernel: one at a time
    try:
        run_all(browser, lab, name, code_cell_count(ROOT / "notebooks" / name), RUN_ALL_TIMEOUT)
    except Exception:
        browser.save_screenshot(str(shots / f"{stem}-failed.png"))
        raise
    wait_until(lambda: browser.execute_script(WIDGETS_DRAWN), 60, f"{name}'s widgets to be drawn")
    found = browser.execute_script(PROBLEMS)
    _screenshots(browser, shots, stem)
    assert not found["errors"], found["errors"]
    assert not found["clipped"], found["clipped"]
    assert not found["unnamed"], found["unnamed"]
    assert found["pictures"] > 0  # every lecture shows pictures: the checks above saw them
    assert browser.find_elements(By.CSS_SELECTOR, ".jp-NotebookPanel:not(.lm-mod-hidden)")
