"""The course as a static book: `make site` (or `ikteach site`).

    python -m ikteach.course.book [--out build/site]

Stages a Sphinx source folder (build/site-src) from what is committed, then runs Sphinx with
myst-nb and sphinx-book-theme (docs/conf.py) into build/site:

- the lecture notebooks and the exercise templates, as committed: never re-executed (the outputs
  nbval checks are the outputs students read); the instructor's solutions are never read;
- a home page (what the course teaches, one line and a picture per lecture), the notation table
  of notebooks/README.md, and the guides of docs/ (students, lecturers, maintainers);
- MathJax from the npm package (node_modules, `make node_modules`), copied into the site: the
  book opens from disk with no network (a lecture hall);
- the lectures' slides (ikteach.course.slides) in build/site/slides, linked from the home page
  and from each lecture's page.

The published folder holds pages and assets only: Sphinx's caches (.doctrees, .buildinfo)
are kept outside it (build/site-cache; the staged sources in build/site-src).

The staged copies (never the committed files) get a line of links at the top: "Open in Colab",
"Binder" and "download the notebook", from the course's home in pyproject.toml. A relative link
to a file of the repository that is not a page of the book points at the repository instead.
"""
import argparse
import base64
import html
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

if __package__:
    from .course_home import ROOT, home
    from .notebook_html import (ANIMATION_STILL, PLAYER, STILL, WIDGET, _source,  # noqa: F401
                                has_still, one_animation, rewrite_links, title)
else:  # run as a file: `make site` from the light site venv (no JAX: see the Makefile)
    from course_home import ROOT, home
    from notebook_html import (ANIMATION_STILL, PLAYER, STILL, WIDGET, _source,  # noqa: F401
                               has_still, one_animation, rewrite_links, title)

STAGE = ROOT / "build" / "site-src"  # beside(OUT, "src")
OUT = ROOT / "build" / "site"
TESTED = ROOT / "build" / "test-site"  # the book `make test` builds; the browser tests reuse it
MATHJAX = ROOT / "node_modules" / "mathjax" / "es5"
MATHJAX_FILES = ("tex-svg-full.js", "a11y", "ui", "sre", "adaptors")  # what the page may load
ORIGINALS = "_notebooks"  # the committed notebooks as they are, for "download the notebook"
GUIDES = ("students", "lecturers", "maintainers")
DATA_IMG = re.compile(r"<img\b[^>]*>")


def lectures(root=ROOT):
    return sorted((Path(root) / "notebooks").glob("*.ipynb"))


def exercises(root=ROOT):
    return sorted((Path(root) / "notebooks" / "exercises").glob("*.ipynb"))


def pages(root=ROOT):
    """{repository path: book path} for every file that is a page of the book."""
    root = Path(root)
    mapping = {p.relative_to(root).as_posix(): p.relative_to(root).as_posix()
               for p in lectures(root) + exercises(root)}
    mapping.update({f"docs/{g}.md": f"guides/{g}.md" for g in GUIDES})
    mapping["notebooks/README.md"] = "notation.md"
    mapping["README.md"] = "index.md"
    return mapping


def has_widgets(book):
    """True when an output is a widget or a widget's still (ikteach.pictures.stills)."""
    return any(has_still(cell) for cell in book["cells"])


def deck(repo_path):
    """The book path of a lecture's slides, or None (exercises have none)."""
    path = Path(repo_path)
    return f"slides/{path.stem}.slides.html" if path.parent.as_posix() == "notebooks" else None


def launch_cell(repo_path, h, widgets):
    """The Markdown cell put under a page's title: Colab, Binder, the notebook's download and,
    for a lecture, its slides."""
    original = os.path.relpath(f"{ORIGINALS}/{repo_path}", Path(repo_path).parent)
    text = (f"[Open in Colab]({h.colab_url(repo_path)}) · [Binder]({h.binder_url(repo_path)}) · "
            f"{{download}}`download the notebook <{original}>`")
    if deck(repo_path):
        text += f" · <a href=\"../{deck(repo_path)}\">the slides</a>"
    if widgets:
        text += ("\n\n*This page shows the interactive widgets as still pictures; the live "
                 "version needs a kernel: open the notebook on Colab, Binder or your laptop.*")
    return {"cell_type": "markdown", "metadata": {}, "source": text}


def stage_notebook(src, root, h, mapping):
    """The book's copy of a notebook: links fixed, the launch line under the title."""
    repo_path = src.relative_to(root).as_posix()
    book = json.loads(src.read_text(encoding="utf-8"))
    for cell in book["cells"]:
        if cell["cell_type"] == "markdown":
            cell["source"] = rewrite_links(_source(cell), repo_path, h, mapping)
        elif cell.get("outputs"):
            cell["outputs"] = one_animation(cell["outputs"])
    first = next(i for i, c in enumerate(book["cells"]) if c["cell_type"] == "markdown")
    book["cells"].insert(first + 1, launch_cell(repo_path, h, has_widgets(book)))
    for cell in book["cells"]:
        cell.pop("id", None)
    book["nbformat_minor"] = min(book.get("nbformat_minor", 4), 4)
    return book


def first_picture(book):
    """(PNG bytes, alt text) of the notebook's first picture with alt text, or None."""
    for cell in book["cells"]:
        for out in cell.get("outputs", []):
            data = out.get("data", {})
            png = data.get("image/png")
            alt = out.get("metadata", {}).get("image/png", {}).get("alt")
            if png and alt:
                return base64.b64decode("".join(png)), alt
            for tag in DATA_IMG.findall("".join(data.get("text/html", ""))):
                src = re.search(r'src="data:image/png;base64,([^"]+)"', tag)
                alt = re.search(r'alt="([^"]+)"', tag)
                if src and alt:
                    return base64.b64decode(src.group(1)), html.unescape(alt.group(1))
    return None


def lecture_lines(root=ROOT):
    """{notebook name: what it derives and checks}: the rows of notebooks/README.md's table."""
    text = (Path(root) / "notebooks" / "README.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\|\s*`(\d\d_[\w-]+\.ipynb)`[^|]*\|\s*((?:\\\||[^|])+?)\s*\|", text, re.M)
    return {name: line.replace("\\|", "|") for name, line in rows}


def home_page(root, h, thumbs):
    """index.md: what the course teaches, then one line and a picture per lecture."""
    lines = lecture_lines(root)
    out = ["# Inverse kinematics, derived and run", "",
           "Lecture notebooks and a small, tested Python module for the inverse-kinematics part "
           "of a computer-animation course. Each lecture derives one method on the board (the "
           "geometric Jacobian, Jacobian transpose with Buss's optimal step, the SVD "
           "pseudoinverse, damped least squares, and beyond), checks every claim numerically "
           "and animates the arm converging. Exercises are checked on the spot. Every page is "
           "the committed, executed notebook; open it on Colab or Binder to run it.", "",
           f"Source: [{h.github}]({h.repository}). Start with the "
           "[students' guide](guides/students.md).", "", "## Lectures", ""]
    for path in lectures(root):
        book = json.loads(path.read_text(encoding="utf-8"))
        out += [f"### [{title(book)}](notebooks/{path.name})", "",
                f'<a href="{deck(f"notebooks/{path.name}")}">Slides</a> for the lecture hall.', ""]
        if path.stem in thumbs:
            out += [f"![{thumbs[path.stem]}](_static/thumbs/{path.stem}.png)", ""]
        out += [lines.get(path.name, ""), ""]
    out += ["Every deck: <a href=\"slides/index.html\">the slides</a> (reveal.js, offline; "
            "<kbd>F</kbd> full screen, <kbd>S</kbd> the speaker's notes).", "", "## Exercises", ""]
    for path in exercises(root):
        book = json.loads(path.read_text(encoding="utf-8"))
        out.append(f"- [{title(book)}](notebooks/exercises/{path.name})")
    out += ["", toctree("Lectures", [f"notebooks/{p.stem}" for p in lectures(root)]),
            toctree("Exercises", [f"notebooks/exercises/{p.stem}" for p in exercises(root)]),
            toctree("Reference", ["notation"]),
            toctree("Guides", [f"guides/{g}" for g in GUIDES])]
    return "\n".join(out) + "\n"


def toctree(caption, entries):
    return "\n".join(["```{toctree}", ":hidden:", f":caption: {caption}", "", *entries, "```", ""])


KEEP_AS_IS = re.compile(r"(`[^`\n]*`|\]\([^)\n]*\)|</?[a-zA-Z][^>\n]*>)")  # code, a link's target, a tag


def literal_underscores(text):
    """Markdown text whose underscores show as written (A⁺_λ, J⁺_{1,λ}), not as emphasis;
    code spans, link targets and HTML tags are left alone."""
    parts = KEEP_AS_IS.split(text)
    return "".join(part if i % 2 else re.sub(r"(?<!\\)_", r"\\_", part)
                   for i, part in enumerate(parts))


def notation_page(root, h, mapping):
    """notation.md: the notation section of notebooks/README.md, symbols as written."""
    text = (Path(root) / "notebooks" / "README.md").read_text(encoding="utf-8")
    start = text.index('<a id="notation"></a>')
    section = text[start:].split("\n", 1)[1]
    section = re.sub(r"^## Notation.*$", "# Notation", section, count=1, flags=re.M)
    return literal_underscores(rewrite_links(section, "notebooks/README.md", h, mapping))


def copy_mathjax(static):
    (static / "mathjax").mkdir(parents=True, exist_ok=True)
    if not (MATHJAX / MATHJAX_FILES[0]).is_file():
        raise SystemExit(f"site: MathJax is missing ({MATHJAX}): run `make node_modules` "
                         "(npm ci: installs package-lock.json's MathJax and reveal.js)")
    for name in MATHJAX_FILES:
        src, dst = MATHJAX / name, static / "mathjax" / name
        (shutil.copytree if src.is_dir() else shutil.copy2)(src, dst)


def stage(root=ROOT, dest=STAGE):
    """Write the Sphinx source folder; returns it."""
    root, dest = Path(root), Path(dest)
    if not (root / "docs" / "conf.py").is_file():
        raise SystemExit(f"site: no docs/conf.py under {root}: build the book from a clone of "
                         "the course's repository")
    try:
        h = home(root / "pyproject.toml")
        h.github  # noqa: B018 - checks it is a GitHub repository URL
    except (KeyError, ValueError) as exc:
        raise SystemExit(f"site: name the course's repository in pyproject.toml, [project.urls] "
                         f"Repository = \"https://github.com/OWNER/NAME\" ({exc})") from None
    shutil.rmtree(dest, ignore_errors=True)
    (dest / "_static" / "thumbs").mkdir(parents=True)
    mapping = pages(root)
    thumbs = {}
    for src in lectures(root) + exercises(root):
        book = stage_notebook(src, root, h, mapping)
        target = dest / src.relative_to(root)
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(json.dumps(book, ensure_ascii=False), encoding="utf-8")
        original = dest / ORIGINALS / src.relative_to(root)
        original.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src, original)
        picture = first_picture(book) if src.parent.name == "notebooks" else None
        if picture:
            (dest / "_static" / "thumbs" / f"{src.stem}.png").write_bytes(picture[0])
            thumbs[src.stem] = picture[1].replace("[", "(").replace("]", ")")
    for guide in GUIDES:
        text = (root / "docs" / f"{guide}.md").read_text(encoding="utf-8")
        (dest / "guides").mkdir(exist_ok=True)
        (dest / "guides" / f"{guide}.md").write_text(
            rewrite_links(text, f"docs/{guide}.md", h, mapping), encoding="utf-8")
    (dest / "notation.md").write_text(notation_page(root, h, mapping), encoding="utf-8")
    (dest / "index.md").write_text(home_page(root, h, thumbs), encoding="utf-8")
    for name in ("book.css", "book.js", "favicon.svg"):
        shutil.copy2(root / "docs" / name, dest / "_static" / name)
    shutil.copy2(root / "docs" / "conf.py", dest / "conf.py")
    (dest / "course_home.json").write_text(json.dumps(
        {"repository": h.repository, "branch": h.branch}), encoding="utf-8")
    copy_mathjax(dest / "_static")
    return dest


def beside(out, what):
    """A working folder next to the output folder (build/site -> build/site-src): builds into
    different folders never share one."""
    return Path(out).parent / f"{Path(out).name}-{what}"


def sphinx(src, out, builder="html", quiet=True):
    """Run Sphinx on the staged folder; its caches (doctrees) go beside out, never into it."""
    shutil.rmtree(out, ignore_errors=True)  # nothing left over from an earlier build
    cmd = [sys.executable, "-m", "sphinx", "-b", builder, "-j", "auto", "-E",
           "-d", str(beside(out, "cache")), str(src), str(out)] + (["-q"] if quiet else [])
    subprocess.run(cmd, check=True)
    (Path(out) / ".buildinfo").unlink(missing_ok=True)  # the config's hash, nothing to read
    if (Path(out) / "_sources").is_dir() and not any((Path(out) / "_sources").iterdir()):
        (Path(out) / "_sources").rmdir()  # html_copy_source = False leaves it empty
    return Path(out)


# What a build reads besides the notebooks, the guides and docs/: the code that builds it, the
# versions it runs with (uv.lock, package-lock.json) and the course's home (pyproject.toml).
BUILT_FROM = ("README.md", "pyproject.toml", "uv.lock", "node_modules/.package-lock.json",
              "ikteach/course/book.py", "ikteach/course/slides.py",
              "ikteach/course/notebook_html.py", "ikteach/course/course_home.py")
BUILT_FROM_FOLDERS = ("notebooks", "docs", "ikteach/course/slides_template")


def inputs_digest(root=ROOT):
    """A digest of everything a build of the book reads (names and bytes), and of the Python
    that runs it: equal digests, the same book."""
    import hashlib

    root = Path(root)
    files = [root / name for name in BUILT_FROM]
    files += [p for folder in BUILT_FROM_FOLDERS for p in (root / folder).rglob("*")
              if p.is_file() and "__pycache__" not in p.parts and ".ipynb_checkpoints" not in p.parts]
    digest = hashlib.sha256(f"{sys.executable} {sys.version}".encode())
    for path in sorted(set(files)):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0")
        digest.update(path.read_bytes() if path.is_file() else b"(missing)")
        digest.update(b"\0")
    return digest.hexdigest()


def build(out=OUT, root=ROOT, quiet=True, reuse=False):
    """Stage and run Sphinx (docs/conf.py), then the lectures' slides into out/slides;
    returns the output folder. reuse: keep a book already in out that was built from the same
    inputs (inputs_digest, kept beside out: the browser tests reuse the one `make test` built)."""
    if __package__:
        from . import slides
    else:
        import slides
    out, digest = Path(out), inputs_digest(root)
    stamp = beside(out, "cache") / "inputs.sha256"
    if reuse and (out / "index.html").is_file() and stamp.is_file() and stamp.read_text() == digest:
        return out
    stamp.unlink(missing_ok=True)  # a build that stops half way is never reused
    out = sphinx(stage(root, beside(out, "src")), out, quiet=quiet)
    slides.build(lectures(root), out / "slides")
    stamp.write_text(digest)
    return out


PDF = ROOT / "build" / "book.pdf"
CHROMIUM = "/usr/bin/chromium"  # Debian's, as the browser tests use (make test-browser)


def pdf(out=PDF, root=ROOT, chromium=CHROMIUM, quiet=True):
    """One PDF of the whole book: Sphinx's singlehtml builder (every page on one page), printed by
    headless Chromium once MathJax has typeset it (no LaTeX). Returns the PDF's path."""
    if not Path(chromium).is_file():
        raise SystemExit(f"pdf: no Chromium at {chromium}: `make pdf` installs Debian's chromium")
    out = Path(out)
    single = out.parent / f"{out.stem}-single"  # build/book-single for build/book.pdf
    single = sphinx(stage(root, beside(single, "src")), single, builder="singlehtml", quiet=quiet)
    out.parent.mkdir(parents=True, exist_ok=True)
    subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                    "--disable-background-networking", "--no-pdf-header-footer",
                    "--virtual-time-budget=600000", "--run-all-compositor-stages-before-draw",
                    f"--print-to-pdf={out}", (single / "index.html").as_uri()],
                   check=True, capture_output=quiet)
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(prog="ikteach site", description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=OUT, help="output folder (build/site)")
    parser.add_argument("--pdf", action="store_true",
                        help="one PDF of the book instead (build/book.pdf; needs Chromium)")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    if args.pdf:
        path = pdf()
        print(f"pdf: {path} ({path.stat().st_size / 1e6:.1f} MB, "
              f"{time.perf_counter() - start:.0f} s)")
        return 0
    try:
        out = build(args.out)
    except subprocess.CalledProcessError as exc:
        print(f"site: sphinx-build failed (exit status {exc.returncode})", file=sys.stderr)
        return 1
    pages_built = len([p for p in out.rglob("*.html")
                       if p.relative_to(out).parts[0] not in ("_static", "slides")])
    decks = len(list((out / "slides").glob("*.slides.html")))
    print(f"site: {pages_built} pages and {decks} decks in {out} "
          f"({time.perf_counter() - start:.0f} s); open {out / 'index.html'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
