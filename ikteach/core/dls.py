"""Damped least squares: minimise ||J delta_theta - e||^2 + lambda^2 ||delta_theta||^2."""
import jax
import jax.numpy as jnp

from .small_solve import solve_small


@jax.jit
def dls_step(J, e, damping):
    """delta_theta = J^T (J J^T + lambda^2 I)^-1 e: an m x m solve (m = rows of J).

    Equal to dls_step_normal by (J^T J + lambda^2 I)^-1 J^T = J^T (J J^T + lambda^2 I)^-1,
    and cheaper when n >> m. solve_small: closed form for m <= 3, LU above.
    """
    J, e = jnp.asarray(J), jnp.asarray(e)
    m = J.shape[0]
    return J.T @ solve_small(J @ J.T + damping**2 * jnp.eye(m), e)


@jax.jit
def dls_step_normal(J, e, damping):
    """The normal equations (J^T J + lambda^2 I) delta_theta = J^T e: an n x n solve."""
    J, e = jnp.asarray(J), jnp.asarray(e)
    n = J.shape[1]
    return jnp.linalg.solve(J.T @ J + damping**2 * jnp.eye(n), J.T @ e)
