"""The built package works outside the checkout: wheel and sdist from a copy of the source
(plus a probe data file, to show that new package data is shipped), the wheel installed into
a clean venv in a temporary folder, then a solve, a plot and an off-screen pyvista scene run
from there. A second venv stands in for Colab: Colab's preinstalled jax, numpy, matplotlib,
ipywidgets... first, then the wheel, which upgrades those below pyproject's bounds only (ipywidgets).

uv does the builds and installs (from its cache after the first run; pins from the lock).
"""
import os
import re
import shutil
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PROBE = "data/_probe_for_tests.txt"

# Colab's preinstalled versions (Python 3.12), from Colab's pip freeze (googlecolab/backend-info,
# pip-freeze.gpu.txt, 2026; its GPU runtime also has jax-cuda12-plugin and jax-cuda12-pjrt 0.7.2).
# Update them when Colab moves (docs/lecturers.md, "Colab").
COLAB_PYTHON = "3.12"
COLAB = {"jax": "0.7.2", "jaxlib": "0.7.2", "numpy": "2.0.2", "scipy": "1.16.3",
         "matplotlib": "3.10.0", "scikit-image": "0.25.2", "ipywidgets": "7.7.1"}
# Only ipywidgets is below pyproject's lower bounds (ipywidgets 8: the demo's static still), so
# the wheel upgrades it and keeps the rest: jax, jaxlib (and so the CUDA plugin) stay matched.
COLAB_UPGRADED = ("ipywidgets",)

SMOKE = r'''
import importlib.resources, sys
from pathlib import Path
import numpy as np
import ikteach as ik
from ikteach._runtime import devices
cores = devices.use_cores()  # what ik.notebook.setup() does, before JAX's first operation

# the tests' folder ($IKTEACH_JAX_CACHE or the per-user one); None where jaxlib's cache is not trusted
print("cache:", ik.notebook.compilation_cache())
assert not Path(ik.__file__).resolve().is_relative_to(Path(sys.argv[1])), ik.__file__
arm = ik.planar_chain([1.0, 1.0, 1.0])
res = ik.solve(arm, np.array([2.0, 1.0]), np.zeros(3), method="dls", damping=0.5)
assert res.status == "converged", res.status
print("solve:", res.status, res.iterations)

import jax
from ikteach._runtime import engine as batch
grid = np.stack(np.meshgrid(np.linspace(-3.2, 3.2, 20), np.linspace(-3.2, 3.2, 20)), -1).reshape(-1, 2)
batch.SPLIT_FROM = 16  # split even this small grid over the devices, then compare with one
split = ik.solve_batch(arm, grid, np.full(3, 0.3))
batch.SPLIT_FROM = 10**9
whole = ik.solve_batch(arm, grid, np.full(3, 0.3))
assert len(jax.devices()) == cores == devices.wanted(), (jax.devices(), cores)
assert np.array_equal(split.theta, whole.theta) and np.array_equal(split.iterations, whole.iterations)
print("batch:", len(jax.devices()), "devices, split = whole")

import matplotlib
matplotlib.use("Agg")
from matplotlib.figure import Figure
fig = Figure()
ax = fig.subplots()
ik.pictures.plot.draw_arm(ax, arm, res.theta)
fig.savefig("arm.png")
assert Path("arm.png").stat().st_size > 1000
print("plot: arm.png")

if "--scene" in sys.argv:
    import pyvista as pv
    pv.OFF_SCREEN = True
    ur5 = ik.core.robots.ur5()
    p = ik.pictures.scene.scene(ur5, np.zeros(6))
    image = ik.pictures.scene.render(p)
    p.close()
    assert image.ndim == 3 and image.std() > 1.0, "blank scene"
    print("scene:", image.shape)

if "--probe" in sys.argv:
    print("data:", importlib.resources.files("ikteach").joinpath(sys.argv[-1]).read_text().strip())

if "--demo" in sys.argv:
    demo = ik.pictures.demo.Demo()
    demo.update(x=3.5, y=1.0)
    import ipywidgets
    print("demo:", ipywidgets.__version__, demo.result.status)
'''


def _uv(*args, **kw):
    return subprocess.run([sys.executable, "-m", "uv", *args], check=True, capture_output=True,
                          text=True, env={**os.environ, "UV_PYTHON_DOWNLOADS": "never"}, **kw)


def _run(python, *args, cwd):
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PYVISTA_OFF_SCREEN"] = "true"
    return subprocess.run([str(python), *args], cwd=cwd, check=True, capture_output=True,
                          text=True, env=env, timeout=600)


@pytest.fixture(scope="module")
def dist(tmp_path_factory):
    """wheel and sdist built from a copy of the source with a probe data file added."""
    tmp = tmp_path_factory.mktemp("build")
    src = tmp / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    shutil.copytree(ROOT / "ikteach", src / "ikteach",
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    (src / "ikteach" / PROBE).parent.mkdir(exist_ok=True)
    (src / "ikteach" / PROBE).write_text("probe data file\n")
    _uv("build", "--quiet", "--sdist", "--wheel", "--out-dir", str(tmp / "dist"), str(src))
    wheel = next((tmp / "dist").glob("ikteach-*.whl"))
    sdist = next((tmp / "dist").glob("ikteach-*.tar.gz"))
    return wheel, sdist


def _venv(tmp, python):
    _uv("venv", "--quiet", "--python", str(python), str(tmp / "venv"))
    return tmp / "venv" / "bin" / "python"


def test_wheel_and_sdist_ship_the_module_and_package_data(dist):
    wheel, sdist = dist
    names = zipfile.ZipFile(wheel).namelist()
    assert "ikteach/core/solve.py" in names and f"ikteach/{PROBE}" in names
    assert not [n for n in names if "__pycache__" in n or n.startswith(("tests/", "notebooks/"))]
    with tarfile.open(sdist) as tar:
        members = tar.getnames()
    assert any(m.endswith(f"ikteach/{PROBE}") for m in members)
    metadata = zipfile.ZipFile(wheel).read(
        next(n for n in names if n.endswith(".dist-info/METADATA"))).decode()
    assert "Project-URL: Repository, https://github.com/" in metadata
    requires = [line for line in metadata.splitlines() if line.startswith("Requires-Dist:")]
    runtime = [r for r in requires if "extra ==" not in r]
    assert {re.split(r"[<>=!\[ ]", r.split()[1])[0] for r in runtime} == {
        "jax", "jaxlib", "numpy", "matplotlib", "scikit-image", "ipywidgets"}


def test_wheel_in_a_clean_venv_solves_plots_and_renders(dist, tmp_path):
    wheel, _ = dist
    python = _venv(tmp_path, sys.executable)
    _uv("pip", "install", "--quiet", "--python", str(python), f"ikteach[scenes] @ {wheel.as_uri()}",
        "-c", str(ROOT / "binder" / "constraints.txt"))
    work = tmp_path / "work"
    work.mkdir()
    (work / "smoke.py").write_text(SMOKE)
    out = _run(python, "smoke.py", str(ROOT), "--scene", "--probe", PROBE, cwd=work).stdout
    assert "solve: converged" in out and "split = whole" in out and "plot: arm.png" in out
    assert "scene: (" in out and "data: probe data file" in out
    frozen = _uv("pip", "list", "--python", str(python)).stdout
    for extra in ("jupyterlab", "nbclient", "pytest"):
        assert f"\n{extra} " not in frozen, f"runtime install pulled {extra}"


def _colab_python():
    """A Python 3.12 like Colab's, if this machine has one (else the tests' own Python)."""
    pyenv = Path(os.environ.get("PYENV_ROOT", Path.home() / ".pyenv")) / "versions"
    try:
        candidates = sorted(str(p) for p in pyenv.glob(f"{COLAB_PYTHON}.*/bin/python"))
    except OSError:  # e.g. another user's pyenv, not readable by this one
        candidates = []
    found = shutil.which(f"python{COLAB_PYTHON}")
    if found and "shims" not in found:  # a pyenv shim refuses versions not selected
        candidates.append(found)
    return candidates[-1] if candidates else sys.executable


def test_wheel_on_a_colab_like_kernel_keeps_colabs_numpy_and_matplotlib(dist, tmp_path):
    wheel, _ = dist
    python = _venv(tmp_path, _colab_python())
    _uv("pip", "install", "--quiet", "--python", str(python),
        *[f"{name}=={version}" for name, version in COLAB.items()])
    _uv("pip", "install", "--quiet", "--python", str(python), str(wheel))  # what Colab's cell does
    listed = dict(line.split()[:2] for line in
                  _uv("pip", "list", "--python", str(python)).stdout.splitlines()[2:])
    for name, version in COLAB.items():
        if name in COLAB_UPGRADED:
            assert listed[name] != version, f"Colab's {name} {version} was kept"
        else:
            assert listed[name] == version, f"installing the wheel changed Colab's {name}"
    assert not {"pyvista", "vtk"} & set(listed), "the lectures without 3-D pulled VTK"
    work = tmp_path / "work"
    work.mkdir()
    (work / "smoke.py").write_text(SMOKE)
    out = _run(python, "smoke.py", str(ROOT), "--demo", cwd=work).stdout
    assert "solve: converged" in out and "split = whole" in out
    assert f"demo: {listed['ipywidgets']}" in out
    # a second run loads the loops from the compilation cache and still solves
    again = _run(python, "smoke.py", str(ROOT), cwd=work).stdout
    assert "solve: converged" in again and "split = whole" in again
