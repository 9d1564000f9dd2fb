"""ikteach: inverse kinematics for a computer-animation course.

Importing ikteach switches JAX to 64-bit floats, so every result is float64.
Modules that pull in heavy libraries (matplotlib, ipywidgets, pyvista, scikit-image)
load on first use: `ik.plot`, `ik.demo`, `ik.scene`, `ik.workspace`... are in LAZY.
"""
import importlib

import jax

from . import host_devices

jax.config.update("jax_enable_x64", True)
host_devices.request(jax)  # one CPU device per core, for solve_batch (before JAX starts)

from . import lapack_tables  # noqa: E402

lapack_tables.preload()  # the first SVD or solve lowers without importing scipy.linalg (0.2 s)

from .chain import Chain, planar_chain, serial_chain, reach  # noqa: E402
from .kinematics import fk, joint_positions, joint_frames, rotation_about  # noqa: E402
from .jacobian import jacobian, jacobian_autodiff, jacobian_fd  # noqa: E402
from .jt import jt_step, optimal_alpha  # noqa: E402
from .pinv import pinv_step  # noqa: E402
from .dls import dls_step, dls_step_normal  # noqa: E402
from .limits import clamp_error, cap_step  # noqa: E402
from .priority import priority_step, multilevel_step, damped_pinv, null_projector  # noqa: E402
from .solve import solve, Result, Trace, STATUSES, METHODS  # noqa: E402
from .solve import StopSolve  # noqa: E402
from .batch import solve_batch, BatchResult  # noqa: E402
from . import notebook  # noqa: E402
from .sdls import sdls_step, GAMMA_MAX  # noqa: E402
from .ccd import ccd_sweep, ccd_angle  # noqa: E402
from .fabrik import fabrik_pass  # noqa: E402
from .tree import Tree, tree, tree_fk, tree_frames, tree_jacobian, tree_jacobian_autodiff  # noqa: E402
from .tree import tree_jacobian_from_frames  # noqa: E402
from .track import track, TrackResult  # noqa: E402
from .jitter import jitter, jitter_per_step  # noqa: E402
from . import stop_rules, settle  # noqa: E402
from . import buss_trees  # noqa: E402
from .pose import fk_pose, rotation_log, rotation_exp, pose_errors, make_pose, PoseTask  # noqa: E402
from .robots import ur5, iiwa14  # noqa: E402
from . import robots  # noqa: E402
from . import bvh, skeleton, clip_ik, footplant, look_at  # noqa: E402  (characters: BVH, rigs, foot planting)

# name -> (submodule, attribute or None for the module itself): imported on first use.
LAZY = {
    "check": ("check", None),
    "plot": ("plot", None),
    "demo": ("demo", None),
    "scene": ("scene", None),
    "workspace": ("workspace", None),
    "tree_plot": ("tree_plot", None),
    "live_map": ("live_map", None),
    "character_plot": ("character_plot", None),
    "character_scene": ("character_scene", None),
}


def __getattr__(name):
    if name not in LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module_name, attribute = LAZY[name]
    module = importlib.import_module(f".{module_name}", __name__)
    value = module if attribute is None else getattr(module, attribute)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(LAZY))


__all__ = [
    "Chain", "planar_chain", "serial_chain", "reach",
    "fk", "joint_positions", "joint_frames", "rotation_about",
    "jacobian", "jacobian_autodiff", "jacobian_fd",
    "jt_step", "optimal_alpha", "pinv_step", "dls_step", "dls_step_normal",
    "clamp_error", "cap_step",
    "priority_step", "multilevel_step", "damped_pinv", "null_projector",
    "solve", "Result", "Trace", "STATUSES", "METHODS",
    "solve_batch", "BatchResult", "notebook",
    "StopSolve", "check",
    "sdls_step", "GAMMA_MAX", "ccd_sweep", "ccd_angle", "fabrik_pass",
    "Tree", "tree", "tree_fk", "tree_frames", "tree_jacobian", "tree_jacobian_autodiff",
    "tree_jacobian_from_frames",
    "track", "TrackResult", "jitter", "jitter_per_step", "stop_rules", "settle", "buss_trees", "tree_plot", "plot", "demo",
    "fk_pose", "rotation_log", "rotation_exp", "pose_errors", "make_pose", "PoseTask",
    "ur5", "iiwa14", "robots", "scene", "workspace", "live_map",
    "bvh", "skeleton", "clip_ik", "footplant", "look_at", "character_plot", "character_scene",
]
__version__ = "0.1.0"
