"""Jacobian transpose: step along the gradient of 1/2 ||e||^2 with Buss's optimal alpha."""
import jax.numpy as jnp

from ikteach.core._validate import as_number  # absolute: the self-check runs this file as a cell
from ikteach.core.method import JacobianMethod, method
from ikteach._runtime.jit import quick_jit  # absolute, as above


@quick_jit
def optimal_alpha(J, e):
    """alpha = <e, J J^T e> / <J J^T e, J J^T e>, the alpha minimising ||e - alpha J J^T e||.

    When J J^T e = 0 (e.g. e = 0, or e orthogonal to every column of J) every alpha
    is equally good; 0 is returned so the step is 0, never NaN.
    """
    v = J @ (J.T @ e)
    vv = jnp.dot(v, v)
    return jnp.where(vv > 0, jnp.dot(e, v) / jnp.where(vv > 0, vv, 1.0), 0.0)


@quick_jit
def jt_step(J, e):
    """Jacobian-transpose step: delta_theta = alpha J^T e, alpha from optimal_alpha."""
    J, e = jnp.asarray(J), jnp.asarray(e)
    return optimal_alpha(J, e) * (J.T @ e)


@method(data=("alpha",))
class JT(JacobianMethod):
    """The Jacobian transpose: delta_theta = alpha J^T e with Buss's optimal alpha, or with a
    fixed step length alpha > 0 when one is given (lecture 02 compares the two; alpha = 0
    would never move)."""
    alpha: float = None

    def __post_init__(self):
        if self.alpha is not None:
            object.__setattr__(self, "alpha", as_number(self.alpha, "alpha", minimum=0,
                                                           strict=True))

    def step(self, J, e):
        if self.alpha is None:
            return jt_step(J, e)
        return self.alpha * (J.T @ e)
