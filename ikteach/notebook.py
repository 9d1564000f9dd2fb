"""One call at the top of every notebook: print precision, seeds, plotting defaults."""
import os
import random

import numpy as np

SEED = 0


def setup(seed=SEED):
    """Round printed numbers, seed the random generators, set plotting defaults.

    Returns a numpy Generator seeded with `seed` for the notebook's own random draws.
    Under test (no display, or PYVISTA_OFF_SCREEN set) pyvista renders off screen.
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
    _setup_alt_text()
    print_versions()
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
