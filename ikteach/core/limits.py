"""Buss's safeguards: clamp the error vector, cap the joint step."""
import jax.numpy as jnp


def clamp_error(e, d_max):
    """Clamp |e| to at most D_max: e <- D_max e / |e| when |e| > D_max (D_max = inf: no clamp)."""
    norm = jnp.linalg.norm(e)
    return jnp.where(norm > d_max, e * (d_max / jnp.where(norm > 0, norm, 1.0)), e)


def cap_step(delta_theta, max_step):
    """Scale delta_theta so that no joint turns more than max_step (radians) in one step."""
    largest = jnp.max(jnp.abs(delta_theta))
    return jnp.where(largest > max_step, delta_theta * (max_step / jnp.where(largest > 0, largest, 1.0)), delta_theta)
