"""Characters: BVH skeletons and motion, rigs, the shipped walk, foot planting, clip IK, look-at.
Uses the core only."""
from .._lazy import submodules  # noqa: E402

__getattr__ = submodules(__name__, globals())  # ik.characters.<module>: imported on first use
