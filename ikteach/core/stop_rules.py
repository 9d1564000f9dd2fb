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
theta where the solve stopped and tells four cases apart. A solve with priority levels has one
error block e_k per level (level 0 first; a rest pose is not one: it is not part of ||e||); a
plain solve has one level, e itself. Two tests, both scale-free (sigma_max, J's largest
singular value, sets the scale of the gradient and of the probe's damping):

  projected gradient  g_k = N_<k J_k^T e_k, the direction that lowers 1/2 ||e_k||^2 without
              touching the levels before it (N_<k: the null space of their Jacobians; N = I for
              level 0). Small when ||g_k|| <= GRADIENT_FRACTION sigma_max ||e|| for every level.
  probe       a weak direction of J (sigma_i << sigma_max) keeps g small although the error
              lies along it; so also try what a lighter step would do: the priority step
              (ik.core.priority.multilevel_step; DLS for one level) with damping lambda = f sigma_max,
              f in LIGHT_DAMPINGS, each turn capped at PROBE_MAX_TURN radians and taken at
              PROBE_FRACTIONS of its length. It improves when some level's ||e_k|| falls by
              more than IMPROVABLE ||e|| and by more than tol (a gain below the accuracy asked
              for changes nothing the solve can tell) while no level before it grows by more
              than IMPROVABLE ||e||.

  MINIMUM      "stalled": g small and no probe improves, and the Hessian H of 1/2 ||e_0||^2
               (level 0) has no clearly negative eigenvalue: a minimum of ||e|| - the
               target is out of reach of this start (another start may reach it: a local
               minimum looks the same from inside). "A minimum" as far as one light step can
               tell: a long, flat valley that descends only after tens of steps reads as one;
  SADDLE       "singular": the same, but H < -CURVATURE_FRACTION sigma_max^2 along some
               direction: a saddle, e.g. a straight arm whose target lies on its own line.
               Reachable; a nudge of the start gets the solve going;
  CUT_SHORT    "damped": g is not small or a lighter step would still lower ||e||: the
               method's steps, not the target, stopped the solve short of a minimum (a large
               damping lambda, max_step or clamp for this arm's size, or J's weak direction).
               Whether the target is in reach is open: solve again with less damping;
  FIXED_POINT  "fixed_point": as CUT_SHORT, but for a method that is not a Jacobian step
               (FABRIK, CCD) run without max_step: its own update has a fixed point there
               (FABRIK's hinge recovery on a spatial chain, say). Not out of reach; a Jacobian
               method (dls, pinv) goes on from there.
KIND_STATUS names the status each kind reports.
Joints resting on a joint limit and pushed against it count as fixed.
"""
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from .priority import multilevel_step, null_projector
from .safeguards import cap_step
from .._runtime import jit as runtime_jit

STOP_RULES = ("joint_steps", "motion")
STALL_FRACTION = 1e-5  # the report's loop: stall_tol = STALL_FRACTION x L (benchmarks/sweep.py)
DEFAULT_STOP_RULE = "motion"
SLOW_PROGRESS = 1e-4  # "slow" when ||e|| still fell by more than this fraction in the last step
GRADIENT_FRACTION = 1e-2  # a small projected gradient: below this fraction of sigma_max ||e||
CURVATURE_FRACTION = 1e-6  # a saddle: an eigenvalue of H below -this fraction of sigma_max^2
LIGHT_DAMPINGS = (1e-1, 1e-2, 1e-3)  # the probe steps' lambda, as fractions of sigma_max
PROBE_FRACTIONS = (1.0, 0.25, 0.0625)  # each probe step is tried at these fractions of its length
PROBE_MAX_TURN = 0.1  # radians: a probe step stays near theta (it tests the neighbourhood)
IMPROVABLE = 1e-3  # a probe that lowers a level's ||e_k|| by this fraction of ||e||: not a minimum
MINIMUM, SADDLE, CUT_SHORT, FIXED_POINT = range(4)  # what stall_kind returns
KIND_STATUS = ("stalled", "singular", "damped", "fixed_point")  # the status each kind reports


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


def level_norms(e, levels):
    """||e_k|| for each level k (levels: the error's row indices, level 0 first)."""
    return jnp.stack([jnp.linalg.norm(e[jnp.asarray(rows)]) for rows in levels])


def level_projectors(J, levels):
    """N_<k for each level k: the null space of the Jacobians of the levels before it."""
    n = J.shape[1]
    done = [jnp.concatenate([jnp.asarray(r) for r in levels[:k]]) for k in range(1, len(levels))]
    return [jnp.eye(n)] + [null_projector(J[rows]) for rows in done]


def gradient_small(J, e, levels, projectors, sigma_max):
    """Every level's projected gradient N_<k J_k^T e_k below GRADIENT_FRACTION sigma_max ||e||."""
    bound = GRADIENT_FRACTION * sigma_max * jnp.linalg.norm(e)
    norms = [jnp.linalg.norm(N @ (J[jnp.asarray(r)].T @ e[jnp.asarray(r)]))
             for r, N in zip(levels, projectors)]
    return jnp.all(jnp.stack(norms) <= bound)


def lexicographic_gain(before, after, scale, tol):
    """Does `after` improve on `before` level by level: some level falls by more than
    IMPROVABLE scale and more than tol, while none before it rises by more than IMPROVABLE scale?"""
    fall = before - after
    safe_so_far = jnp.cumprod(jnp.concatenate([jnp.ones(1), (fall > -IMPROVABLE * scale)[:-1]]))
    return jnp.any((fall > jnp.maximum(IMPROVABLE * scale, tol)) & (safe_so_far > 0))


def probe_steps(J, e, levels, sigma_max):
    """The probe's trial steps, one row each: the light priority steps (one per damping in
    LIGHT_DAMPINGS), capped at PROBE_MAX_TURN, at each of PROBE_FRACTIONS of their length."""
    parts = [(J[jnp.asarray(r)], e[jnp.asarray(r)]) for r in levels]
    light = lambda lam: cap_step(multilevel_step(parts, lam), PROBE_MAX_TURN)
    steps = jax.vmap(light)(jnp.asarray(LIGHT_DAMPINGS) * sigma_max)
    return (jnp.asarray(PROBE_FRACTIONS)[:, None, None] * steps[None]).reshape(-1, J.shape[1])


def probe_improves(error_of, J, e, theta, levels, sigma_max, lower, upper, tol):
    """Would a lighter step still lower ||e||? (module doc: the probe). J's pinned columns are
    zeroed by the caller, so the probe steps leave those joints where they are."""
    before = level_norms(e, levels)
    scale = jnp.where(jnp.linalg.norm(e) > 0, jnp.linalg.norm(e), 1.0)
    after = jax.vmap(lambda d: level_norms(error_of(jnp.clip(theta + d, lower, upper)), levels))(
        probe_steps(J, e, levels, sigma_max))
    return jnp.any(jax.vmap(lambda a: lexicographic_gain(before, a, scale, tol))(after))


def saddle(error_of, theta, rows, pinned, sigma_max):
    """The Hessian of 1/2 ||e_0||^2 (level 0's rows, the free joints) clearly negative somewhere.
    Only level 0: a later level moves on the curved set where the levels before it stay met,
    whose curvature its own Hessian does not see (a saddle there reads as a minimum)."""
    half_sq = lambda q: 0.5 * jnp.sum(error_of(q)[jnp.asarray(rows)] ** 2)
    H = jnp.where(pinned[:, None] | pinned[None, :], 0.0, jax.hessian(half_sq)(theta))
    return jnp.linalg.eigvalsh(H)[0] < -CURVATURE_FRACTION * sigma_max**2


def stall_kind(task, arm, target, theta, lower, upper, levels=None, tol=0.0):
    """Why a solve stalled at theta: MINIMUM (out of reach), SADDLE or CUT_SHORT (module doc;
    why_stalled turns CUT_SHORT into FIXED_POINT for FABRIK and CCD).

    levels: the error's row indices per priority level, level 0 first (a tuple of tuples;
    None: one level, the whole error - a plain solve). tol: the solve's tolerance (a probe
    must gain more than tol to count)."""
    error_of = lambda q: task.error(arm, target, q)
    e = error_of(theta)
    levels = (tuple(range(e.shape[0])),) if levels is None else levels
    J = task.jacobian(arm, theta)
    g = J.T @ e
    pinned = ((theta <= lower) & (g < 0)) | ((theta >= upper) & (g > 0))  # pushed into a limit
    J = jnp.where(pinned[None, :], 0.0, J)
    sigma_max = jnp.linalg.norm(J, 2)
    projectors = level_projectors(J, levels)
    stationary = gradient_small(J, e, levels, projectors, sigma_max) & \
        ~probe_improves(error_of, J, e, theta, levels, sigma_max, lower, upper, tol)
    at_saddle = saddle(error_of, theta, levels[0], pinned, sigma_max)
    return jnp.where(stationary, jnp.where(at_saddle, SADDLE, MINIMUM), CUT_SHORT)


STALL_BLOCKS = (8, 1024)  # rows per call: a solve's, a batch's


@partial(runtime_jit.jit, static_argnames=("levels",))  # the task is a pytree: new weights reuse it
def _stall_kinds(task, arm, targets, thetas, lower, upper, levels, tol):
    return jax.vmap(lambda t, q: stall_kind(task, arm, t, q, lower, upper, levels, tol))(targets, thetas)


def why_stalled(task, arm, targets, thetas, stalled, options, levels=None, own_update=False):
    """stall_kind of every row where `stalled` (MINIMUM elsewhere); CUT_SHORT becomes
    FIXED_POINT for a method that needs no J (FABRIK, CCD) without max_step (own_update). Rows go in blocks of
    STALL_BLOCKS[0] (a few rows: a solve) or STALL_BLOCKS[1] (a batch), the last one padded:
    two compiled programs per problem, whatever the count (a new count would otherwise compile
    again: 0.3-0.5 s on a live map's lambda change). Prioritised solves (levels, a rest pose)
    are judged level by level (priority_levels).

    Called once after the loop: targets (B, ...) and thetas (B, n) where each row stopped,
    stalled (B,) True where the row ended STALLED, options the solve's (tol, joint_limits),
    levels the error's rows per priority level (None: one level); KIND_STATUS[kind] is the
    status each stalled row reports."""
    kinds = np.full(np.shape(stalled), MINIMUM)
    rows = np.flatnonzero(stalled)
    if rows.size == 0:
        return kinds
    targets, thetas = np.asarray(targets), np.asarray(thetas)
    block = STALL_BLOCKS[0] if rows.size <= STALL_BLOCKS[0] else STALL_BLOCKS[1]
    padded = np.concatenate([rows, np.repeat(rows[-1:], -rows.size % block)])
    n = np.shape(thetas)[-1]
    bounds = [np.broadcast_to(np.asarray(b, dtype=float), (n,)) for b in options.joint_limits]
    found = [_stall_kinds(task, arm, targets[part], thetas[part], *bounds, levels, options.tol)
             for part in padded.reshape(-1, block)]
    kinds[rows] = np.concatenate([np.asarray(f) for f in found])[: rows.size]
    if own_update:
        kinds[kinds == CUT_SHORT] = FIXED_POINT
    return kinds
