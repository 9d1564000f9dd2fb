"""When to stop short of the target: the stall rules, and why a solve stopped there.

A stall rule ends a solve when the steps have become too small to matter. Two rules:

  "motion"       the default: the end effector's predicted motion ||J delta_theta|| < stall_tol,
                 a length compared with a length (default stall_tol = tol / 100): the same
                 decision at every scale.
  "joint_steps"  the lab report's rule: sum_i |delta_theta_i| < stall_tol.
                 The sum is in radians but the default stall_tol is tol / 100 (a length,
                 proportional to the link lengths), so the rule depends on the units of length:
                 scale arm and target by s and the JT/pinv/DLS steps (lambda scaled with them)
                 stay the same while the threshold grows with s. Kept as an option (lecture 05).

A small step happens for two reasons: the target is out of reach (||e|| levels off at the
distance to the workspace), or the method converges slowly (||e|| still shrinks by a steady
fraction per step, e.g. the Jacobian transpose near a singular direction). When a rule fires,
the relative progress of the last step, (||e_prev|| - ||e||) / ||e_prev||, tells them apart:
above SLOW_PROGRESS the status is "slow" instead of "stalled".

A step can also be small for reasons that say nothing about reach; stall_kind looks at the
theta where the solve stopped and tells three cases apart (with g = J^T e, the direction
that lowers 1/2 ||e||^2, and H its Hessian):

  "stalled"   ||g|| < GRADIENT_FRACTION sigma_max ||e|| (J cannot see the error any more) and
              H has no clearly negative eigenvalue: a minimum of ||e||, the target is out of
              reach (of this start's basin);
  "singular"  the same small g, but H < -CURVATURE_FRACTION sigma_max^2 along some direction:
              a saddle, e.g. a straight arm whose target lies on its own line. Reachable;
              a nudge of the start gets the solve going;
  "damped"    g is not small: J sees the error, but the steps were cut (a large damping
              lambda, max_step or clamp for this arm's size). Not out of reach.
Joints resting on a joint limit and pushed against it count as fixed.
"""
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from .._runtime import jit as runtime_jit

STOP_RULES = ("joint_steps", "motion")
STALL_FRACTION = 1e-5  # the report's loop: stall_tol = STALL_FRACTION x L (benchmarks/sweep.py)
DEFAULT_STOP_RULE = "motion"
SLOW_PROGRESS = 1e-4  # "slow" when ||e|| still fell by more than this fraction in the last step
GRADIENT_FRACTION = 1e-2  # stationary: ||J^T e|| below this fraction of sigma_max ||e||
CURVATURE_FRACTION = 1e-6  # a saddle: an eigenvalue of H below -this fraction of sigma_max^2
MINIMUM, SADDLE, CUT_SHORT = range(3)  # what stall_kind returns


def check_rule(rule):
    """The rule's name, or a ValueError naming stop_rule."""
    if not isinstance(rule, str) or rule not in STOP_RULES:
        raise ValueError(f"stop_rule: expected one of {list(STOP_RULES)}, got {rule!r:.80}")
    return rule


def joint_steps(delta_theta):
    """The report's step size: sum_i |delta_theta_i| (radians)."""
    return jnp.sum(jnp.abs(delta_theta))


def motion(J, delta_theta):
    """The end effector's predicted motion ||J delta_theta|| (units of the error)."""
    return jnp.linalg.norm(J @ delta_theta)


def step_size(rule, J, delta_theta):
    """The size the stall rule compares with stall_tol: rule "motion" or "joint_steps"."""
    return motion(J, delta_theta) if rule == "motion" else joint_steps(delta_theta)


def relative_progress(previous_error, error):
    """(||e_prev|| - ||e||) / ||e_prev||: the fraction of the error the last step removed."""
    return (previous_error - error) / jnp.where(previous_error > 0, previous_error, 1.0)


def still_progressing(previous_error, error):
    """True when the error still shrinks by a steady fraction: a slow solve, not a stall."""
    return relative_progress(previous_error, error) > SLOW_PROGRESS


def stall_kind(task, arm, target, theta, lower, upper):
    """Why a solve stalled at theta: MINIMUM (out of reach), SADDLE or CUT_SHORT (module doc)."""
    e = task.error(arm, target, theta)
    J = task.jacobian(arm, theta)
    g = J.T @ e
    pinned = ((theta <= lower) & (g < 0)) | ((theta >= upper) & (g > 0))  # pushed into a limit
    g = jnp.where(pinned, 0.0, g)
    sigma_max = jnp.linalg.norm(J, 2)
    stationary = jnp.linalg.norm(g) <= GRADIENT_FRACTION * sigma_max * jnp.linalg.norm(e)
    half_sq = lambda q: 0.5 * jnp.sum(task.error(arm, target, q) ** 2)
    H = jax.hessian(half_sq)(theta)
    H = jnp.where(pinned[:, None] | pinned[None, :], 0.0, H)
    saddle = jnp.linalg.eigvalsh(H)[0] < -CURVATURE_FRACTION * sigma_max**2
    return jnp.where(stationary, jnp.where(saddle, SADDLE, MINIMUM), CUT_SHORT)


STALL_BLOCKS = (8, 1024)  # rows per call: a solve's, a batch's


@partial(runtime_jit.jit, static_argnames=("task",))
def _stall_kinds(task, arm, targets, thetas, lower, upper):
    return jax.vmap(lambda t, q: stall_kind(task, arm, t, q, lower, upper))(targets, thetas)


def why_stalled(task, arm, targets, thetas, stalled, lower, upper, prioritised=False):
    """stall_kind of every row where `stalled` (MINIMUM elsewhere). Rows go in blocks of
    STALL_BLOCKS[0] (a few rows: a solve) or STALL_BLOCKS[1] (a batch), the last one padded:
    two compiled programs per problem, whatever the count (a new count would otherwise compile
    again: 0.3-0.5 s on a live map's lambda change). Prioritised solves (levels, a rest pose) stop
    at a compromise between levels, not at a minimum of ||e||: they are left as they are."""
    kinds = np.full(np.shape(stalled), MINIMUM)
    rows = np.flatnonzero(stalled)
    if rows.size == 0 or prioritised:
        return kinds
    block = STALL_BLOCKS[0] if rows.size <= STALL_BLOCKS[0] else STALL_BLOCKS[1]
    padded = np.concatenate([rows, np.repeat(rows[-1:], -rows.size % block)])
    n = np.shape(thetas)[-1]
    bounds = [np.broadcast_to(np.asarray(b, dtype=float), (n,)) for b in (lower, upper)]
    targets, thetas = np.asarray(targets), np.asarray(thetas)
    found = [_stall_kinds(task, arm, targets[part], thetas[part], *bounds)
             for part in padded.reshape(-1, block)]
    kinds[rows] = np.concatenate([np.asarray(f) for f in found])[: rows.size]
    return kinds
