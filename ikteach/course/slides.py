"""Slides for the lecture hall: `make slides` (or `ikteach slides`).

    python -m ikteach.course.slides [--out build/site/slides] [NOTEBOOK ...]

One reveal.js deck per lecture notebook (nbconvert's slides exporter), from the committed
notebooks (never re-executed) and served from disk: reveal.js and MathJax come from
node_modules (`make node_modules`) and are copied next to the decks; nothing loads from another
site. The slide metadata is decided here, at build time, on a copy of each notebook (the
committed notebooks are never changed), by these rules:

- a Markdown cell that starts with a heading starts a new slide;
- a long Markdown cell (a derivation) is split at its paragraphs into sub-slides (down arrow),
  each at most one screen (`BUDGET` lines at 1280 x 720);
- a code cell with its output is a fragment of the slide it fits on, else a sub-slide of its own;
  one taller than a slide is shown in parts, each on its own sub-slide: its source (a long one
  cut at blank lines), then its outputs (each picture, or animation, alone; long printed output
  in parts), so that no slide is shrunk much and nothing hides in a scroll box
  (slides_template shrinks what still overflows, a little);
- an animation is shown once (its player, not the still before it);
- the first slide links the notebook live (Colab, Binder, `make lab`), and so does each widget's
  still (a picture of a slider or a map that moves only in a kernel);
- the generated Colab set-up block of the first code cell is not shown.
The same notebook always gives the same deck. `index.html` lists the decks.
"""
import argparse
import copy
import html
import json
import math
import shutil
import sys
from pathlib import Path

if __package__:
    from .notebook_html import has_still, one_animation, rewrite_links, title
    from .course_home import ROOT, home
else:  # run as a file: `make slides` from the light site venv (no JAX: see the Makefile)
    from notebook_html import has_still, one_animation, rewrite_links, title
    from course_home import ROOT, home


HOME = home()
OUT = ROOT / "build" / "site" / "slides"  # next to the book's pages: published with them
NODE = ROOT / "node_modules"
TEMPLATES = Path(__file__).resolve().parent / "slides_template"
BUDGET = 20         # lines of prose (20 px, 30 px apart) that fit on one 1280 x 720 slide
LINE_CHARS = 95     # characters per line of prose on a slide
PICTURE_LINES = 14  # a figure or animation, shrunk to at most 430 px (slides_template)
CODE_LINE = 0.8     # a line of code (17 px) or of printed output (14 px), in lines of prose
SOURCE_CHARS = 105  # characters of code on one line of a slide; a longer line wraps
OUTPUT_CHARS = 125  # characters of printed output on one line
SOURCE_PART = 18    # at most this many lines of a long cell's source on one sub-slide
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


def wrapped(text, width):
    """Lines the text takes where lines longer than width characters wrap."""
    return sum(max(1, math.ceil(len(line) / width)) for line in text.splitlines())


def _text(out):
    """The printed text of an output (a stream or a plain-text result), or None."""
    if "text" in out:
        return "".join(out["text"])
    data = out.get("data", {})
    if "text/plain" in data and not _is_picture(out):
        return "".join(data["text/plain"])
    return None


def _is_picture(out):
    data = out.get("data", {})
    return "image/png" in data or "<img" in "".join(data.get("text/html", ""))


def output_lines(cell):
    """Estimated lines a code cell's outputs take."""
    lines = 0
    for out in cell.get("outputs", []):
        text = _text(out)
        if _is_picture(out):
            lines += PICTURE_LINES
        elif text is not None:
            lines += CODE_LINE * wrapped(text, OUTPUT_CHARS)
    return lines


def source_lines(source):
    return CODE_LINE * wrapped(source, SOURCE_CHARS) + 1 if source.strip() else 0


def code_lines(cell):
    hidden = cell.get("metadata", {}).get("transient", {}).get("remove_source")
    return (0 if hidden else source_lines(_source(cell))) + output_lines(cell)


def source_parts(source, most=SOURCE_PART):
    """A long source cut into parts of at most `most` lines, at a blank line where one is near."""
    lines, parts = source.rstrip("\n").split("\n"), []
    while len(lines) > most:
        blanks = [i for i in range(most // 2, most + 1) if not lines[i].strip()]
        cut = blanks[-1] if blanks else most
        parts.append("\n".join(lines[:cut]).strip("\n"))
        lines = lines[cut:]
    parts.append("\n".join(lines).strip("\n"))
    return [part for part in parts if part]


def text_parts(out, most):
    """A printed output cut into outputs of at most `most` estimated lines each."""
    lines, parts, current = _text(out).splitlines(keepends=True), [], []
    for line in lines:
        if current and CODE_LINE * wrapped("".join(current + [line]), OUTPUT_CHARS) > most:
            parts.append(current)
            current = []
        current.append(line)
    parts.append(current)
    pieces = []
    for part in parts:
        piece = copy.deepcopy(out)
        if "text" in piece:
            piece["text"] = "".join(part)
        else:
            piece["data"] = {"text/plain": "".join(part)}
        pieces.append(piece)
    return pieces


def _only_outputs(cell, outputs):
    piece = copy.deepcopy(cell)
    piece["outputs"] = outputs
    piece.setdefault("metadata", {})["transient"] = {"remove_source": True}
    return piece


def cell_parts(cell):
    """A code cell as parts that each fit on a slide: the cell itself when it fits, else its
    source (in parts) and then its outputs, each picture alone, long text in parts."""
    cell = copy.deepcopy(cell)
    cell["outputs"] = one_animation(cell.get("outputs", []))
    if code_lines(cell) <= BUDGET:
        return [cell]
    parts = []
    for source in source_parts(_source(cell)):
        part = copy.deepcopy(cell)
        part["source"], part["outputs"] = source, []
        parts.append(part)
    group = []
    for out in cell["outputs"]:
        pieces = [out] if _is_picture(out) or _text(out) is None else text_parts(out, BUDGET - 1)
        for piece in pieces:
            if group and (_is_picture(piece) or output_lines({"outputs": group + [piece]}) > BUDGET):
                parts.append(_only_outputs(cell, group))
                group = []
            group.append(piece)
            if _is_picture(piece):
                parts.append(_only_outputs(cell, group))
                group = []
    if group:
        parts.append(_only_outputs(cell, group))
    return parts


def live_links(repo_path):
    """Markdown: where to run the notebook live."""
    return (f"[Open in Colab]({HOME.colab_url(repo_path)}) · [Binder]({HOME.binder_url(repo_path)})"
            f" · on your laptop: `make lab`, then open `{repo_path}`")


def overflows(used, lines):
    """True when lines more do not fit on a slide already holding `used` (not just a heading)."""
    return used + lines > BUDGET and used > HEADING_ONLY


def _cell(source, slide_type):
    return {"cell_type": "markdown", "metadata": {"slideshow": {"slide_type": slide_type}},
            "source": source}


def slide_cells(book, repo_path="notebooks/x.ipynb"):
    """The notebook's cells with slide metadata, long Markdown cells split, long code cells in
    parts, the live links on the first slide and under each widget's still; a new list."""
    out, used = [], BUDGET  # the first cell always starts a slide
    first_code, linked = True, False
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
                if not linked:  # under the title: run it live
                    linked = True
                    out.append(_cell("Run it live: " + live_links(repo_path), "-"))
                    used += 1.5
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
        for part in cell_parts(cell):
            lines = code_lines(part)
            if overflows(used, lines):
                kind, used = "subslide", lines
            else:
                kind, used = "fragment", used + lines
            part.setdefault("metadata", {})["slideshow"] = {"slide_type": kind}
            out.append(part)
        if has_still(cell):
            out.append(_cell("*A still: the live widget runs in a kernel* — "
                             + live_links(repo_path), "-"))
            used += 1.5
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
    other_themes = shutil.ignore_patterns(*[p.name for p in (reveal / "dist" / "theme").glob("*.css")
                                            if p.name != "white.css"])  # some load web fonts
    shutil.copytree(reveal / "dist", out / "reveal.js" / "dist", dirs_exist_ok=True,
                    ignore=other_themes)
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


def index_page(decks):
    """index.html: a link to every deck (by the notebook's title) in the folder."""
    items = "\n".join(f'<li><a href="{html.escape(deck.name)}">{html.escape(name)}</a></li>'
                      for deck, name in decks)
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
            "<title>ikteach: the slides</title>\n<style>body { font: 20px/1.5 sans-serif; "
            "max-width: 40em; margin: 2em auto; padding: 0 1em; }</style></head>\n"
            "<body><main><h1>ikteach: the slides</h1>\n<p>One deck per lecture; press "
            "<kbd>F</kbd> for full screen, <kbd>S</kbd> for the speaker's notes. Each deck's "
            "notebook, to read at your pace: <a href=\"../index.html\">the book</a>.</p>\n"
            f"<ol>\n{items}\n</ol></main></body></html>\n")


def build(notebooks=None, out=OUT):
    """One deck per notebook (default: every lecture) and index.html; returns the decks' paths."""
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
    titles = [(deck, title(json.loads(path.read_text(encoding="utf-8"))))
              for deck, path in zip(decks, notebooks)]
    (out / "index.html").write_text(index_page(titles), encoding="utf-8")
    return decks


def main(argv=None):
    parser = argparse.ArgumentParser(prog="ikteach slides", description=__doc__.split("\n")[0])
    parser.add_argument("notebooks", nargs="*", metavar="NOTEBOOK",
                        help="lecture notebooks (default: every one in notebooks/)")
    parser.add_argument("--out", type=Path, default=OUT, help="output folder (build/site/slides)")
    args = parser.parse_args(argv)
    missing = [p for p in args.notebooks if not Path(p).is_file()]
    if missing:
        parser.error(f"NOTEBOOK: no such file: {', '.join(missing)}")
    for deck in build(args.notebooks, args.out):
        print(f"wrote {deck}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
