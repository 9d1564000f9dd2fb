"""Following moving targets: one pass of the IK loop per time step (Buss's demo protocol).

At each time step the targets move, then the method takes ONE step from the current theta
(loop.iterate with no stop rule: no iterating to convergence). Reported per step: the sum
over end effectors of the distance to its target after the step, and the joint motion.
"""
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from ._pytree import replace
from ._validate import as_array
from .jitter import jitter
from .loop import RUNNING, iterate, start
from .methods import require_traceable
from .options import Options
from .solve import as_options, prepare
from .tasks import TASKS, task_for
from .._runtime import engine

NEVER = np.iinfo(np.int64).max  # max_iter for tracking: the loop's stops never fire


@dataclasses.dataclass(frozen=True)
class TrackResult:
    """theta (T+1, n) from the start; error (T,) = sum_k |t_k - x_k| after each step.
    For P paths at once: theta (P, T+1, n) and error (P, T), one row per path."""
    theta: np.ndarray
    error: np.ndarray

    @property
    def mean_error(self):
        """The mean of error over the steps (one per path for several paths)."""
        mean = np.mean(self.error, axis=-1)
        return float(mean) if np.ndim(mean) == 0 else mean

    @property
    def jitter(self):
        """ik.core.jitter.jitter of the joint path: the mean of sum_j |theta_j(t+1) - 2 theta_j(t) + theta_j(t-1)|
        (one per path for several paths)."""
        if self.theta.ndim == 3:
            return np.array([jitter(path) for path in self.theta])
        return jitter(self.theta)


def effector_errors(problem, theta):
    """|t_k - x_k| for each end effector k."""
    e = problem.error(theta)
    return jnp.linalg.norm(e.reshape(-1, problem.rows_per_effector(e.shape[0])), axis=1)


def follow(args, carry, target):
    """One time step: the targets move, then one pass of the loop. With grow (Buss's demo
    code, UpdatedSClampValue), effector k's next clamp is D_max plus how much farther from its
    target this step left it (0 if nearer)."""
    problem, method, options, d_max, grow = args
    state, clamps = carry
    problem = replace(problem, target=target)
    before = effector_errors(problem, state.theta)
    state = iterate(problem, method, replace(options, clamp=clamps), state._replace(status=RUNNING))
    after = effector_errors(problem, state.theta)
    clamps = jnp.where(grow, d_max + jnp.maximum(after - before, 0.0), d_max)
    return (state, clamps), (state.theta, jnp.sum(after))


def track(arm, targets, theta0=None, method="dls", options=None, *, damping=None, rcond=None,
          gamma_max=None, clamp_growth=False, **option_values):
    """Follow targets[0], targets[1], ... with one step of `method` each (Buss's protocol).

    targets  (T, *target shape): one target (or one per end effector) per time step, T >= 1;
             or (P, T, *target shape): P paths followed side by side, each on its own (one
             program steps them all at once: the same steps, vectorised).
    theta0   the start (default: all zeros); for P paths one start for all or one per path (P, n).
    method, damping, rcond, gamma_max: as in ik.solve.
    options  as in ik.solve, of which tracking reads clamp (each end effector's error clamped to
             D_max), max_step, joint_limits, limit_mode, levels, rest_pose, rest_gain.
    clamp_growth  Buss's demo code: effector k's clamp is D_max plus how much farther from its
             target the last step left it, and the first step is unclamped. Needs clamp.
    Paths of any length run one compiled program (engine.SCAN_CHUNK steps at a time).
    """
    options = as_options(options, option_values)
    defaults = Options()
    for name in ("tol", "max_iter", "stall_tol", "stop_rule"):
        if getattr(options, name) != getattr(defaults, name):
            raise ValueError(f"{name}: ik.track takes one step per time step and never stops "
                             f"early, so it has no {name}")
    if clamp_growth not in (True, False):
        raise ValueError(f"clamp_growth: expected True or False, got {clamp_growth!r:.80}")
    if clamp_growth and options.clamp is None:
        raise ValueError("clamp_growth: grows the clamp D_max; give clamp= too")
    targets = as_array(targets, "targets")
    if targets.ndim < 2:
        raise ValueError(f"targets: expected one target per time step, got shape {targets.shape}")
    if 0 in targets.shape[:2]:
        raise ValueError(f"targets: expected at least one time step, got none (shape "
                         f"{targets.shape})")
    paths = is_paths(arm, targets.shape)
    shape = targets.shape
    if paths:  # checked and prepared as one long path; stepped as P paths
        targets = targets.reshape((-1,) + shape[2:])
    n, count = arm.n_joints, shape[0] if paths else 1
    theta0 = np.zeros(n) if theta0 is None else as_array(
        theta0, "theta0", shape=(count, n) if paths and np.ndim(theta0) == 2 else (n,))
    problem, method, options, _, targets = prepare(
        arm, targets, theta0.reshape(-1, n)[0], method, options,
        {"damping": damping, "rcond": rcond, "gamma_max": gamma_max}, rows="targets")
    theta0 = np.broadcast_to(np.clip(theta0, *options.joint_limits), (count, n))  # as prepare does
    require_traceable(method, problem, theta0[0], "ik.track")
    options = replace(options, tol=0.0, stall_tol=0.0, max_iter=np.int64(NEVER))
    effectors = jax.eval_shape(lambda q: effector_errors(problem, q), theta0[0]).shape[0]
    d_max = np.full(effectors, options.clamp, dtype=float)
    first_clamp = np.broadcast_to(np.full(effectors, np.inf) if clamp_growth else d_max,
                                  (count, effectors))
    args = (problem, method, options, d_max, np.asarray(bool(clamp_growth)))
    starts = [(start(q), clamp) for q, clamp in zip(theta0, first_clamp)]  # one per path
    if not paths:
        thetas, errors = engine.run_scan(follow, args, starts[0], targets)
        return TrackResult(np.concatenate([theta0, thetas]), np.asarray(errors))
    stacked = jax.tree_util.tree_map(lambda *xs: np.stack([np.asarray(x) for x in xs]), *starts)
    thetas, errors = engine.run_scan(follow, args, stacked, targets.reshape(shape), paths=True)
    return TrackResult(np.concatenate([theta0[:, None], thetas], axis=1), np.asarray(errors))


def is_paths(arm, shape):
    """True when targets of this shape are P paths (P, T, *target), False for one path
    (T, *target); a ValueError naming targets when neither."""
    for paths, target_shape in ((False, shape[1:]), (True, shape[2:])):
        try:
            task_for(arm, target_shape, "targets")
            return paths
        except ValueError:
            pass
    wanted = " or ".join(t.target_shape(arm) for t in TASKS if t.accepts_arm(arm))
    if not wanted:
        task_for(arm, shape[1:], "targets")  # not an arm: its own message
    raise ValueError(f"targets: expected shape (T, *target) for one path or (P, T, *target) for "
                     f"P paths, target of shape {wanted}; got shape {tuple(shape)}")
