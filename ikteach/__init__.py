"""ikteach: inverse kinematics for a computer-animation course.

Importing ikteach switches JAX to 64-bit floats (jax_enable_x64), so every result is
float64. That is the only global change it makes (ik.notebook.setup() is where a notebook
opts into kernel-wide settings).

`ik.<name>` is the lectures' vocabulary (__all__ below). Everything else is reachable under
its folder, loaded on first use:
  ik.core        the IK a student reads: chains, Jacobians, the steps, the loop (ik.core.loop)
  ik.characters  BVH, skeletons, the walk, foot planting, clip IK, look-at
  ik.pictures    2-D plots and animations, 3-D scenes, the demo, live maps, alt text
  ik.course      exercise checks, grading and its sandbox, notebook setup/header/strip
  ik._runtime    the engine that compiles and vectorises the loop (never rewrites it)
Arrows point down: course and pictures use the core and characters; the core uses neither.
"""
import jax

jax.config.update("jax_enable_x64", True)

from .core.chain import Chain, planar_chain, serial_chain, reach  # noqa: E402
from .core.kinematics import fk, joint_positions  # noqa: E402
from .core.jacobian import jacobian, jacobian_autodiff, jacobian_fd  # noqa: E402
from .core.jt import JT, jt_step, optimal_alpha  # noqa: E402
from .core.pinv import Pinv, pinv_step  # noqa: E402
from .core.dls import DLS, dls_step, dls_step_normal  # noqa: E402
from .core.sdls import SDLS, sdls_step  # noqa: E402
from .core.ccd import CCD  # noqa: E402
from .core.fabrik import FABRIK  # noqa: E402
from .core.safeguards import clamp_error, cap_step  # noqa: E402
from .core.priority import priority_step, damped_pinv, null_projector  # noqa: E402
from .core.loop import STATUSES, iterate  # noqa: E402
from .core.options import Options  # noqa: E402
from .core.solve import solve, Result, StopSolve  # noqa: E402
from .core.batch import solve_batch  # noqa: E402
from .core.track import track  # noqa: E402
from .core.tree import tree  # noqa: E402
from .core.pose import fk_pose, make_pose, pose_errors  # noqa: E402
from . import core, characters, pictures, course  # noqa: E402,F401  (folders, loaded lazily)
from .course import notebook  # noqa: E402,F401


def __getattr__(name):
    """ik.check: the exercises' instant checks (ikteach/course/check), imported on first use."""
    if name == "check":
        return course.check
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

__all__ = [
    "Chain", "planar_chain", "serial_chain", "reach", "fk", "joint_positions",
    "jacobian", "jacobian_autodiff", "jacobian_fd", "tree", "fk_pose", "make_pose", "pose_errors",
    "jt_step", "optimal_alpha", "pinv_step", "dls_step", "dls_step_normal", "sdls_step",
    "clamp_error", "cap_step", "priority_step", "damped_pinv", "null_projector",
    "JT", "Pinv", "DLS", "SDLS", "CCD", "FABRIK",
    "Options", "iterate", "solve", "solve_batch", "track", "Result", "STATUSES", "StopSolve",
    "notebook", "check",
]
__version__ = "0.1.0"
