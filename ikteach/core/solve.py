"""ik.solve: the loop of loop.py from theta0 until a stop rule fires, with its trace.

After the loop, a "stalled" or "slow" solve is looked at where it stopped
(stop_rules.why_stalled): a saddle of ||e|| becomes "singular", a stop where a short run of
light steps still gains "damped", and "slow" stays "slow" only while such steps still gain.
"""
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from ._pytree import replace
from ._validate import as_array, round_finite
from .joint_limits import with_limits
from .levels import Priorities, with_priorities
from .loop import CONVERGED, RUNNING, SLOW, STALLED, STATUSES, iterate, start
from .methods import METHODS, as_method, check_method_target, traceable
from .options import Options
from .problem import Problem
from .tasks import task_for
from . import stop_rules
from .._runtime import engine, shared


class StopSolve(Exception):
    """Raise from a step function to end the solve "stalled" (e.g. an out-of-reach stop rule).

    The loop keeps the current theta; the step that raised is not taken.
    """


def status_counts(status):
    """How many entries of an array of status names ended in each status."""
    return {s: int(np.sum(np.asarray(status) == s)) for s in STATUSES[1:]}


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
        theta = round_finite(self.theta, 4).tolist()
        return (f"Result(status={self.status!r}, iterations={self.iterations}, "
                f"error={self.error:.3g}, theta={theta})")


def as_options(options, values):
    """One Options from options= and keyword values (the keywords win)."""
    if options is None:
        return Options(**values)
    if not isinstance(options, Options):
        raise ValueError(f"options: expected ik.Options(...), got {options!r:.80}")
    return dataclasses.replace(options, **values) if values else options


def prepare(arm, target, theta0, method, options, method_parameters, rows=None):
    """Everything solve, solve_batch and track check and build, once: the problem, the method
    (defaults filled in, priorities and joint limits wrapped around it), the resolved options
    and theta0 (moved onto the joint limits). rows: the name of target's rows ("targets") when
    target holds one target per row; the problem then holds the first."""
    name = rows or "target"
    target = as_array(target, name)
    if rows and target.ndim < 2:
        raise ValueError(f"{name}: expected one target per row, got shape {target.shape}")
    if rows and target.shape[0] == 0:
        raise ValueError(f"{name}: expected at least one target, got none (shape {target.shape})")
    task = task_for(arm, target.shape[1:] if rows else target.shape, name)
    if hasattr(task, "check_target"):  # pose targets: rigid transforms only
        task.check_target(target, name)
    if options.weights is not None:
        if not hasattr(task, "weighted"):
            raise ValueError("weights: only pose targets (a 4x4 transform for a spatial "
                             "chain) take weights (position_weight, orientation_weight)")
        task = task.weighted(options.weights)
    problem = Problem(task, arm, jnp.asarray(target[0] if rows else target))
    method = as_method(method, **method_parameters)
    L, n = problem.length_scale(), arm.n_joints
    method, options = method.resolved(L), options.resolved(L, n)
    if rows and np.ndim(theta0) == 2:
        theta0 = as_array(theta0, "theta0", shape=(target.shape[0], n))
    else:
        theta0 = as_array(theta0, "theta0", shape=(n,))
    theta0 = np.clip(theta0, *options.joint_limits)
    method = with_priorities(method, problem, theta0.reshape(-1, n)[0], options)
    check_method_target(method, problem, name)
    if options.levels is None and options.rest_pose is None:  # one program for every method
        method = shared.one_of(method, tuple(METHODS.values()), L)  # (ikteach/_runtime/shared.py)
    method = with_limits(method, options)
    # what the task and method were built from: the loop needs none of it
    options = replace(options, levels=None, rest_pose=None, rest_gain=None, weights=None)
    return problem, method, options, theta0, target


def explain_stalls(problem, method, options, targets, thetas, status):
    """status with each STALLED or SLOW row looked at where it stopped (stop_rules.why_stalled):
    a minimum of ||e|| says STALLED, a saddle SINGULAR, a stop short of a minimum DAMPED (or
    FABRIK's or CCD's own fixed point FIXED_POINT); a SLOW row stays SLOW only while a light
    step still gains. Priority levels are judged level by level."""
    status = np.array(status)
    looked = (status == STALLED) | (status == SLOW)
    if not looked.any():
        return status
    rows = jax.eval_shape(problem.error, np.asarray(thetas)[0]).shape[0]
    inner = getattr(method, "inner", method)  # within joint limits: the method inside
    levels = inner.rows if isinstance(inner, Priorities) else (np.arange(rows),)
    own_update = not method.uses_jacobian and not np.isfinite(options.max_step)
    kinds = stop_rules.why_stalled(problem, targets, thetas, looked, options, levels, own_update)
    named = np.array([STATUSES.index(name) for name in stop_rules.KIND_STATUS])[kinds]
    still_slow = (status == SLOW) & np.isin(kinds, (stop_rules.CUT_SHORT, stop_rules.FIXED_POINT))
    return np.where(looked & ~still_slow, named, status)


def solve(arm, target, theta0, method="dls", options=None, *, damping=None, rcond=None,
          gamma_max=None, **option_values):
    """Solve F(theta) = target from theta0 by repeated steps of `method` (loop.py's loop).

    method    a method object (ik.JT(), ik.Pinv(rcond), ik.DLS(damping), ik.SDLS(gamma_max),
              ik.CCD(), ik.FABRIK()), its name ("jt", "pinv", "dls", "sdls", "ccd", "fabrik"),
              or a function step(J, e) -> delta_theta (it may raise ik.StopSolve to end the
              solve "stalled": its own stop rule).
    damping, rcond, gamma_max: the named method's own parameter (DLS's lambda, default L / 6
              with L the arm's size; the pseudoinverse's relative cut-off; SDLS's largest turn).
    options   an ik.Options, or its fields as keywords (tol, max_iter, clamp, max_step,
              stall_tol, stop_rule, joint_limits, limit_mode, levels, rest_pose, rest_gain,
              weights; ikteach/core/options.py says what each does).
    Returns a Result: theta, status (loop.STATUSES), iterations, error (final ||e||), trace.

    Bad input raises a ValueError naming the parameter (numbers: ikteach/core/_validate.py;
    a 4x4 target must be a rigid transform; ccd and fabrik take position targets on chains).
    """
    options = as_options(options, option_values)
    problem, method, options, theta0, target = prepare(
        arm, target, theta0, method, options,
        {"damping": damping, "rcond": rcond, "gamma_max": gamma_max})
    args = (problem, method, options)
    if traceable(method, problem, theta0):
        state, thetas, errors = engine.run_traced(iterate, args, start(theta0))
    else:
        state, thetas, errors = engine.run_eager(iterate, args, start(theta0), StopSolve,
                                                 lambda s: stopped_by_step(problem, options, s))
    status = explain_stalls(problem, method, options, np.asarray(target)[None],
                            np.asarray(state.theta)[None], np.asarray(state.status)[None])[0]
    return Result(_frozen(state.theta), STATUSES[int(status)], int(state.i),
                  float(state.error), Trace(_frozen(thetas), _frozen(errors)))


def stopped_by_step(problem, options, state):
    """The state when a step function raised StopSolve: converged if ||e|| < tol, else stalled."""
    error = jnp.linalg.norm(problem.error(state.theta))
    status = CONVERGED if error < options.tol else STALLED
    return state._replace(error=error, status=jnp.asarray(status))


def _frozen(x):
    arr = np.array(x, dtype=np.float64)
    arr.flags.writeable = False
    return arr


__all__ = ["solve", "Result", "Trace", "StopSolve", "RUNNING", "status_counts", "prepare"]
