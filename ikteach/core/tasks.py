"""What a solve aims at: a task gives the error vector e(theta) and its Jacobian.

The solve loop is the same for every task; a task only says how far the arm is from
the target and how that distance changes with theta. TASKS lists them once: points for
chains, 4x4 poses for spatial chains (pose.py), one point per end effector for trees (tree.py).
"""
import dataclasses

import jax

from .chain import Chain, reach
from .jacobian import jacobian, jacobian_from_frames
from .kinematics import fk, joint_frames
from .pose import PoseTask
from .tree import TreeTask


@dataclasses.dataclass(frozen=True)
class PositionTask:
    """Reach a point: e = target - F(theta), J the geometric Jacobian (d x n)."""

    def accepts_arm(self, arm):
        return isinstance(arm, Chain)

    def accepts(self, arm, target_shape):
        return self.accepts_arm(arm) and tuple(target_shape) == (arm.dim,)

    def target_shape(self, arm):
        return f"({arm.dim},)"

    def error(self, arm, target, theta):
        return target - fk(arm, theta)

    def jacobian(self, arm, theta):
        return jacobian(arm, theta)

    def error_and_jacobian(self, arm, target, theta):
        """e and J from one walk of the chain (the solve loop needs both every iteration)."""
        positions, axes, _ = joint_frames(arm, theta)
        return target - positions[-1, : arm.dim], jacobian_from_frames(arm, positions, axes)

    def length_scale(self, arm):
        return float(reach(arm))


# Tasks travel into the compiled loops as pytrees: data (PoseTask's weights) is traced,
# everything else is part of the program's key.
jax.tree_util.register_dataclass(PositionTask, data_fields=[], meta_fields=[])
jax.tree_util.register_dataclass(TreeTask, data_fields=[], meta_fields=[])

TASKS = (PositionTask(), PoseTask(), TreeTask())


def task_for(arm, target_shape, name="target"):
    """The task that takes this arm and a target of this shape, or a ValueError naming `name`."""
    tasks = [t for t in TASKS if t.accepts_arm(arm)]
    if not tasks:
        raise ValueError(f"arm: expected a chain from ik.planar_chain or ik.serial_chain, "
                         f"got {type(arm).__name__}")
    for task in tasks:
        if task.accepts(arm, target_shape):
            return task
    wanted = " or ".join(t.target_shape(arm) for t in tasks)
    raise ValueError(f"{name}: expected shape {wanted}, got shape {tuple(target_shape)}")
