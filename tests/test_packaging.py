"""pyproject.toml, the lock, Binder and conda agree; runtime dependencies are only what the
module needs; the course's home is named once."""
import re
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from ikteach.course import course_home

ROOT = Path(__file__).resolve().parents[1]
RUNTIME = {"jax", "jaxlib", "numpy", "matplotlib", "pyvista", "scikit-image", "ipywidgets"}


def _name(requirement):
    return re.split(r"[\s<>=!~;\[@]", requirement.strip(), maxsplit=1)[0].lower().replace("_", "-")


def pyproject():
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def pyproject_runtime():
    return {_name(r) for r in pyproject()["project"]["dependencies"]}


def locked_versions():
    """{name: {version, ...}} from uv.lock (a name may be pinned per Python version)."""
    lock = tomllib.loads((ROOT / "uv.lock").read_text())
    versions = {}
    for package in lock["package"]:
        versions.setdefault(package["name"], set()).add(package.get("version"))
    return versions


def binder_pins():
    """{name: {version, ...}} pinned by binder/constraints.txt."""
    pins = {}
    for line in (ROOT / "binder" / "constraints.txt").read_text().splitlines():
        m = re.match(r"^([A-Za-z0-9_.-]+)==([^\s;]+)", line)
        if m:
            pins.setdefault(m.group(1).lower().replace("_", "-"), set()).add(m.group(2))
    return pins


def test_runtime_dependencies_are_what_the_module_needs():
    assert pyproject_runtime() == RUNTIME


def test_extras_hold_the_lab_the_grader_and_the_tools():
    extras = {k: {_name(r) for r in v} for k, v in pyproject()["project"]["optional-dependencies"].items()}
    assert {"lab", "grade", "3d", "dev", "bench"} <= set(extras)
    assert "jupyterlab" in extras["lab"]
    assert {"nbformat", "nbclient", "ipykernel"} <= extras["grade"]
    assert "pyvista" in extras["3d"]  # pyvista[jupyter]: trame and friends
    assert {"pytest", "pytest-xdist", "nbval", "hypothesis", "ikteach"} <= extras["dev"]
    assert not (extras["lab"] | extras["grade"] | extras["3d"]) & RUNTIME - {"pyvista"}


def test_lock_pins_every_runtime_dependency():
    versions = locked_versions()
    assert RUNTIME <= set(versions)
    assert "jupyterlab" in versions and "trame" in versions


def test_binder_installs_the_package_with_lab_and_3d_extras_from_the_lock():
    requirements = [line.strip() for line in (ROOT / "binder" / "requirements.txt").read_text().splitlines()
                    if line.strip() and not line.startswith("#")]
    assert requirements == ["-c constraints.txt", ".[lab,3d]"]
    # The same runtime dependencies as pyproject (they come from it), at the locked versions.
    pins, locked = binder_pins(), locked_versions()
    for name in pyproject_runtime() | {"jupyterlab", "trame"}:
        assert name in pins, f"binder/constraints.txt does not pin {name}: run make lock"
        assert pins[name] == locked[name], f"binder/constraints.txt is older than uv.lock ({name})"
    assert "ikteach" not in pins


def test_binder_has_what_repo2docker_needs():
    assert re.fullmatch(r"python-3\.\d+\n?", (ROOT / "binder" / "runtime.txt").read_text())
    apt = (ROOT / "binder" / "apt.txt").read_text().split()
    assert {"libegl1", "libosmesa6", "libgl1-mesa-dri"} <= set(apt)


def test_conda_environment_installs_binders_requirements():
    text = (ROOT / "environment.yml").read_text()
    assert re.search(r"^\s+- -r binder/requirements\.txt\s*$", text, re.M)


def test_project_urls_name_the_course_home():
    home = course_home.home(ROOT / "pyproject.toml")
    assert home.package == pyproject()["project"]["name"] == "ikteach"
    assert home.github.endswith("/ikteach")
    assert home.requirement == f"ikteach @ git+{home.repository}@{home.branch}"
    assert home.colab_url("notebooks/01_jacobian.ipynb").endswith(
        f"{home.github}/blob/{home.branch}/notebooks/01_jacobian.ipynb")


def test_package_data_is_included_by_glob():
    data = pyproject()["tool"]["setuptools"]["package-data"]["ikteach"]
    assert "**/*" in data


def test_ci_runs_the_readme_test_command():
    assert "make test" in (ROOT / "README.md").read_text()
    assert "make test" in (ROOT / ".ci" / "run").read_text()


def test_make_installs_from_the_lock():
    makefile = (ROOT / "Makefile").read_text()
    assert re.search(r"sync --locked", makefile)
    for target in ("lab:", "test:", "test-latest:", "lock:"):
        assert re.search(rf"^{target}", makefile, re.M), target


def test_importing_ikteach_enables_float64():
    import jax.numpy as jnp

    import ikteach  # noqa: F401

    assert jnp.zeros(1).dtype == jnp.float64
