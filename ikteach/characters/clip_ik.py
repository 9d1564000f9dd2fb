"""IK over a whole clip: solve every frame, moving only some joints, warm-started frame to frame.

Frame f starts from the clip's own angles plus the correction found at frame f - 1
(theta0_f = clip_f + theta_{f-1} - clip_{f-1}), so a correction carries over smoothly
instead of being found afresh each frame. Joints outside `active` keep the clip's angles:
their Jacobian columns are zeroed, so DLS never turns them.
"""
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from ..core._validate import as_array
from ..core.dls import DLS
from ..core.loop import STATUSES, iterate, start
from ..core.options import Options
from ..core.problem import Problem
from ..core.tree import TreeTask, tree_jacobian, tree_size
from .._runtime import engine, jit as runtime_jit


@dataclasses.dataclass(frozen=True)
class MaskedTreeTask(TreeTask):
    """A tree task in which only some joints may turn: J's other columns are zero."""
    mask: tuple = ()

    def jacobian(self, arm, theta):
        return tree_jacobian(arm, theta) * jnp.asarray(self.mask)

    def error_and_jacobian(self, arm, target, theta):  # the loops take e and J from here
        e, J = super().error_and_jacobian(arm, target, theta)
        return e, J * jnp.asarray(self.mask)


jax.tree_util.register_dataclass(MaskedTreeTask, data_fields=[], meta_fields=["mask"])


@runtime_jit.jit
def _solve_clip(task, arm, targets, theta, method, options):
    def frame(correction, inputs):
        target, clip = inputs
        state = engine.until_stopped(iterate, (Problem(task, arm, target), method, options),
                                     start(clip + correction))
        return state.theta - clip, (state.theta, state.error, state.i, state.status)

    _, out = jax.lax.scan(frame, jnp.zeros_like(theta[0]), (targets, theta))
    return out


@dataclasses.dataclass(frozen=True)
class ClipResult:
    """theta (F, n) solved angles; error (F,) |e| left per frame; iterations (F,); status (F,)."""
    theta: np.ndarray
    error: np.ndarray
    iterations: np.ndarray
    status: np.ndarray


def solve_clip(rig, root, theta, targets, active, tol=1e-3, max_iter=50, damping=1.0, clamp=None):
    """Solve every frame for the rig's end effectors to reach targets (F, m, 3) (world
    coordinates), turning only the `active` joints (indices of revolute joints), each frame
    warm-started from the clip plus the previous frame's correction.

    Every frame runs the module's solve loop (DLS, stop rules as in ik.solve); the frames
    run in one compiled lax.scan; clamp is Buss's D_max on |e| (None: no clamp), which keeps
    a far target from asking for one huge step. Returns a ClipResult."""
    theta = as_array(theta, "theta", shape=(None, rig.n_joints))
    count = len(theta)
    root = as_array(root, "root", shape=(count, 3))
    targets = as_array(targets, "targets", shape=(count, rig.tree.n_effectors, 3))
    mask = np.zeros(rig.n_joints)
    index = np.asarray(active).ravel()
    if not (np.issubdtype(index.dtype, np.integer) and len(index) and index.min() >= 0
            and index.max() < rig.n_joints):
        raise ValueError(f"active: expected indices of revolute joints in [0, {rig.n_joints}), "
                         f"got {active!r:.80}")
    mask[index] = 1.0
    size = tree_size(rig.tree)
    options = Options(tol=tol, clamp=clamp, max_iter=max_iter, stall_tol=1e-7 * size)
    task = MaskedTreeTask(mask=tuple(mask.tolist()))
    local = targets - root[:, None, :]          # the tree is built around the root
    thetas, errors, iterations, status = _solve_clip(task, rig.tree, jnp.asarray(local),
                                                     jnp.asarray(theta), DLS(damping),
                                                     options.resolved(size, rig.n_joints))
    return ClipResult(np.asarray(thetas), np.asarray(errors), np.asarray(iterations),
                      np.asarray(STATUSES, dtype=object)[np.asarray(status)])
