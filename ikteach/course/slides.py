"""Slides for the lecture hall: `make slides` (or `ikteach slides`).

    python -m ikteach.course.slides [--out build/slides] [NOTEBOOK ...]

One reveal.js deck per lecture notebook (nbconvert's slides exporter), from the committed
notebooks (never re-executed) and served from disk: reveal.js and MathJax come from
node_modules (`make node_modules`) and are copied next to the decks; nothing loads from another
site. The slide metadata is decided here, at build time, on a copy of each notebook (the
committed notebooks are never changed), by these rules:

- a Markdown cell that starts with a heading starts a new slide;
- a long Markdown cell (a derivation) is split at its paragraphs into sub-slides (down arrow),
  each at most one screen (`BUDGET` lines at 1280 x 720);
- a code cell with its output is a fragment of the slide it fits on, else a sub-slide of its own
  (one taller than a slide is shrunk to fit it when shown: slides_template);
- the generated Colab set-up block of the first code cell is not shown.
The same notebook always gives the same deck.
"""
import argparse
import copy
import json
import math
import shutil
import sys
from pathlib import Path

from .book import rewrite_links
from .course_home import ROOT, home


HOME = home()
OUT = ROOT / "build" / "slides"
NODE = ROOT / "node_modules"
TEMPLATES = Path(__file__).resolve().parent / "slides_template"
BUDGET = 20         # lines of prose (20 px, 30 px apart) that fit on one 1280 x 720 slide
LINE_CHARS = 95     # characters per line of prose on a slide
PICTURE_LINES = 14  # a figure or animation, shrunk to at most 430 px (slides_template)
CODE_LINE = 0.8     # a line of code (17 px) or of printed output (14 px), in lines of prose
HEADING_ONLY = 3    # a slide holding only its heading takes what follows, even if it overflows
SETUP = "# Course setup, generated from pyproject.toml"


def _source(cell):
    source = cell.get("source", "")
    return "".join(source) if isinstance(source, list) else source


def paragraphs(text):
    """Markdown text cut at blank lines, never inside a $$ ... $$ block or a code fence."""
    out, current, fenced = [], [], False
    for line in text.split("\n"):
        if not line.strip() and not fenced and current:
            out.append("\n".join(current))
            current = []
            continue
        if line.strip():
            current.append(line)
        fenced ^= (line.count("$$") % 2 == 1) ^ line.strip().startswith("```")
    if current:
        out.append("\n".join(current))
    return out


def markdown_lines(text):
    """Estimated lines a Markdown paragraph takes on a slide."""
    lines = 0
    for line in text.split("\n"):
        if line.startswith("#"):
            lines += 2
        elif line.strip() == "$$":
            lines += 0.5  # a display's fence: its margin
        elif "$$" in line or line.strip().startswith("\\"):
            lines += 1.2
        else:
            lines += max(1, math.ceil(len(line) / LINE_CHARS))
    return lines + 0.5


def output_lines(cell):
    """Estimated lines a code cell's outputs take."""
    lines = 0
    for out in cell.get("outputs", []):
        data = out.get("data", {})
        if "image/png" in data or "<img" in "".join(data.get("text/html", "")):
            lines += PICTURE_LINES
        elif "text" in out:
            lines += CODE_LINE * len("".join(out["text"]).splitlines())
        elif "text/plain" in data:
            lines += CODE_LINE * len("".join(data["text/plain"]).splitlines())
    return lines


def code_lines(cell):
    return CODE_LINE * len(_source(cell).splitlines()) + 1 + output_lines(cell)


def overflows(used, lines):
    """True when lines more do not fit on a slide already holding `used` (not just a heading)."""
    return used + lines > BUDGET and used > HEADING_ONLY


def _cell(source, slide_type):
    return {"cell_type": "markdown", "metadata": {"slideshow": {"slide_type": slide_type}},
            "source": source}


def slide_cells(book, repo_path="notebooks/x.ipynb"):
    """The notebook's cells with slide metadata, long Markdown cells split; a new list."""
    out, used = [], BUDGET  # the first cell always starts a slide
    first_code = True
    for cell in book["cells"]:
        cell = copy.deepcopy(cell)
        if cell["cell_type"] == "markdown":
            for part in paragraphs(rewrite_links(_source(cell), repo_path, HOME, {})):
                lines = markdown_lines(part)
                if part.startswith("#"):
                    kind, used = "slide", lines
                elif overflows(used, lines):
                    kind, used = "subslide", lines
                else:
                    kind, used = "-", used + lines
                out.append(_cell(part, kind))
            continue
        if cell["cell_type"] != "code":
            continue
        source = _source(cell)
        if first_code:
            first_code = False
            if source.startswith(SETUP):
                cell.setdefault("metadata", {})["slideshow"] = {"slide_type": "skip"}
                out.append(cell)
                continue
        lines = code_lines(cell)
        if overflows(used, lines):
            kind, used = "subslide", lines
        else:
            kind, used = "fragment", used + lines
        cell.setdefault("metadata", {})["slideshow"] = {"slide_type": kind}
        out.append(cell)
    return out


def slide_notebook(book, repo_path="notebooks/x.ipynb"):
    """A copy of the notebook, ready for nbconvert's slides exporter (links to the repository)."""
    book = copy.deepcopy(book)
    book["cells"] = slide_cells(book, repo_path)
    for number, cell in enumerate(book["cells"]):
        cell["id"] = f"slide-cell-{number}"  # new cells (split Markdown) need ids too
    book["nbformat_minor"] = max(book.get("nbformat_minor", 5), 5)
    return book


def copy_assets(out):
    """reveal.js and MathJax next to the decks."""
    reveal, mathjax = NODE / "reveal.js", NODE / "mathjax" / "es5"
    if not (reveal / "dist" / "reveal.js").is_file() or not mathjax.is_dir():
        raise SystemExit(f"slides: reveal.js or MathJax missing in {NODE}: run "
                         "`make node_modules` (npm ci: installs package-lock.json)")
    shutil.copytree(reveal / "dist", out / "reveal.js" / "dist", dirs_exist_ok=True)
    shutil.copytree(reveal / "plugin" / "notes", out / "reveal.js" / "plugin" / "notes",
                    dirs_exist_ok=True)
    for name in ("tex-svg-full.js", "a11y", "ui", "sre", "adaptors"):
        src, dst = mathjax / name, out / "mathjax" / name
        dst.parent.mkdir(parents=True, exist_ok=True)
        (shutil.copytree(src, dst, dirs_exist_ok=True) if src.is_dir()
         else shutil.copy2(src, dst))


def exporter():
    from nbconvert import SlidesExporter

    return SlidesExporter(template_file="ikteach_slides.html.j2",
                          extra_template_paths=[str(TEMPLATES)],
                          reveal_url_prefix="reveal.js", reveal_theme="white",
                          reveal_width="1280", reveal_height="720", reveal_number="c/t",
                          exclude_input_prompt=True, exclude_output_prompt=True)


def build(notebooks=None, out=OUT):
    """One deck per notebook (default: every lecture); returns the decks' paths."""
    import nbformat

    notebooks = [Path(p) for p in notebooks] if notebooks else \
        sorted((ROOT / "notebooks").glob("*.ipynb"))
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    copy_assets(out)
    export, decks = exporter(), []
    for path in notebooks:
        book = slide_notebook(json.loads(path.read_text(encoding="utf-8")),
                              path.resolve().relative_to(ROOT).as_posix())
        body, _ = export.from_notebook_node(nbformat.reads(json.dumps(book), as_version=4),
                                            resources={"metadata": {"name": path.stem}})
        deck = out / f"{path.stem}.slides.html"
        deck.write_text(body, encoding="utf-8")
        decks.append(deck)
    return decks


def main(argv=None):
    parser = argparse.ArgumentParser(prog="ikteach slides", description=__doc__.split("\n")[0])
    parser.add_argument("notebooks", nargs="*", metavar="NOTEBOOK",
                        help="lecture notebooks (default: every one in notebooks/)")
    parser.add_argument("--out", type=Path, default=OUT, help="output folder (build/slides)")
    args = parser.parse_args(argv)
    missing = [p for p in args.notebooks if not Path(p).is_file()]
    if missing:
        parser.error(f"NOTEBOOK: no such file: {', '.join(missing)}")
    for deck in build(args.notebooks, args.out):
        print(f"wrote {deck}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
