"""One call at the top of every notebook: print precision, seeds, plotting defaults, and the
kernel-wide settings a notebook opts into (none of them is made by `import ikteach`)."""
import os
import pathlib
import random

import numpy as np

from . import heap
from .._runtime import devices
from ..pictures.backend_3d import (PYVISTA_CHOICES, apply_pyvista_choice, choose_pyvista,  # noqa: F401
                                  pyvista_backend)

SEED = 0
CACHE_ENV = "IKTEACH_JAX_CACHE"  # a folder for compiled code, or "off"


def setup(seed=SEED, pyvista=None, cpu_devices="cores", freeze_heap=True):
    """Round printed numbers, seed the random generators, set plotting defaults.

    Returns a numpy Generator seeded with `seed` for the notebook's own random draws.
    pyvista="static" shows 3-D scenes as PNG images, "interactive" as pyvista's live trame
    view (needs the `3d` extra); None (default) reads $IKTEACH_PYVISTA, else picks live 3-D
    when trame is installed and a display is present. Headless, pyvista renders off screen.
    pyvista itself loads only when a notebook first draws in 3-D (ik.pictures.scene).
    Compiled solvers are kept on disk between runs (see compilation_cache).

    Kernel-wide settings, each measured where the class waits for it and each with its off
    switch (results are the same either way):
    cpu_devices  "cores": one JAX CPU device per core, so ik.solve_batch splits big batches
                 over them (ikteach/_runtime/devices.py: the 256x256 sweep 1.8x on 2 cores);
                 1 keeps JAX's single device. Only possible before JAX's first operation.
    freeze_heap  gc.freeze() what the imports made, once (ikteach/course/heap.py: a kernel
                 stops in 0.2 s instead of 0.6-0.9 s, collections skip 200k objects); False
                 leaves the collector alone.
    """
    devices.use_cores(cpu_devices)
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
    if freeze_heap:
        heap.settle()  # after the imports above: see ikteach/course/heap.py
    return np.random.default_rng(seed)


def versions_line():
    """'versions: ikteach X, jax X, numpy X, python X' (nbval's sanitizer hides the numbers)."""
    import platform

    import jax

    from .. import __version__

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
        from ..pictures import alt_text

        alt_text.register(shell)


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

    Every compilation is kept, however quick. This is JAX's own cache (public jax.config
    options), the one cache ikteach uses. Returns the folder, or None when turned off
    (IKTEACH_JAX_CACHE=off), when the folder cannot be created, or with a jaxlib older than
    CACHE_MIN_JAXLIB, whose CPU cache hands back broken solver loops (it stays off there).
    """
    import jax

    path = default_cache_dir() if path is None else str(path)
    if path is None or not cache_trusted():
        return None
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:
        return None
    jax.config.update("jax_compilation_cache_dir", path)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    return path
