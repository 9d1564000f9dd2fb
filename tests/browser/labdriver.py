"""JupyterLab in headless Chromium, for the browser tests and the browser benchmark.

Selenium drives /usr/bin/chromium through /usr/bin/chromedriver (Debian's chromium and
chromium-driver, installed by `make test-browser`): nothing is downloaded at run time.
JupyterLab serves a temporary folder holding copies of the notebooks (never the repo's).
"""
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from contextlib import contextmanager
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CHROMIUM, CHROMEDRIVER = "/usr/bin/chromium", "/usr/bin/chromedriver"
WIDTH, HEIGHT = 1280, 720
TOKEN = "ikteach-browser-test"
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-dev-shm-usage", "--hide-scrollbars", "--force-device-scale-factor=1")
# No news toast over the notebook; a fresh settings folder otherwise.
# Every cell kept in the page (no windowing), so all prompts and outputs can be found.
SETTINGS = {"@jupyterlab/apputils-extension/notification.jupyterlab-settings":
            '{"fetchNews": "false", "checkForUpdates": false}',
            "@jupyterlab/notebook-extension/tracker.jupyterlab-settings":
            '{"windowingMode": "none"}'}


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_until(condition, timeout, what, every=0.25):
    """condition()'s first true value within timeout seconds; an element re-rendered while the
    condition read it (a widget redrawn) counts as not yet."""
    from selenium.common.exceptions import StaleElementReferenceException

    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            value = condition()
        except StaleElementReferenceException:
            value = None
        if value:
            return value
        time.sleep(every)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


@contextmanager
def jupyterlab(home, notebooks=()):
    """JupyterLab on a free port with a token, serving `home` (copies of `notebooks` put there).
    Yields its URL."""
    home = Path(home)
    for path in notebooks:
        shutil.copy(path, home / Path(path).name)
    settings = home / ".settings"
    for name, text in SETTINGS.items():
        (settings / name).parent.mkdir(parents=True, exist_ok=True)
        (settings / name).write_text(text)
    port = free_port()
    env = dict(os.environ, PYVISTA_OFF_SCREEN="true", JUPYTER_CONFIG_DIR=str(home / ".config"),
               JUPYTER_RUNTIME_DIR=str(home / ".runtime"))
    with open(home / "lab.log", "w") as log:
        server = subprocess.Popen(
            [sys.executable, "-m", "jupyter", "lab", "--no-browser", f"--port={port}",
             "--ip=127.0.0.1", f"--IdentityProvider.token={TOKEN}", f"--ServerApp.root_dir={home}",
             f"--LabApp.user_settings_dir={settings}", f"--LabApp.workspaces_dir={home / '.ws'}",
             "--ServerApp.allow_root=True"],
            cwd=home, env=env, stdout=log, stderr=subprocess.STDOUT)
        url = f"http://127.0.0.1:{port}"

        def up():
            try:
                with urllib.request.urlopen(f"{url}/api/status?token={TOKEN}", timeout=2) as r:
                    return r.status == 200
            except OSError:
                return server.poll() is not None  # died: stop waiting, fail below

        try:
            wait_until(up, 120, "JupyterLab to start")
            assert server.poll() is None, (home / "lab.log").read_text()[-3000:]
            yield url
        finally:
            server.terminate()
            server.wait(timeout=30)


@contextmanager
def chromium(width=WIDTH, height=HEIGHT):
    """A headless Chromium window of width x height CSS pixels, driven by selenium."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in FLAGS:
        options.add_argument(flag)
    profile = tempfile.mkdtemp(prefix="ikteach-chromium-")
    options.add_argument(f"--user-data-dir={profile}")
    options.add_argument(f"--window-size={width},{height}")
    driver = webdriver.Chrome(service=Service(executable_path=CHROMEDRIVER), options=options)
    try:
        driver.set_window_size(width, height)
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def kernel_states(url):
    """Execution state of each running session's kernel, from the server's REST API."""
    with urllib.request.urlopen(f"{url}/api/sessions?token={TOKEN}", timeout=5) as reply:
        return [s["kernel"]["execution_state"] for s in json.load(reply)]


def shut_down_kernels(url):
    """Shut down every running kernel (one notebook's kernel at a time on 2 cores)."""
    with urllib.request.urlopen(f"{url}/api/sessions?token={TOKEN}", timeout=5) as reply:
        sessions = json.load(reply)
    for s in sessions:
        request = urllib.request.Request(f"{url}/api/sessions/{s['id']}?token={TOKEN}",
                                         method="DELETE")
        urllib.request.urlopen(request, timeout=30).close()


def code_cell_count(path):
    return sum(c["cell_type"] == "code" for c in json.loads(Path(path).read_text())["cells"])


def run_all(driver, url, name, code_cells, timeout=600):
    """Open notebook `name` in JupyterLab, Run All Cells and wait until every code cell has run."""
    from selenium.webdriver.common.by import By

    driver.get(f"{url}/lab/tree/{name}?token={TOKEN}&reset")  # reset: no earlier tab restored
    wait_until(lambda: driver.find_elements(By.CSS_SELECTOR, ".jp-Notebook .jp-Cell"), 120,
               "the notebook to open")
    wait_until(lambda: "idle" in kernel_states(url), 180, "the kernel to start")
    driver.find_element(By.XPATH, "//li[contains(@class,'lm-MenuBar-item')][.='Run']").click()
    driver.find_element(By.XPATH, "//li[contains(@class,'lm-Menu-item')]"
                                  "[.//*[normalize-space()='Run All Cells']]").click()

    def finished():  # every code cell numbered ([12]:), none pending ([*]:) or queued ([ ]:)
        prompts = driver.execute_script(
            "return [...document.querySelectorAll('.jp-NotebookPanel:not(.lm-mod-hidden) "
            ".jp-CodeCell .jp-InputPrompt')].map(p => p.innerText.trim())")
        return len(prompts) == code_cells and all(re.fullmatch(r"\[\d+\]:?", p) for p in prompts)

    wait_until(finished, timeout, f"Run All of {name} to finish", every=1.0)
    return driver
