"""make slides: slide metadata decided at build time (the committed notebooks untouched), and a
deck that loads reveal.js and MathJax from next to itself."""
import json
import re
from pathlib import Path

from ikteach.course import slides

ROOT = Path(__file__).resolve().parents[1]
LECTURE = ROOT / "notebooks" / "04_damped_least_squares.ipynb"


def _notebook(*cells):
    return {"cells": [{"cell_type": kind, "metadata": {}, "source": source,
                       **({"outputs": outputs, "execution_count": 1} if kind == "code" else {})}
                      for kind, source, outputs in cells],
            "metadata": {}, "nbformat": 4, "nbformat_minor": 5}


def _kinds(book):
    return [cell["metadata"]["slideshow"]["slide_type"] for cell in slides.slide_cells(book)]


def test_headings_start_slides_and_code_is_a_fragment():
    book = _notebook(("markdown", "# Title\n\nOne line.", None),
                     ("code", slides.SETUP + "\nimport sys", []),
                     ("markdown", "## Section\n\nA short paragraph.", None),
                     ("code", "x = 1\nprint(x)", [{"output_type": "stream", "name": "stdout",
                                                   "text": "1\n"}]))
    assert _kinds(book) == ["slide", "-", "-", "skip", "slide", "-", "fragment"]


def test_the_first_slide_links_the_notebook_live():
    book = _notebook(("markdown", "# Title\n\nOne line.", None))
    cells = slides.slide_cells(book, "notebooks/04_damped_least_squares.ipynb")
    text = cells[1]["source"]
    assert cells[1]["metadata"]["slideshow"]["slide_type"] == "-"
    home = slides.HOME
    assert home.colab_url("notebooks/04_damped_least_squares.ipynb") in text
    assert home.binder_url("notebooks/04_damped_least_squares.ipynb") in text
    assert "make lab" in text


def _stream(lines):
    return {"output_type": "stream", "name": "stdout",
            "text": "".join(f"line {i}\n" for i in range(lines))}


def _picture():
    return {"output_type": "display_data", "metadata": {},
            "data": {"image/png": "iVBOR", "text/plain": "<Figure>"}}


def test_a_cell_taller_than_a_slide_is_shown_in_parts_that_fit():
    source = "\n".join(f"x{i} = {i}" + ("\n" if i % 6 == 5 else "") for i in range(40))
    book = _notebook(("markdown", "# T", None),
                     ("code", source, [_stream(60), _picture(), _stream(3), _picture()]))
    cells = [c for c in slides.slide_cells(book) if c["cell_type"] == "code"]
    assert all(slides.code_lines(c) <= slides.BUDGET for c in cells)
    shown = [c for c in cells if not c["metadata"].get("transient")]
    assert "\n".join(c["source"] for c in shown).split() == source.split()  # all of it, in order
    outputs = [o for c in cells if c["metadata"].get("transient") for o in c["outputs"]]
    printed = "".join(o.get("text", "") for o in outputs)
    assert printed == _stream(60)["text"] + _stream(3)["text"]
    pictures = [c for c in cells if any("image/png" in o.get("data", {}) for o in c["outputs"])]
    assert len(pictures) == 2 and all(len(c["outputs"]) == 1 for c in pictures)


def test_a_cell_that_fits_stays_whole():
    cell = _notebook(("code", "x = 1", [_stream(3)]))["cells"][0]
    assert slides.cell_parts(cell) == [cell]


def test_an_animation_is_shown_once_and_widget_stills_link_the_live_notebook():
    still = {"output_type": "display_data", "metadata": {},
             "data": {"text/html": '<img alt="Still frame of an animation. x" src="data:,">'}}
    player = {"output_type": "display_data", "metadata": {},
              "data": {"text/html": '<div class="animation"><input type="range" class="anim-slider"></div>'}}
    widget = {"output_type": "display_data", "metadata": {},
              "data": {"text/html": "<img alt='a map' src='data:,'> (a still: run the notebook)"}}
    book = _notebook(("markdown", "# T", None), ("code", "show(anim)", [still, player]),
                     ("code", "live", [widget]))
    cells = slides.slide_cells(book)
    anim = next(c for c in cells if c["cell_type"] == "code" and c["source"] == "show(anim)")
    assert len(anim["outputs"]) == 1 and 'aria-label="Animation frame"' in anim["outputs"][0]["data"]["text/html"]
    after = cells[[c["source"] for c in cells].index("live") + 1]
    assert after["cell_type"] == "markdown" and "make lab" in after["source"]


def test_a_long_derivation_continues_on_sub_slides():
    steps = "\n\n".join(f"Step {i}: " + "words " * 60 + f"\n$$\nx_{i} = y_{i}\n$$" for i in range(8))
    kinds = _kinds(_notebook(("markdown", "## Derivation\n\n" + steps, None)))
    assert kinds[0] == "slide" and kinds.count("subslide") >= 2
    assert set(kinds[1:]) <= {"-", "subslide"}


def test_display_math_is_never_cut():
    text = "Before.\n\n$$\na = b\n\nc = d\n$$\n\nAfter."
    assert slides.paragraphs(text) == ["Before.", "$$\na = b\nc = d\n$$", "After."]


def test_slides_are_decided_on_a_copy_the_same_every_time():
    committed = LECTURE.read_text(encoding="utf-8")
    book = json.loads(committed)
    first, second = slides.slide_notebook(book), slides.slide_notebook(book)
    assert first == second
    assert LECTURE.read_text(encoding="utf-8") == committed
    kinds = [c["metadata"]["slideshow"]["slide_type"] for c in first["cells"]]
    headings = sum(1 for c in book["cells"] if c["cell_type"] == "markdown"
                   and "".join(c["source"]).lstrip().startswith("#"))
    assert kinds.count("slide") >= headings and "subslide" in kinds


def test_a_deck_loads_its_scripts_from_next_to_itself(tmp_path):
    deck, = slides.build([LECTURE], tmp_path)
    assert f'href="{deck.name}"' in (tmp_path / "index.html").read_text(encoding="utf-8")
    text = deck.read_text(encoding="utf-8")
    sources = re.findall(r'<script[^>]+src="([^"]+)"', text)
    assert "reveal.js/dist/reveal.js" in sources and "mathjax/tex-svg-full.js" in sources
    for src in sources:
        assert not re.match(r"(https?:)?//", src), src
        assert (tmp_path / src).is_file(), src
    for href in re.findall(r'<link[^>]+href="([^"]+)"', text):
        if not re.match(r"(https?:)?//|data:", href):
            assert (tmp_path / href).is_file(), href
    assert "unpkg.com" not in text and "cdnjs" not in text and "require.js" not in text
