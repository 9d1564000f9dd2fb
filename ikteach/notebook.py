"""One call at the top of every notebook: print precision, seeds, plotting defaults."""
import os
import pathlib
import random
import sys

import numpy as np

from . import heap

SEED = 0
CACHE_ENV = "IKTEACH_JAX_CACHE"  # a folder for compiled code, or "off"


def setup(seed=SEED, pyvista=None):
    """Round printed numbers, seed the random generators, set plotting defaults.

    Returns a numpy Generator seeded with `seed` for the notebook's own random draws.
    pyvista="static" shows 3-D scenes as PNG images, "interactive" as pyvista's live trame
    view (needs the `3d` extra); None (default) reads $IKTEACH_PYVISTA, else picks live 3-D
    when trame is installed and a display is present. Headless, pyvista renders off screen.
    pyvista itself loads only when a notebook first draws in 3-D (ik.scene).
    Compiled solvers are kept on disk between runs (see compilation_cache).
    """
    np.set_printoptions(precision=4, suppress=True, floatmode="fixed", linewidth=100)
    random.seed(seed)
    np.random.seed(seed)
    import matplotlib as mpl

    mpl.rcParams.update({
        "figure.figsize": (6.4, 4.0),
        "figure.dpi": 80,
        "savefig.dpi": 80,
        "axes.grid": True,
        "grid.alpha": 0.3,
        "animation.html": "jshtml",
        "animation.embed_limit": 4.0,  # MB
        "svg.hashsalt": "ikteach",
    })
    choose_pyvista(pyvista)
    compilation_cache()
    _setup_alt_text()
    print_versions()
    heap.settle()  # after the imports above: see ikteach/heap.py
    return np.random.default_rng(seed)


def versions_line():
    """'versions: ikteach X, jax X, numpy X, python X' (nbval's sanitizer hides the numbers)."""
    import platform

    import jax

    from . import __version__

    return (f"versions: ikteach {__version__}, jax {jax.__version__}, numpy {np.__version__}, "
            f"python {platform.python_version()}")


def print_versions():
    """Print one line of versions, so every executed notebook records what it ran with."""
    print(versions_line())


def _setup_alt_text():
    """In a notebook, matplotlib figures display with alt text (see ikteach.alt_text)."""
    try:
        from IPython import get_ipython
    except ImportError:
        return
    shell = get_ipython()
    if shell is not None and hasattr(shell, "display_formatter"):
        from . import alt_text

        alt_text.register(shell)


PYVISTA_CHOICES = ("static", "interactive")


def pyvista_backend(choice, headless):
    """The pyvista Jupyter backend wanted for a choice of "static", "interactive" or None
    (automatic: live 3-D when a display is present, static images headless and under test)."""
    if choice not in (None, *PYVISTA_CHOICES):
        raise ValueError(f"pyvista must be one of {PYVISTA_CHOICES} or None, got {choice!r}")
    if choice is None:
        return "static" if headless else "trame"
    return "trame" if choice == "interactive" else "static"


_NOT_CHOSEN = object()
_pyvista_choice = _NOT_CHOSEN  # what setup() asked for, until pyvista loads


def choose_pyvista(choice=None):
    """Check and keep the 3-D backend choice: set now if pyvista is loaded, else when ik.scene
    first loads it (importing pyvista costs about 0.4 s; most notebooks draw nothing in 3-D)."""
    global _pyvista_choice
    _pyvista_choice = _checked_choice(choice)
    if "pyvista" in sys.modules:
        apply_pyvista_choice()


def apply_pyvista_choice():
    """Set the backend setup() chose, once; called by ik.scene as it loads pyvista."""
    global _pyvista_choice
    if _pyvista_choice is _NOT_CHOSEN:
        return None
    choice, _pyvista_choice = _pyvista_choice, _NOT_CHOSEN
    return _setup_pyvista(choice)


def _checked_choice(choice):
    """The choice, else $IKTEACH_PYVISTA, else None; a bad one fails before pyvista loads."""
    choice = choice or os.environ.get("IKTEACH_PYVISTA") or None
    pyvista_backend(choice, headless=True)
    return choice


def _setup_pyvista(choice=None):
    """Set pyvista's Jupyter backend (static unless trame is installed); return its name."""
    choice = _checked_choice(choice)
    try:
        import pyvista as pv
    except ImportError:
        return None
    headless = not os.environ.get("DISPLAY") or bool(os.environ.get("PYVISTA_OFF_SCREEN"))
    if headless:
        pv.OFF_SCREEN = True
    backend = pyvista_backend(choice, headless)
    if backend == "trame":
        try:
            pv.set_jupyter_backend("trame")
            return "trame"
        except ImportError:  # no trame: the `3d` extra is not installed
            if choice == "interactive":
                import warnings

                warnings.warn("interactive 3-D needs pyvista's trame backend: pip install "
                              "'ikteach[3d]'; showing static images", stacklevel=3)
    pv.set_jupyter_backend("static")
    return "static"


def default_cache_dir():
    """The per-user folder for compiled code: $IKTEACH_JAX_CACHE, else
    $XDG_CACHE_HOME/ikteach/jax, else ~/.cache/ikteach/jax. None when set to "off"."""
    path = os.environ.get(CACHE_ENV)
    if path:
        return None if path.strip().lower() in ("off", "0", "false", "no") else path
    base = os.environ.get("XDG_CACHE_HOME") or pathlib.Path.home() / ".cache"
    return str(pathlib.Path(base) / "ikteach" / "jax")


# jaxlib 0.5.x (Colab's in 2026) loads the course's compiled loops from its CPU cache wrongly:
# every solve comes back "running" after 0 iterations. 0.6.2, 0.7.2, 0.8.3, 0.9.2, 0.10, 0.12 load
# them right (tests/test_wheel.py runs a Colab-like venv twice).
CACHE_MIN_JAXLIB = (0, 6)


def cache_trusted(jaxlib_version=None):
    """Does this jaxlib load compiled code from its persistent cache correctly?"""
    if jaxlib_version is None:
        import jaxlib

        jaxlib_version = getattr(jaxlib, "__version__", None) or jaxlib.version.__version__
    numbers = []
    for part in str(jaxlib_version).split(".")[:2]:
        digits = "".join(c for c in part if c.isdigit())
        numbers.append(int(digits) if digits else 0)
    return tuple(numbers) >= CACHE_MIN_JAXLIB


def compilation_cache(path=None):
    """Turn on JAX's persistent compilation cache in `path` (default: default_cache_dir()),
    so a notebook's second run loads its compiled solvers from disk instead of compiling.

    Every compilation is kept, however quick. Returns the folder, or None when turned off
    (IKTEACH_JAX_CACHE=off), when the folder cannot be created, or with a jaxlib older than
    CACHE_MIN_JAXLIB, whose CPU cache hands back broken solver loops (it stays off there).
    """
    import jax

    from . import program_store

    path = default_cache_dir() if path is None else str(path)
    if path is None or not cache_trusted():
        return None
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:
        return None
    jax.config.update("jax_compilation_cache_dir", path)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    program_store.open_store(path)  # whole programs too: no tracing either (program_store.py)
    return path
