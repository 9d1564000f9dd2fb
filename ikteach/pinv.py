"""Pseudoinverse step by the SVD, with a cut-off for small singular values."""
import jax
import jax.numpy as jnp

DEFAULT_RCOND = 1e-6


@jax.jit
def pinv_step(J, e, rcond=DEFAULT_RCOND):
    """delta_theta = J^+ e = sum_i (u_i . e / sigma_i) v_i over sigma_i >= rcond * sigma_max.

    J = U diag(sigma) V^T; 1/sigma_i is dropped (set to 0) below the cut-off.
    This is the minimum-norm least-squares solution of J delta_theta = e.
    """
    J, e = jnp.asarray(J), jnp.asarray(e)
    U, sigma, Vt = jnp.linalg.svd(J, full_matrices=False)
    keep = sigma >= rcond * sigma[0]
    inv_sigma = jnp.where(keep & (sigma > 0), 1.0 / jnp.where(keep & (sigma > 0), sigma, 1.0), 0.0)
    return Vt.T @ (inv_sigma * (U.T @ e))
