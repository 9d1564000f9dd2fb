"""One IK problem: an arm, a target and the task that compares them (tasks.py)."""
from ._pytree import pytree_dataclass


@pytree_dataclass(data=("task", "arm", "target"))
class Problem:
    """F(theta) = target for this arm: e(theta) and J(theta) as the task defines them."""
    task: object
    arm: object
    target: object

    def error(self, theta):
        return self.task.error(self.arm, self.target, theta)

    def jacobian(self, theta):
        return self.task.jacobian(self.arm, theta)

    def error_and_jacobian(self, theta):
        """e and J at theta (from one walk of the arm where the task offers it)."""
        if hasattr(self.task, "error_and_jacobian"):
            return self.task.error_and_jacobian(self.arm, self.target, theta)
        return self.error(theta), self.jacobian(theta)

    def rows_per_effector(self, rows):
        """Rows of e per end effector: 3 for a tree's effectors, else all of them."""
        return getattr(self.task, "block_size", None) or rows

    def length_scale(self):
        """The arm's size L (a chain's total link length, a tree's size)."""
        return self.task.length_scale(self.arm)
