# Two commands: `make lab` opens the course, `make test` runs every test.
# Both install from the lock file (uv.lock): the same versions every semester.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
UV := $(VENV)/bin/uv
UV_VERSION ?= 0.13.9
STAMP := $(VENV)/.installed-stamp
# uv installs into $(VENV), never downloads a Python of its own, and keeps the venv's pip.
# --locked: stop with "run make lock" when pyproject.toml has changed since uv.lock.
export UV_PROJECT_ENVIRONMENT := $(VENV)
export UV_PYTHON_DOWNLOADS := never
# --compile-bytecode: .pyc files written once at install (import jax 2 s -> 0.5 s where Python
# may not write them itself, e.g. PYTHONDONTWRITEBYTECODE, a read-only venv).
SYNC := $(UV) sync --locked --inexact --extra dev --compile-bytecode

.PHONY: warm pdf test-browser-smoke lab test test-latest test-lowest lock lock-upgrade header notebooks strip bench clean exercises test-browser bench-browser site slides node_modules

# uv itself comes from PyPI, into the venv (the lock then keeps it at its locked version).
$(UV):
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet uv==$(UV_VERSION)

$(STAMP): pyproject.toml uv.lock | $(UV)
	$(SYNC) --quiet
	@touch $(STAMP)

# Jupyter refuses to run as root unless told (containers, Binder-like machines).
LAB_ARGS ?= $(if $(filter 0,$(shell id -u)),--allow-root)

# The lab also gets the `3d` extra (pyvista's trame: interactive 3-D scenes), and asks for live
# 3-D even without $$DISPLAY (macOS, a remote machine: pyvista renders off screen for trame).
LAB_STAMP := $(VENV)/.lab-stamp
$(LAB_STAMP): $(STAMP)
	$(SYNC) --extra 3d --quiet
	@touch $(LAB_STAMP)

lab: $(LAB_STAMP)
	IKTEACH_PYVISTA=$${IKTEACH_PYVISTA:-interactive} \
		$(VENV)/bin/jupyter lab --notebook-dir=notebooks $(LAB_ARGS)

# Compile every lecture's solvers into the compilation cache before class (ikteach warm): each
# lecture's first run then loads them instead of compiling.
warm: $(STAMP)
	$(VENV)/bin/ikteach warm

# Exercise templates (check cells print "not yet implemented") and the instructor's solutions.
EXERCISES = $(wildcard notebooks/exercises/*.ipynb) $(wildcard instructor/solutions/*.ipynb)
NOTEBOOKS = $(wildcard notebooks/*.ipynb) $(EXERCISES)
# workers: twice a 2-core machine's cores (many tests wait on a grader, a kernel or a browser
# they started): compile cache empty, 496 s against 522 s with 3, back to back (maintainers' guide)
TEST_WORKERS ?= 4
PYTEST_ARGS = -n $(TEST_WORKERS) --dist loadfile tests $(NOTEBOOKS) --nbval --nbval-sanitize-with tests/nbval_sanitize.cfg --durations=15

# The browser assets of the book and the slides (MathJax, reveal.js) and axe-core, from npm at
# the versions of package-lock.json. `make test` builds the book, so it needs them too.
NODE_STAMP := node_modules/.package-lock.json
$(NODE_STAMP): package.json package-lock.json
	@command -v npm >/dev/null || { echo "npm not found: installing Debian's nodejs and npm"; \
	  $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq nodejs npm; }
	npm ci --no-audit --no-fund --loglevel=error
	@touch $(NODE_STAMP)
node_modules: $(NODE_STAMP)

test: $(STAMP) $(NODE_STAMP)
	$(PY) -m pytest $(PYTEST_ARGS)

# The same suite against the newest versions pyproject.toml allows (not the lock), in its own
# venv: run it before `make lock-upgrade`, to see what a refreshed lock would change.
LATEST_VENV ?= .venv-latest
test-latest: $(STAMP)
	@test -x $(LATEST_VENV)/bin/python || $(UV) venv --quiet --python $(PY) $(LATEST_VENV)
	$(UV) pip install --quiet --compile-bytecode --python $(LATEST_VENV)/bin/python --upgrade -e ".[dev]"
	$(LATEST_VENV)/bin/python -m pytest $(PYTEST_ARGS)

# The same suite against the LOWEST versions pyproject.toml allows for its direct dependencies
# (uv's --resolution lowest-direct; the rest resolve to their newest), in its own venv: the
# check that the lower bounds are true. The resolved versions are kept in
# $(LOWEST_VENV)/requirements.txt; the venv is synced to exactly those (nothing else kept).
LOWEST_VENV ?= .venv-lowest
test-lowest: $(STAMP)
	@test -x $(LOWEST_VENV)/bin/python || $(UV) venv --quiet --python $(PY) $(LOWEST_VENV)
	$(UV) pip compile --quiet --resolution lowest-direct --extra dev --no-header \
		--python $(LOWEST_VENV)/bin/python -o $(LOWEST_VENV)/requirements.txt pyproject.toml
	$(UV) pip sync --quiet --compile-bytecode --python $(LOWEST_VENV)/bin/python \
		$(LOWEST_VENV)/requirements.txt
	$(UV) pip install --quiet --no-deps --python $(LOWEST_VENV)/bin/python -e .
	$(LOWEST_VENV)/bin/python -m pytest $(PYTEST_ARGS)

# After editing dependencies in pyproject.toml: record them in uv.lock (other pins unchanged).
# Once a semester (before it starts): `make lock-upgrade` moves every pin to the newest allowed.
# Both rewrite binder/constraints.txt, Binder's copy of the lock.
lock: | $(UV)
	$(UV) lock
	$(MAKE) binder/constraints.txt

lock-upgrade: | $(UV)
	$(UV) lock --upgrade
	$(MAKE) binder/constraints.txt

binder/constraints.txt: uv.lock
	$(UV) export --quiet --frozen --no-hashes --no-emit-project --extra lab --extra 3d \
		--no-header -o $@

# The course's public home (pyproject.toml [project.urls]) -> every notebook's first code cell
# and the Colab/Binder badges in README.md and notebooks/README.md. `make header REF=v2026.1`
# first points them at a tag (a term's release: docs/lecturers.md), `REF=main` back.
header: $(STAMP)
	$(PY) -m ikteach.course.notebook_header $(if $(REF),--ref $(REF))

# Strip run noise (timestamps, widget state, kernel versions) from every committed notebook.
strip: $(STAMP)
	$(PY) -m ikteach.course.notebook_strip $(NOTEBOOKS)

# Re-execute every notebook with the locked versions, then strip: what to commit.
notebooks: $(STAMP)
	$(PY) -m ikteach.course.notebook_header
	$(PY) -m ikteach.course.exercises build
	@for nb in notebooks/*.ipynb instructor/solutions/*.ipynb; do echo "== $$nb"; \
		$(VENV)/bin/jupyter nbconvert --to notebook --execute --inplace \
			--ExecutePreprocessor.timeout=900 $$nb || exit 1; done
	$(PY) -m ikteach.course.notebook_strip $(NOTEBOOKS)

exercises: $(STAMP)
	$(PY) -m ikteach.course.exercises build

# The course as a static HTML book with its reveal.js slides (build/site, the decks in
# build/site/slides), from the committed notebooks (never re-executed), offline:
# docs/lecturers.md, "Publish the course". Built in a venv of their own holding only the
# `site` group of uv.lock (Sphinx, myst-nb, the theme, nbconvert: no JAX, no JupyterLab); the
# scripts run as files, without importing the ikteach package.
SITE_VENV ?= .venv-site
SITE_STAMP := $(SITE_VENV)/.installed-stamp
$(SITE_STAMP): pyproject.toml uv.lock | $(UV)
	UV_PROJECT_ENVIRONMENT=$(SITE_VENV) $(UV) sync --locked --only-group site --quiet
	@touch $(SITE_STAMP)

site: $(SITE_STAMP) $(NODE_STAMP)
	$(SITE_VENV)/bin/python ikteach/course/book.py

slides: $(SITE_STAMP) $(NODE_STAMP)
	$(SITE_VENV)/bin/python ikteach/course/slides.py

# One PDF of the whole book (build/book.pdf): Sphinx's singlehtml page printed by Debian's
# Chromium once MathJax has typeset it (no LaTeX).
pdf: $(SITE_STAMP) $(NODE_STAMP)
	@test -x /usr/bin/chromium || { $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq chromium; }
	$(SITE_VENV)/bin/python ikteach/course/book.py --pdf

clean:
	rm -rf $(VENV) $(LATEST_VENV) $(LOWEST_VENV) $(SITE_VENV) .pytest_cache .hypothesis build node_modules

# Benchmarks print tables (never part of make test). The peer libraries of the bench extra
# go into their own venv, so that they never change what the tests run against.
BENCH_VENV ?= .venv-bench
bench: $(STAMP)
	@test -x $(BENCH_VENV)/bin/python || $(UV) venv --quiet --python $(PY) $(BENCH_VENV)
	UV_PROJECT_ENVIRONMENT=$(BENCH_VENV) $(UV) sync --frozen --quiet --extra dev --extra bench
	@for b in benchmarks/*.py; do echo "== $$b"; $(BENCH_VENV)/bin/python $$b || exit 1; done

# A real browser (Debian's chromium + chromium-driver, driven by selenium) runs notebook 05 in
# JupyterLab, drags the demo's slider and plays an animation, then runs every lecture notebook
# (no error, nothing clipped, alt text on every image); then reads the book (every page at 375
# and 1280 px, menus, search), every deck at 1280 x 720, and make pdf's PDF (read back with
# Debian's poppler-utils: every lecture in it, no raw TeX). Not part of `make test`.
# `make test-browser-smoke` (CI: .ci/run): every book page at 375 px, the menus, one deck.
SUDO := $(if $(filter 0,$(shell id -u)),,sudo)
# selenium: uv.lock's `browser` group, into the venv beside the rest
BROWSER_STAMP := $(VENV)/.browser-stamp
$(BROWSER_STAMP): $(STAMP)
	$(SYNC) --group browser --quiet
	@touch $(BROWSER_STAMP)
BROWSER_PREREQS := $(BROWSER_STAMP) $(NODE_STAMP)
define browser_setup
	@test -x /usr/bin/chromium -a -x /usr/bin/chromedriver || \
	  { $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq chromium chromium-driver; }
endef
test-browser: $(BROWSER_PREREQS)
	$(browser_setup)
	@test -x /usr/bin/pdftotext -a -x /usr/bin/pdfinfo || \
	  { $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq poppler-utils; }
	$(PY) -m pytest -v -p no:cacheprovider tests/browser/lab_05.py tests/browser/lab_notebooks.py \
		tests/browser/site_book.py tests/browser/site_slides.py tests/browser/site_pdf.py

test-browser-smoke: $(BROWSER_PREREQS)
	$(browser_setup)
	$(PY) -m pytest -q -p no:cacheprovider -m smoke tests/browser/site_book.py \
		tests/browser/site_slides.py

# Browser latency (a benchmark: prints p50/p95, asserts nothing): slider -> picture redrawn
# in JupyterLab in headless Chromium. Run on an idle machine; not part of `make test`.
bench-browser: $(BROWSER_STAMP)
	$(browser_setup)
	$(PY) tests/browser/bench_latency.py
