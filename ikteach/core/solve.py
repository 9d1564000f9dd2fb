"""The IK loop: repeat theta <- theta + step(J(theta), e(theta)) until a stop rule fires.

Each iteration, at the current theta:
  1. e = target - F(theta); record theta and ||e|| in the trace;
  2. stop "converged" if ||e|| < tol (checked before any step is taken);
  3. stop "stalled" if the last step was smaller than stall_tol (out of reach), or "slow" if
     so but ||e|| still fell by a steady fraction (see stop_rules.py: the size is
     ||J delta_theta|| by default, sum |delta_theta_i| with stop_rule="joint_steps");
  4. stop "max_iter" after max_iter steps;
  5. otherwise delta_theta = cap(step(J, clamp(e))); a non-finite step stops "diverged"
     and keeps the last finite theta.
After the loop, a "stalled" solve is looked at where it stopped (stop_rules.stall_kind):
a saddle of ||e|| becomes "singular", a stop while J still sees the error "damped".
"""
import dataclasses
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ._validate import as_array, as_count, as_number
from .sdls import GAMMA_MAX
from .levels import with_priorities
from .joint_limits import with_limits
from .limits import cap_step
from .methods import METHODS, check_method_target, resolve_method, traceable
from .pinv import DEFAULT_RCOND
from .tasks import task_for
from . import stop_rules
from .._runtime import jit as runtime_jit

# What each status means (the course's definitions; append only):
#   converged  ||e|| < tol.
#   stalled    the steps stopped moving the end effector at a minimum of ||e||: out of reach.
#   max_iter   max_iter steps taken, none of the other stops fired (e.g. the pseudoinverse
#              out of reach: it never settles).
#   diverged   a non-finite error or step.
#   slow       the stall rule fired, but ||e|| still fell by more than SLOW_PROGRESS per step:
#              still closing in (e.g. the Jacobian transpose along a weak direction).
#   singular   the stall rule fired at a saddle of ||e|| (a singular pose whose error J cannot
#              see, e.g. a straight arm with the target on its line): not out of reach.
#   damped     the stall rule fired while J still sees the error: the damping, max_step or
#              clamp cut the steps to nothing for this arm's size. Not out of reach.
STATUSES = ("running", "converged", "stalled", "max_iter", "diverged", "slow", "singular",
            "damped")
RUNNING, CONVERGED, STALLED, MAX_ITER, DIVERGED, SLOW, SINGULAR, DAMPED = range(8)

# Defaults that are lengths scale with the arm's size L (task.length_scale: the total link
# length of a chain, the size of a tree); for the course's arm of three unit links (L = 3)
# they are tol = 1e-3 and lambda = 0.5.
TOL_PER_LENGTH = 3000      # tol = L / 3000
DAMPING_PER_LENGTH = 6     # damping lambda = L / 6
STALL_PER_TOL = 0.01  # default stall_tol = tol / 100 (L / 300000 with the default tol)
STALL_FRACTION = 1e-5  # the old default stall_tol / L (benchmarks/sweep.py's copies of the report's loop)


class StopSolve(Exception):
    """Raise from a step function to end the solve "stalled" (e.g. an out-of-reach stop rule).

    The loop keeps the current theta; the step that raised is not taken.
    """


def status_counts(status):
    """How many entries of an array of status names ended in each status."""
    return {s: int(np.sum(np.asarray(status) == s)) for s in STATUSES[1:]}


class Settings(NamedTuple):
    """Numbers the loop reads (traced, so changing them does not recompile)."""
    tol: float
    damping: float
    rcond: float
    clamp: float      # D_max; inf for no clamp
    max_step: float   # per-joint cap in radians; inf for none
    stall_tol: float  # 0 disables the stall stop
    gamma_max: float = np.pi / 4  # SDLS: largest joint turn per step (Buss & Kim 2005)
    lower: object = -np.inf  # joint limits, per joint (ikteach/joint_limits.py)
    upper: object = np.inf
    rest_pose: object = 0.0  # the rest-pose level of a prioritised solve (ikteach/levels.py)
    rest_gain: float = 0.0
    stop_rule: int = stop_rules.STOP_RULES.index(stop_rules.DEFAULT_STOP_RULE)


@dataclasses.dataclass(frozen=True)
class Trace:
    """theta[k] and error[k] = ||e|| at iteration k; entry 0 is the start."""
    theta: np.ndarray
    error: np.ndarray


@dataclasses.dataclass(frozen=True)
class Result:
    theta: np.ndarray
    status: str
    iterations: int
    error: float
    trace: Trace

    @property
    def converged(self):
        return self.status == "converged"

    def __repr__(self):
        return (f"Result(status={self.status!r}, iterations={self.iterations}, "
                f"error={self.error:.3g}, theta={np.round(self.theta, 4).tolist()})")


class State(NamedTuple):
    i: jax.Array
    theta: jax.Array
    error: jax.Array
    last_step: jax.Array
    status: jax.Array
    trace_theta: jax.Array
    trace_error: jax.Array


@dataclasses.dataclass(frozen=True)
class _Linearized:
    """The task with J(theta) at this iteration's theta already computed (read, not redone)."""
    task: object
    theta: object
    J: object

    def jacobian(self, arm, theta):
        return self.J if theta is self.theta else self.task.jacobian(arm, theta)

    def __getattr__(self, name):  # everything else is the task's
        if name == "task":
            raise AttributeError(name)
        return getattr(self.task, name)


def linearize(task, arm, target, theta):
    """e(theta) and a task that hands back J(theta): one walk of the chain where the task
    offers error_and_jacobian (position targets on chains), two calls otherwise."""
    if not hasattr(task, "error_and_jacobian"):
        return task.error(arm, target, theta), task
    e, J = task.error_and_jacobian(arm, target, theta)
    return e, _Linearized(task, theta, J)


def advance(method, task, arm, target, settings, max_iter, state, first=0):
    """One pass of the loop described in the module docstring. The trace holds the iterations
    from `first` on (solve runs the loop TRACE_CHUNK iterations at a time)."""
    e, task = linearize(task, arm, target, state.theta)
    err = jnp.linalg.norm(e)
    row = state.i - first
    trace_error = state.trace_error.at[row].set(err) if state.trace_error.size else state.trace_error
    status = jnp.select(
        [~jnp.isfinite(err), err < settings.tol,
         (state.i > 0) & (state.last_step < settings.stall_tol), state.i >= max_iter],
        [DIVERGED, CONVERGED, STALLED, MAX_ITER], RUNNING)
    status = jnp.where((status == STALLED) & stop_rules.still_progressing(state.error, err),
                       SLOW, status)
    delta = jnp.asarray(method.delta(task, arm, target, state.theta, e, settings))
    if delta.shape != state.theta.shape:
        raise ValueError(f"method: the step function returned shape {delta.shape}, "
                         f"expected {state.theta.shape} (one entry per joint)")
    delta = cap_step(delta.astype(state.theta.dtype), settings.max_step)
    new_theta = jnp.clip(state.theta + delta, settings.lower, settings.upper)  # joint limits
    finite = jnp.all(jnp.isfinite(new_theta))
    status = jnp.where((status == RUNNING) & ~finite, DIVERGED, status)
    take = status == RUNNING
    i = jnp.where(take, state.i + 1, state.i)
    theta = jnp.where(take, new_theta, state.theta)
    trace_theta = state.trace_theta
    if trace_theta.size:
        trace_theta = jnp.where(take, trace_theta.at[row + 1].set(new_theta), trace_theta)
    size = stop_rules.step_size(settings.stop_rule, lambda: task.jacobian(arm, state.theta), delta)
    return State(i, theta, err, jnp.where(take, size, state.last_step),
                 status, trace_theta, trace_error)


TRACE_CHUNK = 256  # iterations per compiled run when the trace is kept (memory follows the work)
MAX_ITER_CAP = 10**6  # the largest max_iter accepted: a full trace of 12 joints is then 100 MB


def initial_state(theta0, record):
    """The state before iteration 0; with record, room for one chunk of trace."""
    n = theta0.shape[0]
    rows = TRACE_CHUNK + 1 if record else 0
    inf = jnp.asarray(np.inf, dtype=jnp.float64)  # strongly typed: a state fed back in
    return State(jnp.asarray(0, dtype=jnp.int64), theta0, inf, inf,  # reuses the program
                 jnp.asarray(RUNNING, dtype=jnp.int64), jnp.zeros((rows, n)), jnp.zeros((rows,)))


def run_loop(method, task, arm, target, theta0, settings, max_iter, record=False, state=None):
    """The loop as a lax.while_loop (traceable: used under jit and vmap), from theta0 or from a
    state. Without record it runs to the end; with record it stops after TRACE_CHUNK
    iterations (or at the end), its trace holding iterations state.i, state.i + 1, ..."""
    state = initial_state(theta0, record) if state is None else state
    first = state.i
    if record:
        state = state._replace(trace_theta=jnp.zeros_like(state.trace_theta).at[0].set(state.theta),
                               trace_error=jnp.zeros_like(state.trace_error))
    body = partial(advance, method, task, arm, target, settings, max_iter, first=first)
    more = (lambda s: (s.status == RUNNING) & (s.i < first + TRACE_CHUNK)) if record else \
        (lambda s: s.status == RUNNING)
    return jax.lax.while_loop(more, body, state)


@partial(runtime_jit.jit, static_argnames=("method",))
def _run_jit(method, task, arm, target, state, settings, max_iter):
    """One chunk of the compiled loop, run as a batch of one so that its arithmetic is the
    batched arithmetic of solve_batch. max_iter is traced: any iteration count reuses it."""
    one = lambda t, s: run_loop(method, task, arm, t, None, settings, max_iter, True, s)
    out = jax.vmap(one)(target[None], jax.tree_util.tree_map(lambda x: x[None], state))
    return jax.tree_util.tree_map(lambda x: x[0], out)


def _run_eager(method, task, arm, target, state, settings, max_iter):
    """The same chunk, one Python iteration at a time, for step functions JAX cannot trace."""
    first = int(state.i)
    state = state._replace(trace_theta=jnp.zeros_like(state.trace_theta).at[0].set(state.theta),
                           trace_error=jnp.zeros_like(state.trace_error))
    while int(state.status) == RUNNING and int(state.i) < first + TRACE_CHUNK:
        try:
            state = advance(method, task, arm, target, settings, max_iter, state, first)
        except StopSolve:  # the step function's own stop rule fired
            err = jnp.linalg.norm(task.error(arm, target, state.theta))
            status = CONVERGED if err < settings.tol else STALLED  # same order as advance
            state = state._replace(error=err, status=jnp.asarray(status),
                                   trace_error=state.trace_error.at[int(state.i) - first].set(err))
    return state


def run_chunks(run, method, task, arm, target, theta0, settings, max_iter):
    """Run the loop chunk by chunk (run: _run_jit or _run_eager) until it stops; returns the
    last state (on the host) and the whole trace, theta (k + 1, n) and error (k + 1,)."""
    theta0 = np.asarray(theta0)  # the start state built on the host: no small device programs
    n, rows = theta0.shape[0], TRACE_CHUNK + 1
    state = State(np.int64(0), theta0, np.float64(np.inf), np.float64(np.inf), np.int64(RUNNING),
                  np.zeros((rows, n)), np.zeros(rows))
    thetas, errors, max_iter = [], [], np.int64(max_iter)
    while True:
        first = int(state.i)
        state = jax.device_get(run(method, task, arm, target, state, settings, max_iter))
        k = int(state.i) - first
        done = int(state.status) != RUNNING
        thetas.append(state.trace_theta[: k + done])
        errors.append(state.trace_error[: k + done])
        if done:
            return state, np.concatenate(thetas), np.concatenate(errors)


def with_extras(method, task, arm, target, theta0, settings, levels, rest_pose, rest_gain,
                joint_limits, limit_mode, batch=False):
    """Priority levels and joint limits, when asked for, wrapped around the method.
    With batch=True, target holds one target per row and theta0 may too."""
    one = (target[0], theta0.reshape(-1, arm.n_joints)[0]) if batch else (target, theta0)
    method, settings = with_priorities(method, task, arm, *one, settings, levels, rest_pose,
                                       rest_gain, is_default=method is METHODS["dls"])
    return with_limits(method, settings, theta0, joint_limits, limit_mode, arm.n_joints)


def default_tol(task, arm):
    """tol when none is given: L / TOL_PER_LENGTH (1e-3 for three unit links)."""
    return task.length_scale(arm) / TOL_PER_LENGTH


def default_damping(task, arm):
    """DLS's lambda when none is given: L / DAMPING_PER_LENGTH (0.5 for three unit links)."""
    return task.length_scale(arm) / DAMPING_PER_LENGTH


def check_problem(arm, target, theta0, *, tol, max_iter, damping, rcond, clamp, max_step,
                  stall_tol, gamma_max=GAMMA_MAX, batch=False,
                  weights=None, stop_rule=stop_rules.DEFAULT_STOP_RULE, method=None):
    """Validate everything solve/solve_batch take (numbers: see ikteach/core/_validate.py).

    Returns (task, target, theta0, settings, max_iter). With batch=True, target holds
    one target per row (at least one row) and theta0 is (n,) or (B, n).
    """
    name = "targets" if batch else "target"
    target = as_array(target, name)
    if batch and target.ndim < 2:
        raise ValueError(f"targets: expected one target per row, got shape {target.shape}")
    if batch and target.shape[0] == 0:
        raise ValueError(f"targets: expected at least one target, got none (shape {target.shape})")
    task = task_for(arm, target.shape[1:] if batch else target.shape, name)
    if hasattr(task, "check_target"):  # pose targets: rigid transforms only
        task.check_target(target, name)
    check_method_target(method, task, arm, name)
    if weights is not None:  # pose targets: weights (position, orientation) on the error
        if not hasattr(task, "weighted"):
            raise ValueError("weights: only pose targets (a 4x4 transform for a spatial "
                             "chain) take weights (position_weight, orientation_weight)")
        task = task.weighted(weights)
    n = arm.n_joints
    if batch and np.ndim(theta0) == 2:
        theta0 = as_array(theta0, "theta0", shape=(target.shape[0], n))
    else:
        theta0 = as_array(theta0, "theta0", shape=(n,))
    max_iter = as_count(max_iter, "max_iter", minimum=1)
    if max_iter > MAX_ITER_CAP:
        raise ValueError(f"max_iter: expected at most {MAX_ITER_CAP:,} iterations (ik.solve keeps "
                         f"every iterate), got {max_iter:,}")
    tol = default_tol(task, arm) if tol is None else tol
    if stall_tol is None:  # a step that moves the effector by less than tol / 100 does not matter
        stall_tol = STALL_PER_TOL * as_number(tol, "tol")
    else:
        stall_tol = as_number(stall_tol, "stall_tol", minimum=0)
    damping = default_damping(task, arm) if damping is None else damping
    settings = Settings(
        tol=as_number(tol, "tol", minimum=0, strict=True),
        damping=as_number(damping, "damping", minimum=0),
        rcond=as_number(rcond, "rcond", minimum=0),
        clamp=np.inf if clamp is None else as_number(clamp, "clamp", minimum=0, strict=True),
        max_step=np.inf if max_step is None else as_number(max_step, "max_step", minimum=0, strict=True),
        stall_tol=stall_tol,
        gamma_max=as_number(gamma_max, "gamma_max", minimum=0, strict=True),
        stop_rule=stop_rules.rule_index(stop_rule),
    )
    return task, jnp.asarray(target), jnp.asarray(theta0), settings, max_iter


def explain_stalls(method, task, arm, targets, thetas, status, settings):
    """status with each STALLED row looked at where it stopped (stop_rules.why_stalled):
    a saddle of ||e|| becomes SINGULAR, a stop while J still sees the error DAMPED."""
    status = np.array(status)
    kinds = stop_rules.why_stalled(method, task, arm, targets, thetas, status == STALLED, settings)
    return np.select([kinds == stop_rules.SADDLE, kinds == stop_rules.CUT_SHORT],
                     [SINGULAR, DAMPED], status)


def solve(arm, target, theta0, method="dls", tol=None, max_iter=1000, damping=None,
          rcond=DEFAULT_RCOND, clamp=None, max_step=None, stall_tol=None, gamma_max=GAMMA_MAX,
          weights=None, stop_rule=stop_rules.DEFAULT_STOP_RULE, joint_limits=None,
          limit_mode=None, levels=None, rest_pose=None, rest_gain=None):
    """Solve F(theta) = target from theta0 by repeated steps of `method`.

    method    "jt", "pinv", "dls", "sdls", "ccd", "fabrik", or a function step(J, e) -> delta_theta
              (it may raise ik.StopSolve to end the solve "stalled": its own stop rule).
    tol       stop "converged" when ||e|| < tol (a length; default L / 3000, with L the arm's
              total link length or a tree's size: 1e-3 for three unit links).
    max_iter  stop "max_iter" after this many steps (at most MAX_ITER_CAP; any value reuses the
              compiled loop, and the trace grows with the iterations taken, not with max_iter).
    damping   lambda of DLS (a length: default L / 6, 0.5 for three unit links).
    rcond     the pseudoinverse's relative cut-off.
    clamp     Buss's D_max: |e| is clamped to at most D_max before each step.
    max_step  cap on any joint's change per step, in radians.
    stall_tol stop when the last step's size < stall_tol (default tol / 100; 0 turns it off):
              "stalled" at a minimum of ||e|| (out of reach), "slow" if ||e|| still falls,
              "singular" at a saddle, "damped" if J still sees the error (see STATUSES).
    stop_rule the step's size: "motion" (||J delta_theta||, the end effector's motion:
              scale-free, the default) or "joint_steps" (the report's sum |delta_theta_i|,
              radians against a length: depends on the unit of length). See stop_rules.py.
    gamma_max SDLS's largest joint turn per step (default pi/4).
    weights   for a 4x4 pose target: (position_weight, orientation_weight), default (1, 1).
    joint_limits  (lower, upper): per-joint arrays (or numbers), +-inf for no limit; every
              theta of the result and trace stays within them (ikteach/joint_limits.py).
    limit_mode    "clamping_loop" (default for Jacobian methods: pinned joints leave J and
              the rest re-solves) or "clamp" (clip after the step; any method); only with
              joint_limits.
              A start theta0 outside the limits is first moved onto them (clipped joint by
              joint): the trace starts there, not at theta0.
    levels    priority of each target block, 0 first (one per end effector of a tree; for a
              pose: position, orientation), whole numbers: each level is solved in the null
              space of those before it (ikteach/levels.py).  rest_pose: a last level pulling
              theta towards rest_pose with gain rest_gain (default 0.1, levels.py's
              DEFAULT_REST_GAIN; only with rest_pose) in the freedom that is left.
    Returns a Result: theta, status, iterations, error (final ||e||) and trace. A start outside
    joint_limits is moved onto them first.

    Bad input raises a ValueError naming the parameter: numbers must be real (no booleans,
    strings or complex), finite and of magnitude at most 1e40, positive sizes (tol, damping,
    ...) 0 where allowed or at least 1e-100, link lengths 0 or at least 1e-40 (the reasons:
    ikteach/core/_validate.py); a 4x4 target must be
    a rigid transform (check_pose in ikteach/core/pose.py); ccd and fabrik take position
    targets on chains only.
    """
    method = resolve_method(method)
    task, target, theta0, settings, max_iter = check_problem(
        arm, target, theta0, tol=tol, max_iter=max_iter, damping=damping, rcond=rcond,
        clamp=clamp, max_step=max_step, stall_tol=stall_tol, gamma_max=gamma_max,
        weights=weights, stop_rule=stop_rule, method=method)
    method, settings, theta0 = with_extras(method, task, arm, target, theta0, settings, levels,
                                           rest_pose, rest_gain, joint_limits, limit_mode)
    run = _run_jit if traceable(method, task, arm, target, theta0, settings) else _run_eager
    state, thetas, errors = run_chunks(run, method, task, arm, target, theta0, settings, max_iter)
    status = explain_stalls(method, task, arm, target[None], np.asarray(state.theta)[None],
                            np.asarray(state.status)[None], settings)[0]
    return Result(_frozen(state.theta), STATUSES[int(status)], int(state.i),
                  float(state.error), Trace(_frozen(thetas), _frozen(errors)))


def _frozen(x):
    arr = np.array(x, dtype=np.float64)
    arr.flags.writeable = False
    return arr
