"""Which pyvista backend shows 3-D scenes: static PNGs (headless, under test, committed
notebooks) or pyvista's live trame view. Chosen by ik.notebook.setup(pyvista=...) or
$IKTEACH_PYVISTA, and applied when ik.pictures.scene first loads pyvista (0.4 s saved where a notebook
draws nothing in 3-D)."""
import os
import sys


PYVISTA_CHOICES = ("static", "interactive")
NO_TRAME = ("3-D scenes show as static images here: interactive 3-D needs pyvista's trame. "
            "Open the course with `make lab` (it installs it), or run "
            "pip install 'ikteach[3d]' and restart the kernel.")


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
    """Check and keep the 3-D backend choice: set now if pyvista is loaded, else when ik.pictures.scene
    first loads it (importing pyvista costs about 0.4 s; most notebooks draw nothing in 3-D)."""
    global _pyvista_choice
    _pyvista_choice = _checked_choice(choice)
    if "pyvista" in sys.modules:
        apply_pyvista_choice()


def apply_pyvista_choice():
    """Set the backend setup() chose, once; called by ik.pictures.scene as it loads pyvista."""
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
            # one plain line, not a warning (a warning's first line is a path inside ikteach)
            print(NO_TRAME, file=sys.stderr)
    pv.set_jupyter_backend("static")
    return "static"
