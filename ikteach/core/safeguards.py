"""Buss's safeguards: clamp the error vector, cap the joint step."""
import jax.numpy as jnp


def clamp_error(e, d_max, rows=None):
    """Clamp |e| to at most D_max: e <- D_max e / |e| when |e| > D_max (D_max = inf: no clamp).

    With rows (the rows per end effector of a tree), each effector's part of e is clamped by
    itself, as Buss does; d_max may then hold one D_max per effector.
    """
    rows = e.shape[0] if rows is None else rows
    parts = e.reshape(-1, rows)
    norm = jnp.linalg.norm(parts, axis=1, keepdims=True)
    d_max = jnp.reshape(d_max, (-1, 1))
    scale = jnp.where(norm > d_max, d_max / jnp.where(norm > 0, norm, 1.0), 1.0)
    return (parts * scale).reshape(e.shape)


def cap_step(delta_theta, max_step):
    """Scale delta_theta so that no joint turns more than max_step (radians) in one step."""
    largest = jnp.max(jnp.abs(delta_theta))
    return jnp.where(largest > max_step, delta_theta * (max_step / jnp.where(largest > 0, largest, 1.0)), delta_theta)
