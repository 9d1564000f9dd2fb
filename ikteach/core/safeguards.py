"""Buss's safeguards: clamp the error vector, cap the joint step."""
import jax.numpy as jnp


def clamp_error(e, d_max):
    """Clamp |e| to at most D_max: e <- D_max e / |e| when |e| > D_max (D_max = inf: no clamp).

    d_max may hold one D_max per end effector (Buss's tracking demo): e is then cut into that
    many equal parts, each clamped by itself.
    """
    parts = e.reshape(jnp.size(d_max), -1)
    norm = jnp.linalg.norm(parts, axis=1, keepdims=True)
    d_max = jnp.reshape(d_max, (-1, 1))
    scale = jnp.where(norm > d_max, d_max / jnp.where(norm > 0, norm, 1.0), 1.0)
    return (parts * scale).reshape(e.shape)


def cap_step(delta_theta, max_step):
    """Scale delta_theta so that no joint turns more than max_step (radians) in one step."""
    largest = jnp.max(jnp.abs(delta_theta))
    return jnp.where(largest > max_step, delta_theta * (max_step / jnp.where(largest > 0, largest, 1.0)), delta_theta)
