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

A small step can also have causes that say nothing about reach. So after the loop every
"stalled" or "slow" end is looked at where it stopped (stall_kind): can a short run of light
steps still lower ||e||? A solve with priority levels has one error block e_k per level (level 0
first; a rest pose is not one: it is not part of ||e||) and is judged level by level; a plain
solve has one level, e itself.

  probe       up to PROBE_STEPS light priority steps (ik.core.priority.multilevel_step; DLS for
              one level) from where the solve stopped, each capped at PROBE_MAX_TURN radians (it
              stays near the basin it starts in) and kept only when it helps: some level's
              ||e_k|| falls while no level before it rises by more than a visible change above
              its start (visible: more than tol and more than IMPROVABLE ||e||; a priority
              step's lower level may disturb a level before it by that much, and the next
              step's correction brings it back).
              lambda starts at PROBE_DAMPING sigma_max (sigma_max: J's largest singular value,
              so the probe is scale-free), is divided by PROBE_LIGHTER after a kept step and
              multiplied by PROBE_HEAVIER after a refused one (Levenberg-Marquardt).
  gain        the probe gains when it converges (||e|| < tol), or when some level's ||e_k||
              fell by a visible change with no level before it risen by one.

  MINIMUM      "stalled": no gain and the Hessian H of 1/2 ||e_0||^2 (level 0) has no clearly
               negative eigenvalue: a minimum of ||e||, the target out of reach of this start
               (another start may reach it: a local minimum looks the same from inside);
  SADDLE       "singular": no gain, but H < -CURVATURE_FRACTION sigma_max^2 along some
               direction: a saddle, e.g. a straight arm whose target lies on its own line.
               It says nothing about reach (the straight arm (1, 1, 1) at theta = 0 stops
               "singular" for the target (2, 0) and for (-5, 0), 2 beyond its reach): nudge the
               start and solve again to learn whether the target is in reach;
  CUT_SHORT    "damped": the probe gains: the method's steps, not the target, stopped the solve
               short of a minimum (a large damping lambda, max_step or clamp for this arm's
               size, a pseudoinverse cut-off, or J's weak direction). Solve again with less damping;
  FIXED_POINT  "fixed_point": as CUT_SHORT, but for a method that is not a Jacobian step
               (FABRIK, CCD) run without max_step: its own update has a fixed point there
               (FABRIK's hinge recovery on a spatial chain, say). A Jacobian method goes on.
A "slow" end (the stall rule fired while ||e|| still fell) stays "slow" only when the probe
gains; otherwise ||e|| has stopped falling and it is named like a stall. KIND_STATUS names the
status each kind reports. Joints resting on a joint limit and pushed against it count as fixed.
"""
import jax
import jax.numpy as jnp
import numpy as np

from ._pytree import replace
from .dls import damped_step
from .priority import multilevel_step
from .safeguards import cap_step
from .._runtime import engine

STOP_RULES = ("joint_steps", "motion")
STALL_FRACTION = 1e-5  # the report's loop: stall_tol = STALL_FRACTION x L (benchmarks/sweep.py)
DEFAULT_STOP_RULE = "motion"
SLOW_PROGRESS = 1e-4  # "slow" when ||e|| still fell by more than this fraction in the last step
CURVATURE_FRACTION = 1e-6  # a saddle: an eigenvalue of H below -this fraction of sigma_max^2
PROBE_STEPS = 30  # the probe: at most this many light steps
PROBE_DAMPING = 1e-2  # the probe's first lambda, as a fraction of sigma_max
PROBE_LIGHTER, PROBE_HEAVIER = 3.0, 2.0  # lambda / 3 after a kept step, x 2 after a refused one
PROBE_MAX_TURN = 0.1  # radians per probe step: the probe stays near the basin it starts in
IMPROVABLE = 1e-3  # a gain counts above this fraction of ||e|| (and above tol)
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


def helps(start, current, trial, slack):
    """Is `trial` better than `current`, level by level? Some level falls while no level
    before it is more than `slack` above where the probe started (`start`)."""
    held = trial <= start + slack
    held_before = jnp.cumprod(jnp.concatenate([jnp.ones(1, bool), held[:-1]]))
    return jnp.any((trial < current) & (held_before > 0))


def gains(start, end, visible):
    """Did the probe gain? Some level fell by more than `visible` while no level before it
    rose by more than `visible`."""
    fall = start - end
    held_before = jnp.cumprod(jnp.concatenate([jnp.ones(1), (fall >= -visible)[:-1]]))
    return jnp.any((fall > visible) & (held_before > 0))


def probe(problem, theta, e, J, levels, free, lower, upper, sigma_max, slack):
    """Up to PROBE_STEPS light priority steps from theta (e and J there), each kept only when it
    helps (module doc); returns where the probe ends, e there and its level norms. Each step walks
    the arm once, at its trial point: e and J there are kept with it (a refused trial leaves q,
    its e and its J as they were)."""
    def light_step(e, J, damping):
        J = J * free
        if len(levels) == 1:  # one level: the DLS step (as multilevel_step, without its SVD)
            step = damped_step(J[jnp.asarray(levels[0])], e[jnp.asarray(levels[0])], damping)
        else:
            step = multilevel_step([(J[jnp.asarray(r)], e[jnp.asarray(r)]) for r in levels], damping)
        return cap_step(step, PROBE_MAX_TURN)

    start = level_norms(e, levels)

    def one(_, carry):
        q, e, J, norms, f = carry
        trial = jnp.clip(q + light_step(e, J, f * sigma_max), lower, upper)
        trial_e, trial_J = problem.error_and_jacobian(trial)
        trial_norms = level_norms(trial_e, levels)
        kept = helps(start, norms, trial_norms, slack)
        keep = lambda new, old: jnp.where(kept, new, old)
        return (keep(trial, q), keep(trial_e, e), keep(trial_J, J), keep(trial_norms, norms),
                keep(f / PROBE_LIGHTER, f * PROBE_HEAVIER))

    end, end_e, _, norms, _ = jax.lax.fori_loop(0, PROBE_STEPS, one, (theta, e, J, start, PROBE_DAMPING))
    return end, end_e, norms


def saddle(problem, theta, rows, free, sigma_max):
    """The Hessian of 1/2 ||e_0||^2 (level 0's rows, the free joints) clearly negative somewhere.
    Only level 0: a later level moves on the curved set where the levels before it stay met,
    whose curvature its own Hessian does not see (a saddle there reads as a minimum).
    H = jax.hessian, forward over reverse mode: n forward passes of the gradient, each one
    reverse pass (a 57-joint character: 12 ms a row, where forward over forward took 260 ms)."""
    half_square = lambda q: 0.5 * jnp.sum(problem.error(q)[jnp.asarray(rows)] ** 2)
    H = jnp.where(free[:, None] & free[None, :], jax.hessian(half_square)(theta), 0.0)
    return jnp.linalg.eigvalsh(H)[0] < -CURVATURE_FRACTION * sigma_max**2


def stall_kind(problem, theta, lower, upper, levels, tol):
    """Why a solve stopped small at theta: MINIMUM (out of reach), SADDLE or CUT_SHORT (module
    doc). levels: the error's row indices per priority level, level 0 first (a tuple of
    tuples); tol: the solve's tolerance."""
    e, J = problem.error_and_jacobian(theta)  # one walk of the arm, shared with the probe
    g = J.T @ e
    free = ~(((theta <= lower) & (g < 0)) | ((theta >= upper) & (g > 0)))  # not pushed into a limit
    sigma_max = jnp.linalg.norm(J * free, 2)
    visible = jnp.maximum(IMPROVABLE * jnp.linalg.norm(e), tol)  # smaller changes do not count
    _, end_e, norms = probe(problem, theta, e, J, levels, free, lower, upper, sigma_max, visible)
    gained = gains(level_norms(e, levels), norms, visible) | (jnp.linalg.norm(end_e) < tol)
    at_saddle = saddle(problem, theta, levels[0], free, sigma_max)
    return jnp.where(gained, CUT_SHORT, jnp.where(at_saddle, SADDLE, MINIMUM))


def why_stopped(problem, theta, lower, upper, levels, tol, own_update):
    """stall_kind, with CUT_SHORT read as FIXED_POINT where own_update (FABRIK or CCD without
    max_step: a method whose update is not a Jacobian step). Pure JAX: one compiled program
    can run it after the loop."""
    kind = stall_kind(problem, theta, lower, upper, levels, tol)
    return jnp.where(own_update & (kind == CUT_SHORT), FIXED_POINT, kind)


STALL_BLOCKS = (8, 1024)  # up to 8 rows: one per call (a solve's); 1,024 per call for a batch


def kind_of_row(shared, target, theta):
    """why_stopped for one row of a batch: the problem with this row's target."""
    problem, lower, upper, levels, tol, own_update = shared
    return why_stopped(replace(problem, target=target), theta, lower, upper, levels, tol,
                       own_update)


def why_stalled(problem, targets, thetas, looked, options, levels, own_update=False):
    """why_stopped of every row where `looked` (MINIMUM elsewhere), run by engine.run_rows:
    one row per call for up to STALL_BLOCKS[0] rows (a solve's, a small batch's; compiled light:
    ikteach/_runtime/jit.py), STALL_BLOCKS[1] per device for a batch on a CPU (on an
    accelerator all rows at once), the last call padded: two compiled programs per problem on a
    CPU, whatever the count (a new count would otherwise compile again: 0.3-0.5 s on a live
    map's lambda change).

    Called once after the loop: targets (B, ...) and thetas (B, n) where each row stopped,
    looked (B,) True where the row ended "stalled" or "slow", options the solve's (tol,
    joint_limits), levels the error's rows per priority level (passed as data: levels of the
    same sizes in another order share a program); KIND_STATUS[kind] is the status each row's
    kind reports."""
    kinds = np.full(np.shape(looked), MINIMUM)
    rows = np.flatnonzero(looked)
    if rows.size == 0:
        return kinds
    n = np.shape(thetas)[-1]
    bounds = [np.broadcast_to(np.asarray(b, dtype=float), (n,)) for b in options.joint_limits]
    levels = tuple(np.asarray(level, dtype=np.int64) for level in levels)  # data, not program
    shared = (problem, *bounds, levels, options.tol, np.asarray(bool(own_update)))
    kinds[rows] = engine.run_rows(kind_of_row, shared, (np.asarray(targets)[rows],
                                                        np.asarray(thetas)[rows]), *STALL_BLOCKS)
    return kinds
