"""Committed notebooks: the generated first cell, no run noise, alt text on every matplotlib
figure; setup() prints its versions line."""
import base64
import json
import re
import shutil
from pathlib import Path

import pytest

from ikteach.pictures import alt_text
from ikteach.course import course_home, notebook, notebook_header, notebook_strip

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = notebook_header.notebook_paths(ROOT)
HOME = course_home.home(ROOT / "pyproject.toml")


def _load(path):
    return json.loads(Path(path).read_text(encoding="utf-8"))


def _first_code(nb):
    cell = next(c for c in nb["cells"] if c["cell_type"] == "code")
    return "".join(cell["source"])


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_first_code_cell_is_generated_from_the_course_home(path):
    nb = _load(path)
    source = _first_code(nb)
    extras = notebook_header.extras(nb)
    assert source.startswith(notebook_header.header(HOME, extras)), \
        f"{path.name}: first cell out of date, run `make header`"
    assert HOME.requirement_with(extras) in source


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_no_run_noise(path):
    assert notebook_strip.noise(_load(path)) == [], f"run `make strip` on {path.name}"


def test_badges_and_headers_are_up_to_date():
    assert notebook_header.update(ROOT, write=False) == [], "run `make header`"
    text = (ROOT / "notebooks" / "README.md").read_text(encoding="utf-8")
    assert notebook_header.missing_rows(text, ROOT) == []
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    for path in NOTEBOOKS:
        rel = path.relative_to(ROOT).as_posix()
        if not rel.startswith("instructor/"):
            assert HOME.colab_url(rel) in readme and HOME.binder_url(rel) in readme


def _copy_course(tmp_path):
    for rel in ("pyproject.toml", "README.md", "notebooks", "instructor"):
        src = ROOT / rel
        (shutil.copytree if src.is_dir() else shutil.copy)(src, tmp_path / rel)
    return tmp_path


def _new_notebook(path, first_source):
    nb = {"cells": [{"cell_type": "markdown", "metadata": {}, "source": ["# New"]},
                    {"cell_type": "code", "execution_count": None, "metadata": {}, "outputs": [],
                     "source": [first_source]}],
          "metadata": {}, "nbformat": 4, "nbformat_minor": 5}
    path.write_text(json.dumps(nb), encoding="utf-8")


def test_header_is_added_to_a_new_notebook_and_idempotent(tmp_path):
    root = _copy_course(tmp_path)
    new = root / "notebooks" / "09_new.ipynb"
    _new_notebook(new, "import ikteach as ik\nrng = ik.notebook.setup()")
    readme = root / "notebooks" / "README.md"
    readme.write_text(readme.read_text().replace("|---|---|\n", "|---|---|\n| `09_new.ipynb` | new |\n", 1))
    changed = notebook_header.update(root)
    assert new in changed and root / "README.md" in changed
    source = _first_code(_load(new))
    assert source == notebook_header.header(HOME) + "import ikteach as ik\nrng = ik.notebook.setup()"
    assert HOME.colab_url("notebooks/09_new.ipynb") in readme.read_text()
    assert notebook_header.update(root) == []  # a second run changes nothing


def test_header_follows_a_new_home(tmp_path):
    root = _copy_course(tmp_path)
    pyproject = root / "pyproject.toml"
    pyproject.write_text(pyproject.read_text().replace("ikteach-course/ikteach", "a-school/ik-course"))
    notebook_header.update(root)
    home = course_home.home(pyproject)
    for path in notebook_header.notebook_paths(root):
        source = _first_code(_load(path))
        assert source.count("%pip install") == 1
        assert re.search(r'"ikteach(\[scenes\])? @ git\+https://github\.com/a-school/ik-course@main"',
                         source)
    assert "github.com/ikteach-course" not in (root / "README.md").read_text()
    assert home.binder_url("notebooks/01_jacobian.ipynb") in (root / "notebooks" / "README.md").read_text()


def test_a_hand_edited_header_fails_the_check(tmp_path):
    root = _copy_course(tmp_path)
    path = notebook_header.notebook_paths(root)[0]
    nb = _load(path)
    cell = next(c for c in nb["cells"] if c["cell_type"] == "code")
    cell["source"] = ["".join(cell["source"]).replace("--quiet ", "")]
    path.write_text(json.dumps(nb), encoding="utf-8")
    assert path in notebook_header.update(root, write=False)


def _noisy_notebook():
    html = ('<img id="_anim_img0f1e2d3c4b5a49788a7b6c5d4e3f2a1b">'
            '<script>var anim0f1e2d3c4b5a49788a7b6c5d4e3f2a1b = 1;</script>')
    return {
        "cells": [{"cell_type": "code", "execution_count": 1, "id": "abc",
                   "metadata": {"execution": {"iopub.status.busy": "2026-11-22T01:00:00Z"},
                                "scrolled": True, "tags": ["keep-me"]},
                   "outputs": [{"output_type": "display_data", "metadata": {},
                                "data": {"text/plain": ["VBox()"],
                                         "application/vnd.jupyter.widget-view+json":
                                             {"model_id": "d166e049", "version_major": 2,
                                              "version_minor": 0}}},
                               {"output_type": "display_data", "metadata": {},
                                "data": {"text/html": [html]}},
                               {"output_type": "stream", "name": "stdout", "text": ["17 iterations\n"]},
                               {"output_type": "stream", "name": "stdout", "text": ["converged\n"]}],
                   "source": ["demo"]}],
        "metadata": {"language_info": {"name": "python", "version": "3.11.7"},
                     "widgets": {"application/vnd.jupyter.widget-state+json": {"state": {}}}},
        "nbformat": 4, "nbformat_minor": 5}


def test_strip_removes_run_noise_and_keeps_results():
    nb = _noisy_notebook()
    assert len(notebook_strip.noise(nb)) == 5
    notebook_strip.strip_notebook(nb)
    assert notebook_strip.noise(nb) == []
    cell = nb["cells"][0]
    assert cell["metadata"] == {"tags": ["keep-me"]}
    assert cell["outputs"][0]["data"] == {"text/plain": ["VBox()"]}
    assert cell["outputs"][2]["text"] == ["17 iterations\n", "converged\n"]  # one stream
    assert len(cell["outputs"]) == 3
    assert nb["metadata"] == {"language_info": {"name": "python"}}
    html = "".join(cell["outputs"][1]["data"]["text/html"])
    assert "0f1e2d3c4b5a49788a7b6c5d4e3f2a1b" not in html
    new_id = re.search(r"_anim_img([0-9a-f]{32})", html).group(1)
    assert f"var anim{new_id} = 1" in html  # every use of one id gets the same new id


def test_strip_is_deterministic_and_idempotent(tmp_path):
    a, b = _noisy_notebook(), _noisy_notebook()
    b["cells"][0]["outputs"][1]["data"]["text/html"] = [
        b["cells"][0]["outputs"][1]["data"]["text/html"][0].replace(
            "0f1e2d3c4b5a49788a7b6c5d4e3f2a1b", "99999999999940008000aaaaaaaaaaaa")]
    assert notebook_strip.strip_notebook(a) == notebook_strip.strip_notebook(b)  # another run
    path = tmp_path / "nb.ipynb"
    path.write_text(json.dumps(_noisy_notebook()))
    assert notebook_strip.strip_file(path) is True
    assert notebook_strip.strip_file(path) is False


def _images(nb):
    """(cell index, PNG bytes, alt or None) for each PNG image in the outputs."""
    for i, cell in enumerate(nb["cells"]):
        for output in cell.get("outputs", []):
            data = output.get("data", {})
            if "image/png" in data:
                png = base64.b64decode("".join(data["image/png"]))
                alt = output.get("metadata", {}).get("image/png", {}).get("alt")
                yield i, png, alt
            html = "".join(data.get("text/html", []))
            for tag in re.findall(r"<img\b[^>]*>", html):
                src = re.search(r'src="data:image/png;base64,([^"]+)"', tag)
                alt = re.search(r'alt="([^"]*)"', tag)
                if src:
                    yield i, base64.b64decode(src.group(1)), alt and alt.group(1)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_image_has_alt_text(path):
    images = list(_images(_load(path)))
    for i, png, alt in images:
        assert png.startswith(b"\x89PNG")
        assert alt, f"{path.name} cell {i}: an image without alt text"


def test_figure_alt_text_is_made_of_titles_and_labels():
    from matplotlib.figure import Figure

    fig = Figure()
    ax1, ax2 = fig.subplots(1, 2)
    fig.suptitle("DLS against λ")
    ax1.set(title="error", xlabel="iteration", ylabel="|e|")
    ax2.set_title("joint angles")
    assert alt_text.figure_alt(fig) == "DLS against λ: error (|e| against iteration); joint angles"
    html = alt_text.figure_html(fig)
    assert html.startswith('<img alt="DLS against λ: error (|e| against iteration); joint angles" ')
    png = base64.b64decode(re.search(r"base64,([^\"]+)", html).group(1))
    assert png.startswith(b"\x89PNG") and b"Matplotlib" in png[:400]
    assert alt_text.figure_alt(Figure()) == "Figure"
    assert alt_text.img_html(b"x", 'a "quoted" <b>').startswith('<img alt="a &quot;quoted&quot; &lt;b&gt;"')


def test_a_figure_in_a_notebook_is_shown_once_with_alt_text():
    """In a real kernel: a cell's figure is shown once, as an <img> with alt text."""
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(src) for src in (
        "import matplotlib.pyplot as plt, ikteach as ik\nrng = ik.notebook.setup()",
        "fig, ax = plt.subplots()\nax.plot([0, 1], [1, 0])\n_ = ax.set_title('a line')")]
    NotebookClient(nb, timeout=120, kernel_name="python3").execute()
    (shown,) = [out["data"] for out in nb.cells[1].outputs]
    assert shown["text/html"].startswith('<img alt="Figure: a line"')
    assert "image/png" not in shown


def test_setup_prints_one_versions_line(capsys):
    import platform

    import jax
    import numpy as np

    import ikteach

    notebook.setup()
    lines = capsys.readouterr().out.splitlines()
    assert lines == [f"versions: ikteach {ikteach.__version__}, jax {jax.__version__}, "
                     f"numpy {np.__version__}, python {platform.python_version()}"]
    # nbval compares it with the numbers replaced (tests/nbval_sanitize.cfg).
    cfg = (ROOT / "tests" / "nbval_sanitize.cfg").read_text()
    regex = re.search(r"\[versions line\]\nregex: (.*)\nreplace: (.*)", cfg)
    assert re.sub(regex.group(1), regex.group(2), lines[0]) == "versions: VERSIONS"


GENERIC_ALT = {"", "image", "figure", "animation", "gif"}


def _img_tags(nb):
    """(cell index, <img> tag) for every <img> in an HTML output: stills, the playing image of
    a JavaScript animation, GIFs, widget stills."""
    for i, cell in enumerate(nb["cells"]):
        for output in cell.get("outputs", []):
            for tag in re.findall(r"<img\b[^>]*>", "".join(output.get("data", {}).get("text/html", []))):
                yield i, tag


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_img_and_gif_says_what_it_shows(path):
    nb = _load(path)
    for i, tag in _img_tags(nb):
        alt = re.search(r'alt="([^"]*)"', tag)
        assert alt and alt.group(1).strip().lower() not in GENERIC_ALT, \
            f"{path.name} cell {i}: {tag[:80]} has no alt text that says what it shows"
    for i, cell in enumerate(nb["cells"]):
        for output in cell.get("outputs", []):
            assert "image/gif" not in output.get("data", {}), \
                f"{path.name} cell {i}: a bare GIF (no alt): show it with ik.pictures.plot.gif_view"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_no_output_loads_anything_from_the_network(path):
    """Committed outputs open offline (a lecture hall, a book from disk): no stylesheet, script
    or image from a URL, e.g. the font-awesome CDN of matplotlib's animation player."""
    for i, cell in enumerate(_load(path)["cells"]):
        for output in cell.get("outputs", []):
            page = "".join(output.get("data", {}).get("text/html", []))
            outside = re.findall(r"""(?:src|href)\s*=\s*["']?((?:https?:)?//[^"'\s>]+)""", page)
            assert not outside, f"{path.name} cell {i}: output loads {outside[:2]} from the network"
            assert not re.search(r'class="fa\b', page), f"{path.name} cell {i}: a font-awesome icon"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_a_widget_shows_a_still_where_no_kernel_runs_it(path):
    """A displayed widget's output carries an image (with alt text): never a bare 'VBox(...)'."""
    for i, cell in enumerate(_load(path)["cells"]):
        for output in cell.get("outputs", []):
            data = output.get("data", {})
            plain = "".join(data.get("text/plain", []))
            assert not re.match(r"(VBox|HBox|Box|Image|FloatSlider)\(", plain), \
                f"{path.name} cell {i}: a widget without a still ({plain[:40]})"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_notebook_links_the_one_notation_table(path):
    nb = json.loads(path.read_text(encoding="utf-8"))
    first = "".join(next(c for c in nb["cells"] if c["cell_type"] == "markdown")["source"])
    link = re.search(r"\[notation table\]\(([^)#]+)#notation\)", first.splitlines()[-1]).group(1)
    table = (path.parent / link).resolve()
    assert table == ROOT / "notebooks" / "README.md"
    assert '<a id="notation"></a>' in table.read_text(encoding="utf-8")


def _math(path):
    """The LaTeX in a notebook's Markdown cells ($...$ and $$...$$), one string."""
    cells = _load(path)["cells"]
    text = "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "markdown")
    return " ".join(re.findall(r"\$\$?(.+?)\$\$?", text, flags=re.S))


# the notation table's "one meaning each" for letters once used twice (issue 49, item 10)
ONE_MEANING = {"g": {"02_jacobian_transpose"}, "A": {"10_redundancy", "07_priority_step"},
               "C": {"05_singularities_out_of_reach"}, r"\\kappa": {"10_redundancy"}}


@pytest.mark.parametrize("symbol", ONE_MEANING)
def test_a_letter_with_one_meaning_is_written_only_where_the_table_says(symbol):
    pattern = re.compile(rf"(?<![\\A-Za-z]){symbol}(?![A-Za-z])")
    used = {p.stem for p in NOTEBOOKS if pattern.search(_math(p))}
    assert used <= ONE_MEANING[symbol] and used, (symbol, used)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_quick_jit_is_explained_before_a_lecture_first_prints_it(path):
    """One decorator in printed source (`@quick_jit`, never a bare jax.jit), and a word on it before it shows."""
    said = False
    for cell in _load(path)["cells"]:
        if cell["cell_type"] == "markdown":
            said = said or "`@quick_jit`" in "".join(cell["source"])
            continue
        shown = "".join("".join(o.get("text", "")) for o in cell.get("outputs", []))
        assert not re.search(r"^@(functools\.)?(partial\()?jax\.jit", shown, flags=re.M), path.name
        if re.search(r"^@(partial\()?quick_jit", shown, flags=re.M):
            assert said, f"{path.name}: prints @quick_jit before a Markdown cell says what it is"
            return


def test_every_lecture_title_is_written_the_same_way():
    """'# NN — Title' (one dash for the menu, the home page and the slides index alike)."""
    for path in (p for p in NOTEBOOKS if p.parent.name == "notebooks"):
        first = "".join(next(c for c in _load(path)["cells"] if c["cell_type"] == "markdown")["source"])
        assert re.match(rf"# {path.name[:2]} — \S", first), (path.name, first.splitlines()[0])
