"""When to stop short of the target: the stall rules, and telling "stalled" from "slow".

A stall rule ends a solve when the steps have become too small to matter. Two rules:

  "joint_steps"  the lab report's rule: sum_i |delta_theta_i| < stall_tol.
                 The sum is in radians but the default stall_tol is STALL_FRACTION x the
                 total link length (a length), so the rule depends on the units of length:
                 scale arm and target by s and the JT/pinv/DLS steps (lambda scaled with them)
                 stay the same while the threshold grows with s.
  "motion"       the end effector's predicted motion ||J delta_theta|| < stall_tol, a length
                 compared with a length (default STALL_FRACTION x reach): the same decision at
                 every scale. The recommended rule.

A small step happens for two reasons: the target is out of reach (||e|| levels off at the
distance to the workspace), or the method converges slowly (||e|| still shrinks by a steady
fraction per step, e.g. the Jacobian transpose near a singular direction). When a rule fires,
the relative progress of the last step, (||e_prev|| - ||e||) / ||e_prev||, tells them apart:
above SLOW_PROGRESS the status is "slow" instead of "stalled".
"""
import jax
import jax.numpy as jnp

STOP_RULES = ("joint_steps", "motion")
DEFAULT_STOP_RULE = "joint_steps"
SLOW_PROGRESS = 1e-4  # "slow" when ||e|| still fell by more than this fraction in the last step


def rule_index(rule):
    """The rule's number (what the traced loop reads), or a ValueError naming stop_rule."""
    if rule not in STOP_RULES:
        raise ValueError(f"stop_rule: expected one of {list(STOP_RULES)}, got {rule!r:.80}")
    return STOP_RULES.index(rule)


def joint_steps(delta_theta):
    """The report's step size: sum_i |delta_theta_i| (radians)."""
    return jnp.sum(jnp.abs(delta_theta))


def motion(J, delta_theta):
    """The end effector's predicted motion ||J delta_theta|| (units of the error)."""
    return jnp.linalg.norm(J @ delta_theta)


def step_size(rule, jacobian_at_theta, delta_theta):
    """The size the stall rule compares with stall_tol (rule: a traced index into STOP_RULES).

    jacobian_at_theta() is only evaluated for the "motion" rule. Outside a trace (an eager
    solve with a numpy step function) the rule is a plain number: a Python branch, since an
    eager lax.cond on a fresh lambda compiles anew on every call.
    """
    if not isinstance(rule, jax.core.Tracer):
        return motion(jacobian_at_theta(), delta_theta) if int(rule) == 1 else joint_steps(delta_theta)
    return jax.lax.cond(rule == 1, lambda: motion(jacobian_at_theta(), delta_theta),
                        lambda: joint_steps(delta_theta))


def relative_progress(previous_error, error):
    """(||e_prev|| - ||e||) / ||e_prev||: the fraction of the error the last step removed."""
    return (previous_error - error) / jnp.where(previous_error > 0, previous_error, 1.0)


def still_progressing(previous_error, error):
    """True when the error still shrinks by a steady fraction: a slow solve, not a stall."""
    return relative_progress(previous_error, error) > SLOW_PROGRESS
