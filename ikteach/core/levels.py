"""Priority levels in the solve loop: ik.solve(tree, targets, theta0, levels=..., rest_pose=...).

levels[k] is the priority of the k-th block of the target (0 first): one block per end
effector for a tree, the position and the orientation for a 4x4 pose target, the whole
target for a point on a chain. Each level is solved in the null space of all the levels
before it (ik.core.priority.multilevel_step), so e.g. feet (level 0) stay planted while a hand (level 1)
reaches as far as the feet allow. rest_pose adds one last level, e = gain (theta_rest - theta)
with J = I: with the freedom that is still left, drift back towards a preferred pose.

The rest level's step: the damped pseudoinverse of J N = N (singular values 1) is
N / (1 + lambda^2), so each step moves theta by gain / (1 + lambda^2) of the way to rest_pose
within the null space N. Above 1 + lambda^2 it overshoots (at 2 (1 + lambda^2) the overshoot
grows every step); near 2 (1 + lambda^2) with lambda ~ 0 the swings are so wide that the other
levels' linear model no longer holds (measured: lambda 0, gain 1.99 on 30 reachable targets of a
three-link arm, 21 ran to max_iter with angles up to 176 rad; gain 0.99, 4 with 8.7 rad). So
rest_gain may be at most rest_gain_bound(lambda) = 1 + lambda^2, a step that goes at most all the
way (a ValueError otherwise); the default 0.1 is far below.

The loop itself is unchanged: it stops "converged" when the whole error (every level,
not the rest pose) is below tol, and "stalled" when the levels conflict and the step dies out.
"""
import jax
import jax.numpy as jnp
import numpy as np

from ._validate import as_number
from .method import JacobianMethod, method
from .pose import PoseTask
from .priority import multilevel_step

DEFAULT_REST_GAIN = 0.1


def rest_gain_bound(damping):
    """The largest rest gain accepted: 1 + lambda^2, no overshoot (module doc)."""
    return 1.0 + damping**2


def check_rest_gain(gain, damping):
    """0 < gain <= rest_gain_bound(damping), or a ValueError naming rest_gain."""
    gain = as_number(gain, "rest_gain", minimum=0, strict=True)
    bound = rest_gain_bound(damping)
    if gain > bound:
        raise ValueError(f"rest_gain: expected a gain of at most 1 + damping^2 = {bound:.4g} "
                         f"(each step moves theta rest_gain / (1 + damping^2) of the way to "
                         f"rest_pose; above 1 + damping^2 it overshoots), got {gain:g}")
    return gain


def block_size(task, rows):
    """Rows per block of the error: 3 per effector (trees), 3 + 3 for a pose, else all."""
    if isinstance(task, PoseTask):
        return 3
    return getattr(task, "block_size", None) or rows


def level_rows(levels, block):
    """The error's row indices of each priority level, level 0 first (levels: one priority
    per block of `block` rows)."""
    per_row = np.repeat(np.asarray(levels), block)
    return tuple(np.flatnonzero(per_row == level) for level in sorted(set(levels)))


@method(data=("rows", "damping", "rest_pose", "rest_gain"))
class Priorities(JacobianMethod):
    """The damped multilevel priority step. rows: the error's row indices of each level
    (level_rows), data: the same sizes in another order reuse the compiled loop."""
    rows: tuple
    damping: float
    rest_pose: object = None
    rest_gain: float = 0.0

    def delta(self, problem, theta, e, J, free=None):
        """J's rows split by level, the rest pose (if any) as the last level, J = I there
        less the joints a joint-limit pass pinned (free = False)."""
        parts = [(J[rows], e[rows]) for rows in self.rows]
        if self.rest_pose is not None:
            free = jnp.ones(theta.shape[0], bool) if free is None else free
            parts.append((jnp.diag(free.astype(J.dtype)), self.rest_gain * (self.rest_pose - theta)))
        return multilevel_step(parts, self.damping)


def with_priorities(method, problem, theta0, options):
    """The solve's method with priority levels / a rest pose (unchanged without them)."""
    if options.levels is None and options.rest_pose is None:
        return method
    if getattr(method, "damping", None) is None:
        raise ValueError("method: levels= and rest_pose= use the damped priority step "
                         "(ik.core.priority.multilevel_step with damping=); use method='dls' or ik.DLS(damping)")
    rows = jax.eval_shape(problem.error, theta0).shape[0]
    block = block_size(problem.task, rows)
    blocks = rows // block
    levels = (0,) * blocks if options.levels is None else options.levels
    if isinstance(levels, (str, bytes)) or not np.iterable(levels) or any(
            isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)) for v in levels):
        raise ValueError(f"levels: expected one integer priority per target block "
                         f"(whole numbers 0, 1, ...), got {levels!r:.80}")
    levels = tuple(int(v) for v in levels)
    if len(levels) != blocks or min(levels) < 0:
        raise ValueError(f"levels: expected {blocks} priorities >= 0 (one per "
                         f"{'end effector' if blocks > 1 else 'target'}), got {list(levels)}")
    rest_pose, gain = options.rest_pose, 0.0
    if rest_pose is not None:
        if np.shape(rest_pose) != np.shape(theta0):
            raise ValueError(f"rest_pose: expected shape {np.shape(theta0)} (one angle per "
                             f"joint), got shape {np.shape(rest_pose)}")
        rest_pose = jnp.asarray(rest_pose)
        gain = check_rest_gain(DEFAULT_REST_GAIN if options.rest_gain is None
                               else options.rest_gain, method.damping)
    return Priorities(level_rows(levels, block), method.damping, rest_pose, gain)
