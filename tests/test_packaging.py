"""environment.yml and pyproject.toml must list the same runtime dependencies."""
import re
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]


def _name(requirement):
    return re.split(r"[\s<>=!~;\[]", requirement.strip(), maxsplit=1)[0].lower().replace("_", "-")


def pyproject_runtime():
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    return {_name(r) for r in data["project"]["dependencies"]}


def environment_runtime():
    names, in_deps = set(), False
    for line in (ROOT / "environment.yml").read_text().splitlines():
        if line.startswith("dependencies:"):
            in_deps = True
            continue
        if in_deps and re.match(r"^  - [A-Za-z]", line):  # top-level conda entries only
            names.add(_name(line[4:]))
        elif in_deps and line and not line.startswith(" "):
            in_deps = False
    return names - {"python", "pip", "pip:"}


def test_environment_yml_matches_pyproject():
    assert environment_runtime() == pyproject_runtime()


def test_environment_yml_installs_the_package():
    assert re.search(r"^\s+- -e \.\s*$", (ROOT / "environment.yml").read_text(), re.M)


def test_ci_runs_the_readme_test_command():
    assert "make test" in (ROOT / "README.md").read_text()
    assert "make test" in (ROOT / ".ci" / "run").read_text()


def test_importing_ikteach_enables_float64():
    import jax.numpy as jnp

    import ikteach  # noqa: F401

    assert jnp.zeros(1).dtype == jnp.float64
