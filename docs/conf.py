"""Sphinx settings of the course's book (`make site`, ikteach/course/book.py stages the pages).

Offline: the notebooks are read as committed (never executed), MathJax is served from the
site's own _static folder, nothing is loaded from another site when a page is viewed.
"""
import json
from pathlib import Path

# The course's home (pyproject.toml), written next to this file by the stager (book.py): Sphinx
# runs in the light site venv, which cannot import ikteach (no JAX there).
HOME = json.loads((Path(__file__).parent / "course_home.json").read_text(encoding="utf-8"))
project = "ikteach: inverse kinematics, derived and run"
author = "the ikteach course"
copyright = "the ikteach course authors (MIT licence)"
language = "en"

extensions = ["myst_nb"]
exclude_patterns = ["_build", "_notebooks", "**.ipynb_checkpoints"]
suppress_warnings = ["mystnb.unknown_mime_type"]

# Notebooks: shown as committed, outputs and all; widgets as their stills (no widget JS).
nb_execution_mode = "off"
nb_mime_priority_overrides = [("html", "application/vnd.jupyter.widget-view+json", None)]
nb_ipywidgets_js = {}
myst_enable_extensions = ["dollarmath", "amsmath"]
# The notebooks put a `$$ ... $$` display on its own lines inside a paragraph (as JupyterLab,
# nbconvert and the slides read it); without this, dollarmath pairs those dollars wrongly.
myst_dmath_double_inline = True
myst_heading_anchors = 3  # links like guide.md#a-heading work as on GitHub

# MathJax 3 from node_modules (copied in by the stager): SVG output, so no font files to load.
mathjax_path = "mathjax/tex-svg-full.js"
mathjax3_config = {"svg": {"fontCache": "global"}}

html_theme = "sphinx_book_theme"
html_title = "ikteach"
html_static_path = ["_static"]
html_css_files = ["book.css"]
html_js_files = ["book.js"]
html_favicon = "_static/favicon.svg"  # a served site asks for one (a 404 in the console)
html_context = {"default_mode": "light"}  # readable on a projector; the reader may switch
html_copy_source = False
html_show_sourcelink = False
html_theme_options = {
    "repository_url": HOME["repository"],
    "repository_branch": HOME["branch"],
    "use_repository_button": True,
    "use_download_button": False,
    "show_toc_level": 2,
    "navbar_persistent": [],  # one search field (the menu's), not a second one in the header
}
smartquotes = False  # the notebooks' text as written
