"""Joint limits lower_j <= theta_j <= upper_j, kept after every step of the solve loop.

Two ways to respect them (ik.solve(..., joint_limits=(lower, upper), limit_mode=...)):

"clamp"          take the method's step, then clip theta into the limits. Cheap and works
                 for every method, but the motion a saturated joint was meant to make is
                 simply lost; the other joints do not know they must make up for it.
"clamping_loop"  (Baerlocher & Boulic) take the step; every joint it would push past a
                 limit is stopped exactly at that limit and its column removed from J; the
                 rest of the error, e - J delta_fixed, is solved again with the remaining
                 joints. Repeat until no free joint overshoots (at most n passes).
                 Needs a Jacobian method: jt, pinv, dls, sdls, a step function, priorities.

The limits travel in the loop's Options (traced), so new limits do not recompile.
"""
import jax
import jax.numpy as jnp
import numpy as np

from .method import method
from .safeguards import cap_step


def within(theta, lower, upper):
    """theta clipped into [lower, upper], joint by joint."""
    return jnp.clip(theta, lower, upper)


def overshoots(theta, delta, lower, upper):
    """Which joints theta + delta pushes past a limit."""
    new = theta + delta
    return (new > upper) | (new < lower)


def clamping_loop(solve_free, J, e, theta, lower, upper, max_step):
    """The limit-aware step: delta from solve_free(J_free, e_rest) with saturated joints removed.

    solve_free(J, e, free) -> delta is the method's step for a Jacobian J (its pinned columns
    zeroed) and error e; free marks the joints it may move. A joint that
    overshoots is pinned: delta_j = limit_j - theta_j, its column zeroed, and the rest of the
    error e - J delta_pinned is solved again by the free joints.
    """
    n = theta.shape[0]
    first = cap_step(solve_free(J, e, jnp.ones(n, bool)), max_step)

    def pass_(carry):
        delta, free, pinned = carry
        hit = free & overshoots(theta, delta, lower, upper)
        pinned = jnp.where(hit, within(theta + delta, lower, upper) - theta, pinned)
        free = free & ~hit
        rest = solve_free(J * free[None, :], e - J @ pinned, free)
        return cap_step(jnp.where(free, rest, pinned), max_step), free, pinned

    def more(carry):
        delta, free, _ = carry
        return jnp.any(free & overshoots(theta, delta, lower, upper))

    delta, _, _ = while_loop(more, pass_, (first, jnp.ones(n, bool), jnp.zeros(n)))
    return within(theta + delta, lower, upper) - theta


def while_loop(cond, body, carry):
    """lax.while_loop when traced (jit, vmap); a Python loop for steps JAX cannot trace."""
    if isinstance(carry[0], jax.core.Tracer):
        return jax.lax.while_loop(cond, body, carry)
    while cond(carry):
        carry = body(carry)
    return carry


@method(data=("inner", "lower", "upper", "max_step"))
class ClampingLoop:
    """A Jacobian method whose steps re-solve with the joints that hit a limit pinned."""
    inner: object
    lower: object
    upper: object
    max_step: float
    uses_jacobian = True

    @property
    def is_jax(self):
        return self.inner.is_jax

    def delta(self, problem, theta, e, J, free=None):
        def solve_free(J_free, e_rest, free):
            return self.inner.delta(problem, theta, e_rest, J_free, free)
        return clamping_loop(solve_free, J, e, theta, self.lower, self.upper, self.max_step)

    def resolved(self, length_scale):
        return self


def with_limits(method, options):
    """The solve's method with joint limits (options resolved): the clamping loop for a
    Jacobian method unless limit_mode="clamp"; with "clamp" (or CCD, FABRIK) the loop's own
    clip into the limits after each step is all there is. A start outside the limits is moved
    onto them by the caller (within)."""
    if options.joint_limits is None or not np.any(np.isfinite(np.concatenate(options.joint_limits))):
        return method
    mode = options.limit_mode
    if mode is None:
        mode = "clamping_loop" if method.uses_jacobian else "clamp"
    if mode == "clamp":
        return method
    if not method.uses_jacobian:
        raise ValueError("limit_mode: 'clamping_loop' re-solves with J, so it needs a Jacobian "
                         "method (jt, pinv, dls, sdls or a step function); use 'clamp' here")
    return ClampingLoop(method, *options.joint_limits, options.max_step)
