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
import urllib.error
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


REPLY_TIMEOUT = 60  # s: one REST request; a request that outlasts it is asked again (not yet)
PATIENCE = 1800  # s: how long a wait for JupyterLab or a kernel may last before it counts as a hang


def not_yet_errors():
    """Errors that mean "not yet", never "failed": no answer from the server yet (OSError: refused,
    reset, timed out on a busy machine) and, with selenium, an element redrawn while read."""
    try:
        from selenium.common.exceptions import StaleElementReferenceException
    except ImportError:  # the REST calls alone need no selenium
        return (OSError,)
    return (OSError, StaleElementReferenceException)


def wait_until(condition, timeout, what, every=0.25):
    """condition()'s first true value. It is asked again while it is false or raises one of
    not_yet_errors(); timeout (s) only guards against a hang, so it is generous."""
    retry = not_yet_errors()
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            value = condition()
        except retry:
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
            wait_until(up, PATIENCE, "JupyterLab to start")
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


def sessions(url):
    """The server's running sessions (REST API). A slow or refused request raises OSError, which
    wait_until takes as "not yet"."""
    with urllib.request.urlopen(f"{url}/api/sessions?token={TOKEN}", timeout=REPLY_TIMEOUT) as reply:
        return json.load(reply)


def kernel_states(url):
    """Execution state of each running session's kernel; call it inside wait_until."""
    return [s["kernel"]["execution_state"] for s in sessions(url)]


def shut_down_kernels(url):
    """Shut down every running kernel (one notebook's kernel at a time on 2 cores), waiting for
    the server's answers however busy the machine is."""
    def delete(session):
        request = urllib.request.Request(f"{url}/api/sessions/{session}?token={TOKEN}", method="DELETE")
        try:
            urllib.request.urlopen(request, timeout=REPLY_TIMEOUT).close()
        except urllib.error.HTTPError as error:
            if error.code != 404:  # 404: gone already (an earlier request that timed out did it)
                raise
        return True

    for s in wait_until(lambda: (sessions(url),), PATIENCE, "the session list")[0]:
        wait_until(lambda: delete(s["id"]), PATIENCE, f"session {s['id']} to shut down")


def code_cell_count(path):
    return sum(c["cell_type"] == "code" for c in json.loads(Path(path).read_text())["cells"])


def run_all(driver, url, name, code_cells, timeout=600):
    """Open notebook `name` in JupyterLab, Run All Cells and wait until every code cell has run."""
    from selenium.webdriver.common.by import By

    driver.get(f"{url}/lab/tree/{name}?token={TOKEN}&reset")  # reset: no earlier tab restored
    wait_until(lambda: driver.find_elements(By.CSS_SELECTOR, ".jp-Notebook .jp-Cell"), PATIENCE,
               "the notebook to open")
    wait_until(lambda: "idle" in kernel_states(url), PATIENCE, "the kernel to start")
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
