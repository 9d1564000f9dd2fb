"""The IK loop: repeat theta <- theta + step(J(theta), e(theta)) until a stop rule fires.

Each iteration, at the current theta:
  1. e = target - F(theta); record theta and ||e|| in the trace;
  2. stop "converged" if ||e|| < tol (checked before any step is taken);
  3. stop "stalled" if the last step was smaller than stall_tol (out of reach), or "slow" if
     so but ||e|| still fell by a steady fraction (see stop_rules.py: the size is
     sum |delta_theta_i| by default, ||J delta_theta|| with stop_rule="motion");
  4. stop "max_iter" after max_iter steps;
  5. otherwise delta_theta = cap(step(J, clamp(e))); a non-finite step stops "diverged"
     and keeps the last finite theta.
"""
import dataclasses
import inspect
from functools import partial
from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ._validate import as_array, as_count, as_number
from .ccd import CCDMethod
from .dls import dls_step
from .fabrik import FABRIKMethod
from .sdls import GAMMA_MAX, SDLSMethod
from .jt import jt_step
from .levels import DEFAULT_REST_GAIN, PriorityMethod, with_priorities
from .joint_limits import LimitedMethod, with_limits
from .limits import cap_step, clamp_error
from .pinv import DEFAULT_RCOND, pinv_step, pinv_two_rows
from .tasks import task_for
from . import stop_rules
from .._runtime import jit as runtime_jit

STATUSES = ("running", "converged", "stalled", "max_iter", "diverged", "slow")  # append only
RUNNING, CONVERGED, STALLED, MAX_ITER, DIVERGED, SLOW = range(6)

DEFAULT_DAMPING = 0.5
STALL_FRACTION = 1e-5  # default stall_tol = STALL_FRACTION * total link length


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
    stop_rule: int = 0  # index into stop_rules.STOP_RULES


def _jt(J, e, s):
    return jt_step(J, e)


def _pinv(J, e, s):
    if J.shape[0] == 2:  # planar position targets: the closed form, no SVD call
        return pinv_two_rows(J, e, s.rcond)
    return pinv_step(J, e, s.rcond)


def _dls(J, e, s):
    return dls_step(J, e, s.damping)


@dataclasses.dataclass(frozen=True)
class JacobianMethod:
    """A method that turns (J, clamped e) into a step: step(J, e, settings) -> delta_theta."""
    step: Callable

    def delta(self, task, arm, target, theta, e, settings):
        J = task.jacobian(arm, theta)
        return self.step(J, clamp_error(e, settings.clamp), settings)


@dataclasses.dataclass(frozen=True)
class UserStep:
    """A step function step(J, e) -> delta_theta given by the user."""
    fn: Callable

    def __call__(self, J, e, s):
        return self.fn(J, e)


METHODS = {"jt": JacobianMethod(_jt), "pinv": JacobianMethod(_pinv), "dls": JacobianMethod(_dls)}
METHODS.update(sdls=SDLSMethod(), ccd=CCDMethod(), fabrik=FABRIKMethod())


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


def advance(method, task, arm, target, settings, max_iter, state):
    """One pass of the loop described in the module docstring."""
    e, task = linearize(task, arm, target, state.theta)
    err = jnp.linalg.norm(e)
    trace_error = state.trace_error.at[state.i].set(err) if state.trace_error.size else state.trace_error
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
        trace_theta = jnp.where(take, trace_theta.at[i].set(new_theta), trace_theta)
    size = stop_rules.step_size(settings.stop_rule, lambda: task.jacobian(arm, state.theta), delta)
    return State(i, theta, err, jnp.where(take, size, state.last_step),
                 status, trace_theta, trace_error)


def initial_state(theta0, max_iter, record):
    n = theta0.shape[0]
    rows = max_iter + 1 if record else 0
    trace_theta = jnp.zeros((rows, n)).at[0].set(theta0) if record else jnp.zeros((0, n))
    return State(jnp.asarray(0), theta0, jnp.asarray(jnp.inf), jnp.asarray(jnp.inf),
                 jnp.asarray(RUNNING), trace_theta, jnp.zeros((rows,)))


def run_loop(method, task, arm, target, theta0, settings, max_iter, record):
    """The loop as a lax.while_loop (traceable: used under jit and vmap)."""
    body = partial(advance, method, task, arm, target, settings, max_iter)
    return jax.lax.while_loop(lambda s: s.status == RUNNING, body,
                              initial_state(theta0, max_iter, record))


@partial(runtime_jit.jit, static_argnames=("method", "task", "max_iter", "record"))
def _run_jit(method, task, arm, target, theta0, settings, max_iter, record):
    """The compiled loop, run as a batch of one so that its arithmetic is the batched
    arithmetic of solve_batch: the same target gives the same iterates to the last bit."""
    one = lambda t, q: run_loop(method, task, arm, t, q, settings, max_iter, record)
    state = jax.vmap(one)(target[None], theta0[None])
    return jax.tree_util.tree_map(lambda x: x[0], state)


def _run_eager(method, task, arm, target, theta0, settings, max_iter, record):
    """The same loop, one Python iteration at a time, for step functions JAX cannot trace."""
    state = initial_state(theta0, max_iter, record)
    while int(state.status) == RUNNING:
        try:
            state = advance(method, task, arm, target, settings, max_iter, state)
        except StopSolve:  # the step function's own stop rule fired
            err = jnp.linalg.norm(task.error(arm, target, state.theta))
            trace_error = state.trace_error.at[state.i].set(err) if record else state.trace_error
            status = CONVERGED if err < settings.tol else STALLED  # same order as advance
            state = state._replace(error=err, status=jnp.asarray(status), trace_error=trace_error)
    return state


_TRACEABLE = {}


def traceable(method, task, arm, target, theta0, settings):
    """Can JAX trace the method (pure jax.numpy), or does it need eager execution?

    Built-in methods are JAX code; a user's step is tried once per problem shape.
    """
    if built_in(method):
        return True
    key = (method, task, type(arm), arm.dim, target.shape, theta0.shape)
    if key not in _TRACEABLE:
        try:
            jax.eval_shape(lambda q: method.delta(task, arm, target, q, task.error(arm, target, q),
                                                  settings), theta0)
            _TRACEABLE[key] = True
        except Exception:
            _TRACEABLE[key] = False
    return _TRACEABLE[key]


def built_in(method):
    """Is the method ikteach's own JAX code: a built-in method, the priority step, or one of
    those within joint limits? (Only a user's step function needs trying.)"""
    if isinstance(method, LimitedMethod):
        return built_in(method.inner)
    return method in METHODS.values() or isinstance(method, PriorityMethod)


def resolve_method(method):
    """A method name or a step function step(J, e) -> the loop's step(J, e, settings)."""
    if isinstance(method, str):
        if method not in METHODS:
            raise ValueError(f"method: expected one of {sorted(METHODS)} or a function "
                             f"step(J, e) -> delta_theta, got {method!r}")
        return METHODS[method]
    if callable(method):
        try:
            inspect.signature(method).bind(None, None)
        except TypeError:
            raise ValueError("method: a step function must accept two arguments (J, e)") from None
        except ValueError:
            pass  # builtins without a signature
        return JacobianMethod(UserStep(method))
    raise ValueError(f"method: expected one of {sorted(METHODS)} or a function "
                     f"step(J, e) -> delta_theta, got {method!r:.80}")


def with_extras(method, task, arm, target, theta0, settings, levels, rest_pose, rest_gain,
                joint_limits, limit_mode, batch=False):
    """Priority levels and joint limits, when asked for, wrapped around the method.
    With batch=True, target holds one target per row and theta0 may too."""
    one = (target[0], theta0.reshape(-1, arm.n_joints)[0]) if batch else (target, theta0)
    method, settings = with_priorities(method, task, arm, *one, settings, levels, rest_pose,
                                       rest_gain, is_default=method is METHODS["dls"])
    return with_limits(method, settings, theta0, joint_limits, limit_mode, arm.n_joints)


def check_problem(arm, target, theta0, *, tol, max_iter, damping, rcond, clamp, max_step,
                  stall_tol, gamma_max=GAMMA_MAX, batch=False,
                  weights=None, stop_rule=stop_rules.DEFAULT_STOP_RULE):
    """Validate everything solve/solve_batch take.

    Returns (task, target, theta0, settings, max_iter). With batch=True, target holds
    one target per row and theta0 is (n,) or (B, n).
    """
    name = "targets" if batch else "target"
    target = as_array(target, name)
    if batch and target.ndim < 2:
        raise ValueError(f"targets: expected one target per row, got shape {target.shape}")
    task = task_for(arm, target.shape[1:] if batch else target.shape, name)
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
    if stall_tol is None:
        stall_tol = STALL_FRACTION * task.length_scale(arm)
    settings = Settings(
        tol=as_number(tol, "tol", minimum=0, strict=True),
        damping=as_number(damping, "damping", minimum=0),
        rcond=as_number(rcond, "rcond", minimum=0),
        clamp=np.inf if clamp is None else as_number(clamp, "clamp", minimum=0, strict=True),
        max_step=np.inf if max_step is None else as_number(max_step, "max_step", minimum=0, strict=True),
        stall_tol=as_number(stall_tol, "stall_tol", minimum=0),
        gamma_max=as_number(gamma_max, "gamma_max", minimum=0, strict=True),
        stop_rule=stop_rules.rule_index(stop_rule),
    )
    return task, jnp.asarray(target), jnp.asarray(theta0), settings, max_iter


def solve(arm, target, theta0, method="dls", tol=1e-3, max_iter=1000, damping=DEFAULT_DAMPING,
          rcond=DEFAULT_RCOND, clamp=None, max_step=None, stall_tol=None, gamma_max=GAMMA_MAX,
          weights=None, stop_rule=stop_rules.DEFAULT_STOP_RULE, joint_limits=None,
          limit_mode=None, levels=None, rest_pose=None, rest_gain=DEFAULT_REST_GAIN):
    """Solve F(theta) = target from theta0 by repeated steps of `method`.

    method    "jt", "pinv", "dls", "sdls", "ccd", "fabrik", or a function step(J, e) -> delta_theta
              (it may raise ik.StopSolve to end the solve "stalled": its own stop rule).
    tol       stop "converged" when ||e|| < tol.
    max_iter  stop "max_iter" after this many steps.
    damping   lambda of DLS.   rcond: the pseudoinverse's relative cut-off.
    clamp     Buss's D_max: |e| is clamped to at most D_max before each step.
    max_step  cap on any joint's change per step, in radians.
    stall_tol stop "stalled" (or "slow": still converging) when the last step's size < stall_tol
              (default STALL_FRACTION * total link length; 0 turns it off).
    stop_rule the step's size: "joint_steps" (the report's sum |delta_theta_i|, radians: the
              default, depends on the unit of length) or "motion" (||J delta_theta||, the
              end effector's motion: scale-free, recommended). See ikteach/stop_rules.py.
    gamma_max SDLS's largest joint turn per step (default pi/4).
    weights   for a 4x4 pose target: (position_weight, orientation_weight), default (1, 1).
    joint_limits  (lower, upper): per-joint arrays (or numbers), +-inf for no limit; every
              theta of the result and trace stays within them (ikteach/joint_limits.py).
    limit_mode    "clamping_loop" (default for Jacobian methods: pinned joints leave J and
              the rest re-solves) or "clamp" (clip after the step; any method).
    levels    priority of each target block, 0 first (one per end effector of a tree; for a
              pose: position, orientation): each level is solved in the null space of those
              before it (ikteach/levels.py).  rest_pose: a last level pulling theta towards
              rest_pose with gain rest_gain in the freedom that is left.
    Returns a Result: theta, status, iterations, error (final ||e||) and trace.
    """
    method = resolve_method(method)
    task, target, theta0, settings, max_iter = check_problem(
        arm, target, theta0, tol=tol, max_iter=max_iter, damping=damping, rcond=rcond,
        clamp=clamp, max_step=max_step, stall_tol=stall_tol, gamma_max=gamma_max,
        weights=weights, stop_rule=stop_rule)
    method, settings, theta0 = with_extras(method, task, arm, target, theta0, settings, levels,
                                           rest_pose, rest_gain, joint_limits, limit_mode)
    args = (method, task, arm, target, theta0, settings, max_iter, True)
    state = (_run_jit if traceable(*args[:6]) else _run_eager)(*args)
    state = jax.device_get(state)  # slice on the host: a device slice would compile per length
    k = int(state.i)
    trace = Trace(_frozen(state.trace_theta[: k + 1]), _frozen(state.trace_error[: k + 1]))
    return Result(_frozen(state.theta), STATUSES[int(state.status)], k, float(state.error), trace)


def _frozen(x):
    arr = np.array(x, dtype=np.float64)
    arr.flags.writeable = False
    return arr
