"""What the book and the slides both do to a notebook's cells (book.py and slides.py use it):
its title, links made right for the book, each animation shown once."""
import copy
import os
import re
from pathlib import Path

if __package__:
    from .course_home import ROOT
else:  # run as a file from the light site venv (see book.py)
    from course_home import ROOT

LINK = re.compile(r"(\]\()([^)\s]+)(\))")
WIDGET = "application/vnd.jupyter.widget-view+json"
STILL = "(a still: run the notebook"  # the caption of a widget's still (pictures/stills.py)
ANIMATION_STILL = '<img alt="Still frame of an animation.'  # pictures/frames.py show()
PLAYER = '<div class="animation">'  # matplotlib's JavaScript player
UNNAMED_SLIDER = re.compile(r'(<input\b(?![^>]*\baria-label=)[^>]*class="anim-slider")')


def _source(cell):
    source = cell.get("source", "")
    return "".join(source) if isinstance(source, list) else source


def title(book):
    """The notebook's first Markdown heading."""
    for cell in book["cells"]:
        if cell["cell_type"] == "markdown":
            match = re.search(r"^#\s+(.+)$", _source(cell), re.M)
            if match:
                return match.group(1).strip()
    raise ValueError("notebook: expected a '# title' in a Markdown cell")


def rewrite_links(text, repo_path, h, mapping):
    """Markdown text of the file at repo_path with relative links made right for the book."""
    book_dir = Path(mapping.get(repo_path, repo_path)).parent

    def fix(match):
        target = match.group(2)
        if re.match(r"[a-z]+:|#|/", target):
            return match.group(0)
        path, _, anchor = target.partition("#")
        full = os.path.normpath(Path(repo_path).parent / path).replace(os.sep, "/")
        if full in mapping:
            new = os.path.relpath(mapping[full], book_dir).replace(os.sep, "/")
            if full == "notebooks/README.md":
                anchor = "notation"
        else:
            kind = "tree" if (ROOT / full).is_dir() else "blob"
            new = f"{h.repository}/{kind}/{h.branch}/{full}"
        return match.group(1) + new + (f"#{anchor}" if anchor else "") + match.group(3)

    return LINK.sub(fix, text)


def _html(output):
    return "".join(output.get("data", {}).get("text/html", ""))


def one_animation(outputs):
    """A cell's outputs with each animation shown once: the still frame that pictures.frames.show
    puts before its player is left out (the player shows that frame first), and the player's
    frame slider gets a name (matplotlib's has none: axe's `label`)."""
    kept = []
    for i, out in enumerate(outputs):
        later = "".join(_html(o) for o in outputs[i + 1:i + 2])
        if _html(out).lstrip().startswith(ANIMATION_STILL) and PLAYER in later:
            continue
        if PLAYER in _html(out):
            out = copy.deepcopy(out)
            out["data"]["text/html"] = UNNAMED_SLIDER.sub(
                r'\1 aria-label="Animation frame"', _html(out))
        kept.append(out)
    return kept


def has_still(cell):
    """True when an output is a widget or a widget's still (moves only in a kernel)."""
    for out in cell.get("outputs", []):
        data = out.get("data", {})
        if WIDGET in data or STILL in "".join(data.get("text/html", "")):
            return True
    return False
