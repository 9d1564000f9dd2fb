"""`make pdf`: one PDF of the whole book (ikteach.course.book.pdf: Sphinx's single page printed by
Debian's Chromium once MathJax has typeset it), read back with poppler's pdfinfo and pdftotext
(Debian's poppler-utils, installed by `make test-browser` as Chromium is): every lecture,
exercise and guide in it, in the book's order, a few pages each, and no TeX left as text.

Run with `make test-browser` (about a minute: a Sphinx build and Chromium printing every page);
not part of `make test` or the CI smoke check. The PDF is built into a temporary folder."""
import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from ikteach.course import book

ROOT = Path(__file__).resolve().parents[2]
# TeX that MathJax would have typeset: the notebooks' $$, Sphinx's \( \) and \[ \], environments
RAW_TEX = re.compile(r"\$\$|\\[(\[]|\\begin\b|\\end\{|\\frac\b")
PAGES_PER_LECTURE = 5  # at least; the shortest (01) printed on 9 pages of 210 (2026-11)

pytestmark = pytest.mark.skipif(not (shutil.which("pdftotext") and shutil.which("pdfinfo")),
                                reason="poppler-utils (pdftotext, pdfinfo): make test-browser")


@pytest.fixture(scope="module")
def pdf(tmp_path_factory):
    return book.pdf(tmp_path_factory.mktemp("pdf") / "book.pdf")


@pytest.fixture(scope="module")
def text(pdf):
    """The PDF's text, pages parted by form feeds, every other run of spaces and line ends one
    space (a title may wrap)."""
    out = subprocess.run(["pdftotext", "-enc", "UTF-8", str(pdf), "-"], check=True,
                         capture_output=True, text=True).stdout
    return re.sub(r"[ \t\r\n\v]+", " ", out)


def page_count(pdf):
    info = subprocess.run(["pdfinfo", str(pdf)], check=True, capture_output=True, text=True).stdout
    return int(re.search(r"^Pages:\s+(\d+)", info, re.M)[1])


def titles(paths):
    return [book.title(json.loads(p.read_text(encoding="utf-8"))) for p in paths]


def guide_titles():
    return [re.search(r"^# (.+)$", (ROOT / "docs" / f"{g}.md").read_text(encoding="utf-8"), re.M)[1]
            for g in book.GUIDES]


@pytest.fixture(scope="module")
def starts(text):
    """{title: the page (1, 2, ...) where its part of the book starts}, in the book's order:
    lectures, exercises, the notation, the guides. A lecture or exercise is named first by the
    contents and the home page's lists, then by its own page's heading (the third time); the
    notation and the guides come after the last exercise, in that order."""
    found = {}
    for title in titles(book.lectures()) + titles(book.exercises()):
        where = [m.start() for m in re.finditer(re.escape(title), text)]
        assert len(where) >= 3, f"{title!r}: no page of its own in the PDF"
        found[title] = where[2]
    for title in ["Notation"] + guide_titles():
        at = text.find(title, max(found.values()))
        assert at >= 0, f"{title!r} is not in the PDF after the exercises"
        found[title] = at
    return {title: text.count("\f", 0, at) + 1 for title, at in found.items()}


def test_the_pdf_is_a_pdf_with_every_part_of_the_book_in_order(pdf, starts):
    assert pdf.read_bytes()[:5] == b"%PDF-"
    pages = page_count(pdf)
    print(f"\n{pdf.name}: {pages} pages, {pdf.stat().st_size / 1e6:.1f} MB; starts on page:",
          ", ".join(f"{title[:12]} {page}" for title, page in starts.items()))
    assert list(starts.values()) == sorted(starts.values()), starts
    assert max(starts.values()) <= pages <= 100 * len(book.lectures())


def test_every_lecture_takes_a_few_pages(starts):
    lectures = titles(book.lectures())
    pages = list(starts.values())
    spans = {title: pages[i + 1] - pages[i] for i, title in enumerate(lectures)}
    assert min(spans.values()) >= PAGES_PER_LECTURE, spans


def test_no_tex_left_as_text(text):
    found = [text[max(0, m.start() - 40):m.end() + 40] for m in RAW_TEX.finditer(text)]
    assert found == []


def test_the_tex_check_finds_tex_left_as_text():
    assert RAW_TEX.search("the identity $$J^T(JJ^T + \\lambda^2 I)^{-1}$$ holds")
    assert RAW_TEX.search("\\begin{aligned} a &= b \\end{aligned}")
    assert RAW_TEX.search("for \\(\\lambda > 0\\) the matrix")
    assert not RAW_TEX.search("costs $3 and the code prints \\n")
