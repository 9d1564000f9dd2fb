# Two commands: `make lab` opens the course, `make test` runs every test.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp

.PHONY: lab test bench clean exercises test-browser

$(STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[dev]"
	@touch $(STAMP)

# Jupyter refuses to run as root unless told (containers, Binder-like machines).
LAB_ARGS ?= $(if $(filter 0,$(shell id -u)),--allow-root)

lab: $(STAMP)
	$(VENV)/bin/jupyter lab --notebook-dir=notebooks $(LAB_ARGS)

test: $(STAMP)
	$(PY) -m pytest -n 2 --dist loadfile tests $(wildcard notebooks/*.ipynb) $(EXERCISES) --nbval --nbval-sanitize-with tests/nbval_sanitize.cfg

# Exercise templates (check cells print "not yet implemented") and the instructor's solutions.
EXERCISES = $(wildcard notebooks/exercises/*.ipynb) $(wildcard instructor/solutions/*.ipynb)

exercises: $(STAMP)
	$(PY) -m ikteach.exercises build

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis

# Benchmarks print tables (never part of make test). The peer libraries of the bench extra
# go into their own venv, so that they never change what the tests run against.
BENCH_VENV ?= .venv-bench
bench:
	@test -x $(BENCH_VENV)/bin/python || $(PYTHON) -m venv $(BENCH_VENV)
	$(BENCH_VENV)/bin/python -m pip install --quiet -e ".[dev,bench]"
	@for b in benchmarks/*.py; do echo "== $$b"; $(BENCH_VENV)/bin/python $$b || exit 1; done

# A real browser (Debian's chromium + chromium-driver, driven by selenium) runs notebook 05 in
# JupyterLab, drags the demo's slider and plays an animation. Not part of `make test`.
SUDO := $(if $(filter 0,$(shell id -u)),,sudo)
test-browser: $(STAMP)
	@test -x /usr/bin/chromium -a -x /usr/bin/chromedriver || \
	  { $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq chromium chromium-driver; }
	$(PY) -m pip install --quiet "selenium>=4.20"
	$(PY) -m pytest -v -p no:cacheprovider tests/browser/lab_05.py
