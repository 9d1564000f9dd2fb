"""One call at the top of every notebook: print precision, seeds, plotting defaults."""
import os
import pathlib
import random

import numpy as np

SEED = 0
CACHE_ENV = "IKTEACH_JAX_CACHE"  # a folder for compiled code, or "off"


def setup(seed=SEED):
    """Round printed numbers, seed the random generators, set plotting defaults.

    Returns a numpy Generator seeded with `seed` for the notebook's own random draws.
    Under test (no display, or PYVISTA_OFF_SCREEN set) pyvista renders off screen.
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
    _setup_pyvista()
    compilation_cache()
    return np.random.default_rng(seed)


def _setup_pyvista():
    try:
        import pyvista as pv
    except ImportError:
        return
    headless = not os.environ.get("DISPLAY") or os.environ.get("PYVISTA_OFF_SCREEN")
    if headless:
        pv.OFF_SCREEN = True
    try:
        import trame  # noqa: F401  (live 3-D in Jupyter when available)
        pv.set_jupyter_backend("static" if headless else "trame")
    except ImportError:
        pv.set_jupyter_backend("static")


def default_cache_dir():
    """The per-user folder for compiled code: $IKTEACH_JAX_CACHE, else
    $XDG_CACHE_HOME/ikteach/jax, else ~/.cache/ikteach/jax. None when set to "off"."""
    path = os.environ.get(CACHE_ENV)
    if path:
        return None if path.strip().lower() in ("off", "0", "false", "no") else path
    base = os.environ.get("XDG_CACHE_HOME") or pathlib.Path.home() / ".cache"
    return str(pathlib.Path(base) / "ikteach" / "jax")


def compilation_cache(path=None):
    """Turn on JAX's persistent compilation cache in `path` (default: default_cache_dir()),
    so a notebook's second run loads its compiled solvers from disk instead of compiling.

    Every compilation is kept, however quick. Returns the folder, or None when turned off
    (IKTEACH_JAX_CACHE=off) or the folder cannot be created.
    """
    import jax

    path = default_cache_dir() if path is None else str(path)
    if path is None:
        return None
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:
        return None
    jax.config.update("jax_compilation_cache_dir", path)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    return path
