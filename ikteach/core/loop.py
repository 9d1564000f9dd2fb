"""The IK loop of lecture 05: repeat theta <- theta + delta_theta until a stop rule fires.

Each pass, at the current theta:
  1. e = target - F(theta) and J(theta);
  2. the stops, checked before any step is taken: "diverged" (||e|| not finite), "converged"
     (||e|| < tol), "stalled" or "slow" (the last step was smaller than stall_tol), "max_iter";
  3. otherwise delta_theta = cap(method's step(J, clamp(e))), theta <- theta + delta_theta,
     kept within the joint limits.

`ik_loop` below is the whole loop in plain Python; ik.solve, ik.solve_batch and ik.track run
the same `iterate`, compiled (jax.lax.while_loop, jax.vmap) by ikteach/_runtime/engine.py.
"""
from typing import NamedTuple

import jax.numpy as jnp

from .safeguards import cap_step, clamp_error
from .stop_rules import step_size, still_progressing

# What each status means (append only):
#   converged  ||e|| < tol.
#   stalled    the steps stopped moving the end effector at a minimum of ||e||: a short downhill
#              run of light steps from there gains no visible change (more than tol and 0.1 % of
#              ||e||; with priorities, no level gains one while the levels before it hold):
#              out of reach from this start.
#   max_iter   max_iter steps taken and no other stop fired (e.g. the pseudoinverse out of
#              reach: it never settles).
#   diverged   a non-finite error or step (the last finite theta is kept).
#   slow       the stall rule fired while ||e|| still fell by a steady fraction per step, and
#              the light steps from there still gain.
#   singular   stalled at a saddle of ||e|| (a singular pose whose error J cannot see).
#   damped     stalled short of a minimum: the light steps still gain (damping, max_step, clamp,
#              a cut-off or a weak direction of J stopped it).
#   fixed_point  FABRIK or CCD (no max_step) stopped where the light steps still gain: a fixed
#              point of its own update, not a minimum of ||e|| (dls or pinv goes on from there).
# (stalled, slow, singular, damped and fixed_point are settled after the loop: stop_rules.py.)
STATUSES = ("running", "converged", "stalled", "max_iter", "diverged", "slow", "singular",
            "damped", "fixed_point")
RUNNING, CONVERGED, STALLED, MAX_ITER, DIVERGED, SLOW, SINGULAR, DAMPED, FIXED_POINT = range(9)


class State(NamedTuple):
    """Where the loop is: i steps taken, theta, ||e|| and the size of the last step."""
    i: int
    theta: jnp.ndarray
    error: float
    step: float
    status: int


def start(theta0):
    """The state before the first pass (no error seen, no step taken yet)."""
    return State(i=0, theta=theta0, error=jnp.inf, step=jnp.inf, status=RUNNING)


def stop_rule(options, state, error):
    """Which stop fires at this pass, the first that holds in this order; RUNNING if none."""
    stalled = (state.i > 0) & (state.step < options.stall_tol)   # the last step was tiny
    return jnp.select(
        [~jnp.isfinite(error),                                    # diverged
         error < options.tol,                                     # converged
         stalled & still_progressing(state.error, error),         # slow: ||e|| still falls
         stalled,                                                 # stalled
         state.i >= options.max_iter],                            # max_iter
        [DIVERGED, CONVERGED, SLOW, STALLED, MAX_ITER], RUNNING)


def iterate(problem, method, options, state):
    """One pass of the loop: look at e, then stop or take one step."""
    e, J = problem.error_and_jacobian(state.theta)                # e = target - F(theta), J
    error = jnp.linalg.norm(e)
    status = stop_rule(options, state, error)                     # checked before any step
    delta = method.delta(problem, state.theta, clamp_error(e, options.clamp), J)
    delta = cap_step(delta, options.max_step)                     # Buss's safeguards
    theta = jnp.clip(state.theta + delta, *options.joint_limits)
    status = jnp.where((status == RUNNING) & ~jnp.all(jnp.isfinite(theta)), DIVERGED, status)
    moving = status == RUNNING                                    # a stopped loop keeps theta
    return State(state.i + moving, jnp.where(moving, theta, state.theta), error,
                 jnp.where(moving, step_size(options.stop_rule, J, delta), state.step), status)


def ik_loop(problem, method, options, theta0):
    """The whole loop, one Python iteration per pass (what the compiled engine runs too)."""
    state = start(theta0)
    while state.status == RUNNING:
        state = iterate(problem, method, options, state)
    return state
