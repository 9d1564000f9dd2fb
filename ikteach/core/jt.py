"""Jacobian transpose: step along the gradient of 1/2 ||e||^2 with Buss's optimal alpha."""
import jax
import jax.numpy as jnp

from .method import JacobianMethod, method


@jax.jit
def optimal_alpha(J, e):
    """alpha = <e, J J^T e> / <J J^T e, J J^T e>, the alpha minimising ||e - alpha J J^T e||.

    When J J^T e = 0 (e.g. e = 0, or e orthogonal to every column of J) every alpha
    is equally good; 0 is returned so the step is 0, never NaN.
    """
    v = J @ (J.T @ e)
    vv = jnp.dot(v, v)
    return jnp.where(vv > 0, jnp.dot(e, v) / jnp.where(vv > 0, vv, 1.0), 0.0)


@jax.jit
def jt_step(J, e):
    """Jacobian-transpose step: delta_theta = alpha J^T e, alpha from optimal_alpha."""
    J, e = jnp.asarray(J), jnp.asarray(e)
    return optimal_alpha(J, e) * (J.T @ e)


@method(data=())
class JT(JacobianMethod):
    """The Jacobian transpose with Buss's optimal alpha (no parameters)."""

    def step(self, J, e):
        return jt_step(J, e)
