"""Damped least squares: minimise ||J delta_theta - e||^2 + lambda^2 ||delta_theta||^2."""
import jax
import jax.numpy as jnp

from ._validate import as_number
from .method import JacobianMethod, method, replace

DAMPING_PER_LENGTH = 6  # default lambda = L / 6 (0.5 for three unit links; L: the arm's size)


@jax.jit
def dls_step(J, e, damping):
    """delta_theta = J^T (J J^T + lambda^2 I)^-1 e: an m x m solve (m = rows of J).

    Equal to dls_step_normal by (J^T J + lambda^2 I)^-1 J^T = J^T (J J^T + lambda^2 I)^-1,
    and cheaper when n >> m. With lambda = 0 at a singular J the system is singular and the
    step is not finite (the solve loop then stops "diverged").
    """
    J, e = jnp.asarray(J), jnp.asarray(e)
    m = J.shape[0]
    return J.T @ jnp.linalg.solve(J @ J.T + damping**2 * jnp.eye(m), e)


@jax.jit
def dls_step_normal(J, e, damping):
    """The normal equations (J^T J + lambda^2 I) delta_theta = J^T e: an n x n solve."""
    J, e = jnp.asarray(J), jnp.asarray(e)
    n = J.shape[1]
    return jnp.linalg.solve(J.T @ J + damping**2 * jnp.eye(n), J.T @ e)


@method(data=("damping",))
class DLS(JacobianMethod):
    """Damped least squares with damping lambda (a length: default L / 6)."""
    damping: float = None

    def __post_init__(self):
        if self.damping is not None:
            object.__setattr__(self, "damping", as_number(self.damping, "damping", minimum=0))

    def step(self, J, e):
        return dls_step(J, e, self.damping)

    def resolved(self, length_scale):
        if self.damping is not None:
            return self
        return replace(self, damping=length_scale / DAMPING_PER_LENGTH)
