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

The limits travel in the loop's Settings (traced), so new limits do not recompile.
"""
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from ._validate import numeric
from .limits import cap_step, clamp_error
from .sdls import SDLSMethod, sdls_step

LIMIT_MODES = ("clamp", "clamping_loop")


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


def jacobian_step(method, task, theta, settings):
    """The method's step as a function (J, e, free) -> delta, or None when it does not use J."""
    if hasattr(method, "jacobian_step"):  # priorities
        return method.jacobian_step(task, theta, settings)
    if isinstance(method, SDLSMethod):
        block = getattr(task, "block_size", None)
        return lambda J, e, free: sdls_step(J, e, settings.gamma_max, block or J.shape[0])
    if hasattr(method, "step"):  # jt, pinv, dls, a user's step function
        return lambda J, e, free: method.step(J, e, settings)
    return None


@dataclasses.dataclass(frozen=True)
class LimitedMethod:
    """A solve method whose steps keep every joint within settings.lower..settings.upper."""
    inner: object
    mode: str

    def delta(self, task, arm, target, theta, e, settings):
        if self.mode == "clamp":
            delta = cap_step(self.inner.delta(task, arm, target, theta, e, settings), settings.max_step)
            return within(theta + delta, settings.lower, settings.upper) - theta
        J = task.jacobian(arm, theta)
        solve_free = jacobian_step(self.inner, task, theta, settings)
        return clamping_loop(solve_free, J, clamp_error(e, settings.clamp), theta,
                             settings.lower, settings.upper, settings.max_step)


def check_limits(joint_limits, n):
    """(lower, upper) as two float arrays of shape (n,); a number applies to every joint."""
    try:
        lower, upper = joint_limits
    except (TypeError, ValueError):
        raise ValueError(f"joint_limits: expected a pair (lower, upper) of per-joint arrays, "
                         f"got {joint_limits!r:.80}") from None
    out = []
    for name, bound, bad in (("lower", lower, np.inf), ("upper", upper, -np.inf)):
        try:
            arr = np.broadcast_to(numeric(bound, "joint_limits"), (n,)).copy()
        except ValueError:
            raise ValueError(f"joint_limits: expected {name} as a number or shape ({n},) "
                             f"(one per joint), got {bound!r:.80}") from None
        if np.any(np.isnan(arr)) or np.any(arr == bad):
            raise ValueError(f"joint_limits: {name} must be numbers (or {-bad} for no limit), "
                             f"got {arr.tolist()}")
        out.append(arr)
    if np.any(out[0] > out[1]):
        j = int(np.argmax(out[0] > out[1]))
        raise ValueError(f"joint_limits: expected lower <= upper, got lower[{j}] = {out[0][j]} "
                         f"> upper[{j}] = {out[1][j]}")
    return out[0], out[1]


def with_limits(method, settings, theta0, joint_limits, limit_mode, n):
    """The solve's method, settings and start with joint limits on (unchanged without them).

    A start outside the limits is first moved onto them, so no result can break them.
    """
    if limit_mode not in (None,) + LIMIT_MODES:
        raise ValueError(f"limit_mode: expected one of {LIMIT_MODES}, got {limit_mode!r:.80}")
    if joint_limits is None:
        if limit_mode is not None:
            raise ValueError(f"limit_mode: {limit_mode!r} says how to keep joint limits, so it "
                             f"needs joint_limits=(lower, upper)")
        return method, settings, theta0
    lower, upper = check_limits(joint_limits, n)
    has_jacobian = jacobian_step(method, None, None, settings) is not None
    if limit_mode is None:
        limit_mode = "clamping_loop" if has_jacobian else "clamp"
    if limit_mode == "clamping_loop" and not has_jacobian:
        raise ValueError("limit_mode: 'clamping_loop' re-solves with J, so it needs a Jacobian "
                         "method (jt, pinv, dls, sdls or a step function); use 'clamp' here")
    settings = settings._replace(lower=jnp.asarray(lower), upper=jnp.asarray(upper))
    return LimitedMethod(method, limit_mode), settings, within(jnp.asarray(theta0), lower, upper)
