"""A term's release: `make header REF=v2026.1` points the launch links at a tag."""
import shutil
from pathlib import Path

import pytest

from ikteach.course import course_home, notebook_header

ROOT = Path(__file__).resolve().parents[1]


def test_with_branch_sets_only_the_course_branch():
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    new = course_home.with_branch(text, "v2026.1")
    assert new.count('"v2026.1"') == 1 and len(new.splitlines()) == len(text.splitlines())
    assert course_home.with_branch(new, course_home.home().branch) == text


@pytest.mark.parametrize("ref", ["", "v1 .0", "a..b", "-x", "v1.lock", 'v"1'])
def test_a_bad_ref_is_refused(ref):
    with pytest.raises(ValueError, match="ref"):
        course_home.with_branch("[tool.ikteach]\nbranch = \"main\"\n", ref)


def test_a_tag_goes_into_every_launch_link(tmp_path):
    root = tmp_path / "course"
    for rel in ("notebooks", "instructor"):
        shutil.copytree(ROOT / rel, root / rel)
    for rel in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / rel, root / rel)
    pyproject = root / "pyproject.toml"
    pyproject.write_text(course_home.with_branch(pyproject.read_text(), "v2026.1"))
    changed = notebook_header.update(root)
    assert root / "README.md" in changed and len(changed) > 10
    home = course_home.home(pyproject)
    first = notebook_header.notebook_paths(root)[0]
    assert f"git+{home.repository}@v2026.1" in first.read_text()
    assert home.colab_url("notebooks/01_jacobian.ipynb").endswith("/blob/v2026.1/notebooks/01_jacobian.ipynb")
    readme = (root / "README.md").read_text()
    assert "/blob/v2026.1/" in readme and "/blob/main/" not in readme
    assert notebook_header.update(root) == []
