"""Pictures: 2-D plots and animations, 3-D scenes, the lab demo, live maps, alt text.
Uses the core and characters; loaded on first use (ik.pictures.plot, ik.pictures.scene, ...)."""
from .._lazy import submodules  # noqa: E402

__getattr__ = submodules(__name__, globals())  # ik.pictures.<module>: imported on first use
