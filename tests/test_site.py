"""The course's book (make site), built once here from the committed notebooks: a page per
lecture and exercise, no solution text, alt text on every image, every internal link and asset
resolves, nothing loaded from another site. The browser half is tests/browser/site_book.py."""
import html
import json
import re
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

from ikteach.course import book, course_home
from ikteach.course.exercises import solution_lines

ROOT = Path(__file__).resolve().parents[1]
HOME = course_home.home(ROOT / "pyproject.toml")
MIN_SOLUTION_CHARS = 16  # shorter solution lines ("return delta", "}") occur in any code


class Page(HTMLParser):
    """The tags of one HTML page that matter here."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.images, self.links, self.ids, self.external = [], [], set(), []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if "id" in attrs:
            self.ids.add(attrs["id"])
        if tag == "img":
            self.images.append(attrs)
        url = attrs.get("src") if tag in ("img", "script") else attrs.get("href")
        if url is None:
            return
        if re.match(r"https?:|//", url):
            if tag == "script" or (tag == "link" and "stylesheet" in attrs.get("rel", "")):
                self.external.append(url)
        elif not re.match(r"[a-z]+:", url):
            self.links.append(url)


@pytest.fixture(scope="module")
def site():
    """Built here every time, into build/test-site: the browser tests read the same book."""
    return book.build(book.TESTED)


@pytest.fixture(scope="module")
def pages(site):
    parsed = {}
    for path in site.rglob("*.html"):
        if {"_static", "slides"} & set(path.relative_to(site).parts):
            continue  # the theme's own files (e.g. a template) and the decks, not pages
        page = Page()
        page.feed(path.read_text(encoding="utf-8"))
        parsed[path] = page
    return parsed


def page_text(path):
    """What a reader sees of a page: tags removed, entities decoded, spaces collapsed."""
    text = re.sub(r"<[^>]+>", "", path.read_text(encoding="utf-8"))
    return re.sub(r"[ \t]+", " ", html.unescape(text))


def solution_texts():
    """Every solution line of instructor/solutions/ long enough to be the answer's own."""
    lines = set()
    for path in sorted((ROOT / "instructor" / "solutions").glob("*.ipynb")):
        for cell in json.loads(path.read_text(encoding="utf-8"))["cells"]:
            source = "".join(cell["source"])
            lines |= {re.sub(r"\s+", " ", line) for line in solution_lines(source)}
    return sorted(line for line in lines if len(line) >= MIN_SOLUTION_CHARS)


def leaks(text, lines):
    return [line for line in lines if line in text]


def test_every_lecture_and_exercise_has_a_page(site):
    for path in book.lectures(ROOT) + book.exercises(ROOT):
        page = site / path.relative_to(ROOT).with_suffix(".html")
        assert page.is_file(), page
        title = book.title(json.loads(path.read_text(encoding="utf-8")))
        assert html.escape(title, quote=False) in page.read_text(encoding="utf-8"), title
    for name in ("index", "notation", "search", "guides/students", "guides/lecturers",
                 "guides/maintainers"):
        assert (site / f"{name}.html").is_file(), name


def test_every_page_links_colab_binder_and_its_download(site):
    for path in book.lectures(ROOT) + book.exercises(ROOT):
        rel = path.relative_to(ROOT).as_posix()
        text = (site / rel).with_suffix(".html").read_text(encoding="utf-8")
        assert html.escape(HOME.colab_url(rel)) in text and html.escape(HOME.binder_url(rel)) in text
        download = re.search(r'href="([^"]*_downloads/[^"]+)"', text)
        assert download, f"{rel}: no download link"
        copy = (site / rel).parent / unquote(download.group(1))
        assert copy.read_bytes() == path.read_bytes(), f"{rel}: the download is not the notebook"


def test_no_solution_text_anywhere(site):
    lines = solution_texts()
    assert len(lines) > 20  # the solutions are there to compare with
    assert not list(site.rglob("instructor"))
    for path in site.rglob("*.html"):
        assert leaks(page_text(path), lines) == [], path.relative_to(site)
    assert leaks((site / "searchindex.js").read_text(encoding="utf-8"), lines) == []
    for path in site.rglob("*.ipynb"):  # the downloads
        assert leaks(path.read_text(encoding="utf-8"), lines) == [], path.relative_to(site)


def test_the_leak_check_finds_a_solution_line():
    lines = solution_texts()
    assert leaks(f"<p>some page</p>\n{lines[0]}\n", lines) == [lines[0]]


# What a page shows as prose once code, scripts and MathJax's own math elements are left out.
NOT_PROSE = re.compile(r"<(pre|script|style|code|textarea)\b.*?</\1>"
                       r"|<(span|div) class=\"math\b[^\"]*\">.*?</\2>", re.S)
RAW_TEX = re.compile(r"\$|\\[a-zA-Z]+")


def raw_tex(page_html):
    """TeX a reader would see as text: a dollar or a \\command outside math and code."""
    prose = html.unescape(re.sub(r"<[^>]+>", " ", NOT_PROSE.sub(" ", page_html)))
    return [prose[max(0, m.start() - 30):m.end() + 30] for m in RAW_TEX.finditer(prose)]


def test_no_raw_tex_outside_math_and_code(pages):
    found = {path.name: raw_tex(path.read_text(encoding="utf-8"))[:2] for path in pages}
    assert {name: tex for name, tex in found.items() if tex} == {}
    text = (next(p for p in pages if p.name == "08_methods_compared.html")).read_text(
        encoding="utf-8")
    assert "(Buss &amp; Kim write" in NOT_PROSE.sub("", text)  # prose stays prose, not math


def test_the_raw_tex_check_finds_tex_in_prose():
    page = ('<p>keep <span class="math notranslate nohighlight">\\(\\lambda\\)</span> and '
            '<code>$HOME</code></p><p>but $x = \\frac{1}{2}$ shows</p>')
    assert len(raw_tex(page)) == 3


def test_every_image_has_alt_text(pages):
    for path, page in pages.items():
        for image in page.images:
            assert (image.get("alt") or "").strip(), f"{path.name}: <img src={image.get('src', '')[:60]}> without alt"


def test_every_internal_link_and_asset_resolves(site, pages):
    ids = {path.resolve(): page.ids for path, page in pages.items()}
    for path, page in pages.items():
        for url in page.links:
            parts = urlsplit(url)
            target = (path.parent / unquote(parts.path)).resolve() if parts.path else path.resolve()
            assert target.exists(), f"{path.relative_to(site)}: {url}"
            if parts.fragment and target.suffix == ".html" and target in ids:
                assert unquote(parts.fragment) in ids[target], f"{path.relative_to(site)}: {url}"


def test_the_published_folder_holds_no_cache_and_no_path_of_this_machine(site):
    names = {p.name for p in site.rglob("*")}
    assert not names & {".doctrees", ".buildinfo", "environment.pickle", "_sources"}
    assert not list(site.rglob("*.pickle")) and not list(site.rglob("*.doctree"))
    here = [str(ROOT).encode(), str(site.parent).encode()]  # the clone, the build folder
    assert [p for p in site.rglob("*") if p.is_file() and any(h in p.read_bytes() for h in here)] == []


def test_the_book_links_every_deck(site, pages):
    index = pages[site / "index.html"]
    for path in book.lectures(ROOT):
        deck = f"slides/{path.stem}.slides.html"
        assert deck in index.links and (site / deck).is_file(), deck
        lecture = pages[site / "notebooks" / f"{path.stem}.html"]
        assert f"../{deck}" in lecture.links, path.name
    assert "slides/index.html" in index.links and (site / "slides" / "index.html").is_file()


def test_the_theme_loads_nothing_from_another_site(site, pages):
    for name in ("index.html", "search.html", "notation.html", "guides/lecturers.html",
                 "notebooks/exercises/04_dls_step.html"):
        assert pages[site / name].external == [], name
    for css in site.rglob("*.css"):
        text = css.read_text(encoding="utf-8", errors="replace")
        assert not re.search(r"(@import|url\()\s*['\"]?(https?:)?//", text), css.relative_to(site)


def test_no_page_loads_a_script_style_or_font_from_another_site(site, pages):
    """Also the notebooks' outputs (e.g. an animation's controls)."""
    found = {str(path.relative_to(site)): page.external
             for path, page in pages.items() if page.external}
    assert found == {}


def test_pages_with_widget_stills_say_the_live_version_needs_a_kernel(site):
    for name in ("05_singularities_out_of_reach", "07_workspace_maps"):
        text = page_text(site / "notebooks" / f"{name}.html")
        assert "a still: run the notebook" in text  # the widget's still is on the page
        assert "the live version needs a kernel" in text, name
    assert "needs a kernel" not in page_text(site / "notebooks" / "01_jacobian.html")


def test_math_is_served_by_the_site(site):
    text = (site / "notebooks" / "04_damped_least_squares.html").read_text(encoding="utf-8")
    script = re.search(r'<script[^>]+src="([^"?]*tex-svg-full\.js)[?"]', text)
    assert script and (site / "notebooks" / script.group(1)).resolve().is_file()
    assert "\\lambda" in text  # the page carries its TeX for MathJax


def test_home_page_has_a_picture_and_a_line_per_lecture(site, pages):
    index = pages[site / "index.html"]
    pictures = [image for image in index.images if image.get("src", "").startswith("_images/")]
    assert len(pictures) == len(book.lectures(ROOT))
    text = page_text(site / "index.html")
    for line in book.lecture_lines(ROOT).values():
        assert re.sub(r"\s+", " ", line.replace("`", ""))[:40] in re.sub(r"\s+", " ", text)


def test_the_home_page_shows_one_column_of_the_lectures_table():
    lines = book.lecture_lines(ROOT)
    assert len(lines) == len(book.lectures(ROOT))
    for name, line in lines.items():
        assert " | " not in line and "core/" not in line, f"{name}: {line}"
        assert "_" not in re.sub(r"`[^`]*`", "", line), f"{name}: a raw subscript ('p_e') on the home page: {line}"


def test_the_notation_table_shows_subscripts_as_written(site):
    text = page_text(site / "notation.html")
    assert "A⁺_λ, J⁺_{1,λ}" in text and "[J]_{ri}, J_{:,i}" in text
    assert "<em>" not in re.sub(r"(?s).*<main|</main>.*", "", (site / "notation.html").read_text(encoding="utf-8"))


def test_each_animation_is_shown_once_with_a_named_slider(site):
    for path in book.lectures(ROOT):
        text = (site / "notebooks" / f"{path.stem}.html").read_text(encoding="utf-8")
        players = text.count('<div class="animation">')
        sliders = re.findall(r'<input\b[^>]*type="range"[^>]*>', text)
        assert len(sliders) == players and all('aria-label="' in s for s in sliders), path.name
        if players:
            assert "Still frame of an animation" not in text, path.name


def test_headings_go_down_one_level_at_a_time(pages):
    for path, page in pages.items():
        levels = [int(h[1]) for h in re.findall(r"<(h[1-6])[ >]", path.read_text(encoding="utf-8"))]
        for before, after in zip(levels, levels[1:]):
            assert after <= before + 1, f"{path.name}: h{before} then h{after}"


def test_relative_links_become_pages_or_repository_links():
    mapping = book.pages(ROOT)
    text = "[table](README.md#notation) [make](../Makefile) [ex](exercises/01_jacobian.ipynb)"
    out = book.rewrite_links(text, "notebooks/01_jacobian.ipynb", HOME, mapping)
    assert "(../notation.md#notation)" in out
    assert f"({HOME.repository}/blob/{HOME.branch}/Makefile)" in out
    assert "(exercises/01_jacobian.ipynb)" in out


def test_a_missing_repository_says_what_to_set(tmp_path):
    for rel in ("docs", "notebooks"):
        (tmp_path / rel).mkdir()
    (tmp_path / "docs" / "conf.py").write_text("")
    (tmp_path / "pyproject.toml").write_text('[project]\nname = "ikteach"\n')
    with pytest.raises(SystemExit, match=r"\[project.urls\] Repository"):
        book.stage(tmp_path, tmp_path / "src")


def test_the_site_group_is_the_site_extra():
    """make site installs the `site` dependency group; `ikteach[site]` (in dev) the extra."""
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    extra = project["project"]["optional-dependencies"]["site"]
    assert sorted(project["dependency-groups"]["site"]) == sorted(extra)
    assert not any(re.match(r"(jax|jupyterlab|ikteach)\b", dep) for dep in extra)


def test_a_book_built_from_the_same_files_is_reused_and_a_change_builds_anew(tmp_path):
    """The browser tests reuse build/test-site (book.build(reuse=True)) only while every file it
    was built from is unchanged (book.inputs_digest)."""
    root, out = tmp_path / "course", tmp_path / "out" / "site"
    (root / "notebooks").mkdir(parents=True)
    (root / "notebooks" / "01_a.ipynb").write_text("{}")
    digest = book.inputs_digest(root)
    assert book.inputs_digest(root) == digest
    out.mkdir(parents=True)
    (out / "index.html").write_text("built before")
    book.beside(out, "cache").mkdir()
    (book.beside(out, "cache") / "inputs.sha256").write_text(digest)
    assert book.build(out, root, reuse=True) == out  # reused: nothing staged (no docs/conf.py)
    for change in (lambda: (root / "notebooks" / "01_a.ipynb").write_text('{"cells": []}'),
                   lambda: (root / "docs").mkdir() or (root / "docs" / "book.css").write_text("")):
        change()
        assert book.inputs_digest(root) != digest
        with pytest.raises(SystemExit, match="no docs/conf.py"):  # builds anew: stages first
            book.build(out, root, reuse=True)
        digest = book.inputs_digest(root)
