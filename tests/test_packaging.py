"""pyproject.toml, the lock, Binder and conda agree; runtime dependencies are only what the
module needs; each notebook's Colab cell installs what that notebook uses; the course's home is
named once."""
import json
import re
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from ikteach.course import course_home, notebook_header
from test_wheel import COLAB  # Colab's preinstalled versions

ROOT = Path(__file__).resolve().parents[1]
RUNTIME = {"jax", "jaxlib", "numpy", "matplotlib", "scikit-image", "ipywidgets"}
# The lectures that draw in 3-D (ik.pictures.scene): the only ones whose cell brings VTK.
DRAW_3D = {"06_pose_targets_3d.ipynb", "07_workspace_maps.ipynb", "09_characters.ipynb"}


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
    assert {"lab", "grade", "scenes", "3d", "dev", "bench"} <= set(extras)
    assert "jupyterlab" in extras["lab"]
    assert {"nbformat", "nbclient", "ipykernel"} <= extras["grade"]
    assert extras["scenes"] == {"pyvista"}
    assert "pyvista" in extras["3d"]  # pyvista[jupyter]: trame and friends
    assert {"pytest", "pytest-xdist", "nbval", "hypothesis", "ikteach"} <= extras["dev"]
    assert "scenes" in next(r for r in pyproject()["project"]["optional-dependencies"]["dev"]
                            if _name(r) == "ikteach")  # the tests render scenes
    assert not (extras["lab"] | extras["grade"] | extras["3d"]) & RUNTIME


def test_lock_pins_every_runtime_dependency():
    versions = locked_versions()
    assert RUNTIME <= set(versions)
    assert "jupyterlab" in versions and "trame" in versions and "vtk" in versions


def test_binder_installs_the_package_with_lab_and_3d_extras_from_the_lock():
    requirements = [line.strip() for line in (ROOT / "binder" / "requirements.txt").read_text().splitlines()
                    if line.strip() and not line.startswith("#")]
    assert requirements == ["-c constraints.txt", ".[lab,3d]"]
    # The same runtime dependencies as pyproject (they come from it), at the locked versions.
    pins, locked = binder_pins(), locked_versions()
    for name in pyproject_runtime() | {"jupyterlab", "trame", "pyvista"}:
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


def _floor(name):
    """The lower bound pyproject.toml puts on a runtime dependency, as a version tuple."""
    requirement = next(r for r in pyproject()["project"]["dependencies"] if _name(r) == name)
    m = re.search(r">=\s*([\d.]+)", requirement)
    assert m, f"pyproject.toml: {name} has no lower bound"
    return tuple(int(v) for v in m.group(1).split("."))


def _version(text):
    return tuple(int(v) for v in re.match(r"[\d.]*\d", text).group(0).split("."))


def lock_closure(extras):
    """Every package uv.lock can install for ikteach with these extras (markers ignored: every
    Python and platform, so a package missing here is missing everywhere)."""
    packages = {}
    for package in tomllib.loads((ROOT / "uv.lock").read_text())["package"]:
        packages.setdefault(package["name"], []).append(package)
    seen, todo = set(), [("ikteach", tuple(extras))]
    while todo:
        name, wanted = todo.pop()
        if (name, wanted) in seen:
            continue
        seen.add((name, wanted))
        for package in packages[name]:
            deps = list(package.get("dependencies", []))
            for extra in wanted:
                deps += package.get("optional-dependencies", {}).get(extra, [])
            todo += [(dep["name"], tuple(dep.get("extra", ()))) for dep in deps]
    return {name for name, _ in seen}


def colab_requirement(path):
    """The requirement a notebook's first cell pip-installs on Colab: (package, extras)."""
    nb = json.loads(Path(path).read_text(encoding="utf-8"))
    first = next("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")
    m = re.search(r'%pip install --quiet "([\w-]+)(?:\[([\w,-]+)\])? @ ', first)
    assert m, f"{path.name}: no generated Colab cell"
    return m.group(1), tuple(m.group(2).split(",")) if m.group(2) else ()


def test_lock_walk_finds_vtk_through_the_scenes_extra_only():
    assert "vtk" in lock_closure(("scenes",)) and "trame" in lock_closure(("3d",))
    assert {"jax", "jaxlib", "numpy", "scipy"} <= lock_closure(())
    assert not {"vtk", "pyvista", "trame", "jupyterlab"} & lock_closure(())


@pytest.mark.parametrize("path", notebook_header.notebook_paths(ROOT),
                         ids=lambda p: p.relative_to(ROOT).as_posix())
def test_colab_cell_brings_vtk_only_to_lectures_that_draw_in_3d(path):
    package, extras = colab_requirement(path)
    assert package == "ikteach"
    pulls_vtk = "vtk" in lock_closure(extras)
    draws_3d = path.parent.name == "notebooks" and path.name in DRAW_3D
    assert pulls_vtk == draws_3d, f"{path.name}: extras {extras}"


def test_jax_floor_agrees_in_pyproject_colab_and_binder():
    floor = _floor("jax")
    assert _floor("jaxlib") == floor
    # Colab: the cell names the package alone (no jax pin of its own), so its floor is
    # pyproject's; that floor must not exceed Colab's jax, so that pip keeps Colab's jax, jaxlib
    # and CUDA plugin together (the plugin's metadata does not pin jaxlib: an upgrade of jax
    # alone would leave a mismatched plugin behind).
    for path in notebook_header.notebook_paths(ROOT):
        nb = json.loads(path.read_text(encoding="utf-8"))
        first = next("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")
        assert "jax" not in first.split("%pip install", 1)[1].split("\n", 1)[0], path.name
    assert floor <= _version(COLAB["jax"]) and floor <= _version(COLAB["jaxlib"])
    # Binder (binder/requirements.txt and, through it, environment.yml) installs the lock's jax.
    pins = binder_pins()
    assert pins["jax"] == pins["jaxlib"]
    assert all(_version(v) >= floor for v in pins["jax"])
