"""Browser latency of the course's widgets: a control moved in JupyterLab -> the picture redrawn.

    make bench-browser            # or: .venv/bin/python tests/browser/bench_latency.py [--n 30]

A benchmark, not a test (speed is never asserted): it prints a table of p50/p95 for
  - demo x: the demo's (notebook 05) target-x slider moved one step -> the arm redrawn;
  - map lambda: the live map's (notebook 07: 128 x 128 targets) lambda slider moved one step
    to a lambda not seen before -> the map redrawn (the map was prefetched while idle);
  - map no prefetch: the same on a live map with prefetch=False: every lambda solved when
    asked for (what a jump of several steps costs);
  - demo method / map method: the method dropdown switched (after one warm-up round, so no
    compiling) -> the picture redrawn.
Each sample is a real key press (selenium: arrow key on the focused slider handle) or a real
<select> change in headless Chromium. Timed in the page with its own clock: the start is the
keydown/change event's timeStamp; "drawn" is a MutationObserver on the widget's output seeing a
new picture (an <img> src or a new <img>/<svg>), then the image decoded (img.decode()) and
the next animation frame (requestAnimationFrame) reached. Between samples the kernel is idle.
The widgets are built as notebooks 05 and 07 build them, in a scratch notebook.
"""
import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from labdriver import chromium, jupyterlab, kernel_states, run_all, wait_until  # noqa: E402

CELLS = [
    "import ikteach as ik\nrng = ik.notebook.setup()",
    "demo = ik.pictures.demo.Demo()\ndemo.widget",
    "arm = ik.planar_chain([1.0, 0.5, 0.25])  # as notebook 07\n"
    "live = ik.pictures.live_map.LiveMap(arm, grid_n=128, theta0=[0.3, 0.6, 0.6], damping=0.2, "
    "max_iter=100)\nlive.widget",
    "cold = ik.pictures.live_map.LiveMap(arm, grid_n=128, theta0=[0.3, 0.6, 0.6], damping=0.2, "
    "max_iter=100, prefetch=False)\ncold.widget  # every lambda solved when asked for",
]
GOALS = {"demo x": 50, "map lambda": 150, "map no prefetch": None, "demo method": None,
         "map method": None}

# One recorder per widget output: start (event timeStamp) and drawn (performance.now()).
INSTALL = """
const [key, root] = arguments;
const all = window.__ikbench = window.__ikbench || {};
const rec = all[key] = {armed: false, start: null, seen: null, drawn: null};
if (!window.__ikbenchListening) {
  window.__ikbenchListening = true;
  const start = e => { for (const r of Object.values(window.__ikbench))
                         if (r.armed && r.start === null) r.start = e.timeStamp; };
  addEventListener('keydown', start, true);
  addEventListener('change', e => { if (e.target.tagName === 'SELECT') start(e); }, true);
}
new MutationObserver(mutations => {
  if (!rec.armed || rec.start === null || rec.seen !== null) return;
  const pictures = [];
  for (const m of mutations) {
    if (m.type === 'attributes' && m.target.tagName === 'IMG') pictures.push(m.target);
    for (const n of m.addedNodes) {
      if (n.nodeType !== 1) continue;
      if (n.tagName === 'IMG' || n.tagName.toLowerCase() === 'svg') pictures.push(n);
      pictures.push(...n.querySelectorAll('img, svg'));
    }
  }
  if (!pictures.length) return;
  rec.seen = performance.now();
  Promise.all(pictures.map(p => p.decode ? p.decode().catch(() => null) : null))
    .then(() => requestAnimationFrame(() => { rec.drawn = performance.now(); }));
}).observe(root, {subtree: true, childList: true, attributes: true, attributeFilter: ['src']});
"""
ARM = "const r = window.__ikbench[arguments[0]]; Object.assign(r, {armed: true, start: null, seen: null, drawn: null});"
READ = "const r = window.__ikbench[arguments[0]]; return r.drawn === null ? null : [r.start, r.seen, r.drawn];"


def output_of_cell(driver, index):
    """The output area of the index-th code cell."""
    return driver.execute_script(
        "return document.querySelectorAll('.jp-CodeCell')[arguments[0]]"
        ".querySelector('.jp-OutputArea')", index)


def settle(driver, url, seconds=0.3):
    wait_until(lambda: kernel_states(url) == ["idle"], 60, "the kernel to be idle", every=0.05)
    time.sleep(seconds)


def sample(driver, url, key, act):
    """One timed action: milliseconds from the event to the picture drawn, and of those the
    last part, from the new picture in the page to its frame (decode + frame)."""
    settle(driver, url)
    driver.execute_script(ARM, key)
    act()
    times = wait_until(lambda: driver.execute_script(READ, key), 30, f"{key} to redraw",
                       every=0.01)
    return times[2] - times[0], times[2] - times[1]


def slider_handles(driver, output):
    from selenium.webdriver.common.by import By

    return output.find_elements(By.CSS_SELECTOR, ".widget-slider .noUi-handle")


def press(driver, handle, key):
    from selenium.webdriver.common.action_chains import ActionChains

    driver.execute_script("arguments[0].focus({preventScroll: false});"
                          " arguments[0].scrollIntoView({block: 'center'})", handle)
    ActionChains(driver).send_keys(key).perform()


def choose(driver, select, text):
    from selenium.webdriver.support.ui import Select

    driver.execute_script("arguments[0].scrollIntoView({block: 'center'})", select)
    Select(select).select_by_visible_text(text)


def measure(driver, url, n):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    demo, live = output_of_cell(driver, 1), output_of_cell(driver, 2)
    driver.execute_script(INSTALL, "demo", demo)
    driver.execute_script(INSTALL, "live", live)
    rows = {}
    x = slider_handles(driver, demo)[0]
    rows["demo x"] = [sample(driver, url, "demo", lambda: press(driver, x, k))
                      for k in [Keys.ARROW_RIGHT] * (n // 2) + [Keys.ARROW_LEFT] * (n - n // 2)]
    lam = slider_handles(driver, live)[0]
    steps = min(n, 36)  # lambda 0.2 -> 2.0 in steps of 0.05: every one new
    rows["map lambda"] = [sample(driver, url, "live", lambda: press(driver, lam, Keys.ARROW_RIGHT))
                          for _ in range(steps)]
    cold = output_of_cell(driver, 3)
    driver.execute_script(INSTALL, "cold", cold)
    lam = slider_handles(driver, cold)[0]
    rows["map no prefetch"] = [
        sample(driver, url, "cold", lambda: press(driver, lam, Keys.ARROW_RIGHT))
        for _ in range(steps)]
    for key, output, names in (("demo", demo, ["pinv", "jt", "dls"]), ("live", live, ["jt", "dls"])):
        select = output.find_elements(By.CSS_SELECTOR, ".widget-dropdown select")[0]
        for name in names:  # warm-up round: compiles (and solves the map) once per method
            sample(driver, url, key, lambda: choose(driver, select, name))
        order = (names * n)[:n]
        rows[f"{'demo' if key == 'demo' else 'map'} method"] = [
            sample(driver, url, key, lambda: choose(driver, select, name)) for name in order]
    return rows


def table(rows, title):
    print(f"\n{title}")
    print(f"| {'what':<15} | {'n':>3} | {'p50 ms':>7} | {'p95 ms':>7} | {'max ms':>7} | "
          f"{'goal p95':>8} | {'decode+frame p50':>16} |")
    print(f"|{'-' * 17}|{'-' * 5}|{'-' * 9}|{'-' * 9}|{'-' * 9}|{'-' * 10}|{'-' * 18}|")
    for name, samples in rows.items():
        t, last = np.asarray(samples).T
        goal = GOALS[name]
        print(f"| {name:<15} | {len(t):>3} | {np.percentile(t, 50):>7.1f} | "
              f"{np.percentile(t, 95):>7.1f} | {t.max():>7.1f} | "
              f"{'< ' + str(goal) if goal else '':>8} | {np.percentile(last, 50):>16.1f} |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=30, help="samples per row")
    ap.add_argument("--title", default="browser latency (headless Chromium, JupyterLab)")
    args = ap.parse_args()
    import nbformat

    load = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="ikteach-bench-") as home:
        nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in CELLS])
        nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                     "language": "python"}
        nbformat.write(nb, Path(home) / "bench.ipynb")
        with jupyterlab(home) as url, chromium() as driver:
            run_all(driver, url, "bench.ipynb", len(CELLS))
            rows = measure(driver, url, args.n)
    table(rows, args.title)
    print(f"{os.cpu_count()} cores; load average at start {load[0]:.2f}, "
          f"at end {os.getloadavg()[0]:.2f} (1 min)")


if __name__ == "__main__":
    main()
