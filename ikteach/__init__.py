"""ikteach: inverse kinematics for a computer-animation course.

Importing ikteach switches JAX to 64-bit floats (jax_enable_x64), so every result is
float64. That is the only global change it makes: the CPU device count, the garbage
collector and sys.modules are left as they were (ik.notebook.setup() is where a notebook
opts into kernel-wide settings).

The package by concern (arrows point down; nothing imports upward):
  ikteach.course      exercise checks, grading and its sandbox, notebook setup/header/strip
  ikteach.pictures    2-D plots and animations, 3-D scenes, the demo, live maps, alt text
  ikteach.characters  BVH, skeletons, the walk, foot planting, clip IK, look-at
  ikteach.core        the IK a student reads: chains, Jacobians, steps, the solve loop
  ikteach._runtime    jax.jit for the whole-loop programs (compiler options, program bound)
Pictures and course load on first use (`ik.plot`, `ik.demo`, `ik.check`...: LAZY below).
"""
import importlib

import jax

jax.config.update("jax_enable_x64", True)

from .core.chain import Chain, planar_chain, serial_chain, reach  # noqa: E402
from .core.kinematics import fk, joint_positions, joint_frames, rotation_about  # noqa: E402
from .core.jacobian import jacobian, jacobian_autodiff, jacobian_fd  # noqa: E402
from .core.jt import jt_step, optimal_alpha  # noqa: E402
from .core.pinv import pinv_step  # noqa: E402
from .core.dls import dls_step, dls_step_normal  # noqa: E402
from .core.limits import clamp_error, cap_step  # noqa: E402
from .core import jt, pinv, dls, sdls, ccd, fabrik, priority, joint_limits, levels, tasks  # noqa: E402,F401
from .core.priority import priority_step, multilevel_step, damped_pinv, null_projector  # noqa: E402
from .core.solve import solve, Result, Trace, STATUSES, METHODS  # noqa: E402
from .core.solve import StopSolve  # noqa: E402
from .core.batch import solve_batch, BatchResult  # noqa: E402
from .course import notebook  # noqa: E402
from .core.sdls import sdls_step, GAMMA_MAX  # noqa: E402
from .core.ccd import ccd_sweep, ccd_angle  # noqa: E402
from .core.fabrik import fabrik_pass  # noqa: E402
from .core.tree import Tree, tree, tree_fk, tree_frames, tree_jacobian, tree_jacobian_autodiff  # noqa: E402
from .core.tree import tree_jacobian_from_frames  # noqa: E402
from .core.track import track, TrackResult  # noqa: E402
from .core.jitter import jitter, jitter_per_step  # noqa: E402
from .core import stop_rules, settle  # noqa: E402
from .core import buss_trees  # noqa: E402
from .core.pose import fk_pose, rotation_log, rotation_exp, pose_errors, make_pose, PoseTask  # noqa: E402
from .core.robots import ur5, iiwa14  # noqa: E402
from .core import robots  # noqa: E402
from .characters import bvh, skeleton, clip_ik, footplant, look_at  # noqa: E402  (characters: BVH, rigs, foot planting)

# name -> (submodule, attribute or None for the module itself): imported on first use.
LAZY = {
    "check": ("course.check", None),
    "plot": ("pictures.plot", None),
    "alt_text": ("pictures.alt_text", None),
    "demo": ("pictures.demo", None),
    "scene": ("pictures.scene", None),
    "workspace": ("pictures.workspace_maps", None),
    "tree_plot": ("pictures.tree_plot", None),
    "live_map": ("pictures.live_map", None),
    "character_plot": ("pictures.character_plot", None),
    "character_scene": ("pictures.character_scene", None),
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
