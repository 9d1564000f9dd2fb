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
    step is not finite (the solve loop then stops "diverged"). ik.DLS takes dls_step_small for
    m <= 3 rows.
    """
    J, e = jnp.asarray(J), jnp.asarray(e)
    m = J.shape[0]
    return J.T @ jnp.linalg.solve(J @ J.T + damping**2 * jnp.eye(m), e)


@jax.jit
def dls_step_small(J, e, damping):
    """dls_step for J with m <= 3 rows, the m x m inverse in closed form (Cramer's rule):

        A^-1 = adj(A) / det(A),   A = J J^T + lambda^2 I;
        m = 2:  adj(A) = [[A_11, -A_01], [-A_10, A_00]],   det(A) = A_00 A_11 - A_01 A_10;
        m = 3:  adj(A) has rows A_1 x A_2, A_2 x A_0, A_0 x A_1 (A symmetric), det(A) = A_0 . (A_1 x A_2).

    The same step as dls_step to rounding (lecture 04 checks it); a batch of targets solves
    these small systems about twice as fast as LU (the 256 x 256 sweep: 0.52 s against 1.02 s).
    """
    J, e = jnp.asarray(J), jnp.asarray(e)
    m = J.shape[0]
    A = J @ J.T + damping**2 * jnp.eye(m)
    if m == 1:
        return J.T @ (e / A[0, 0])
    if m == 2:
        adj = jnp.array([[A[1, 1], -A[0, 1]], [-A[1, 0], A[0, 0]]])
        return J.T @ (adj @ e) / (A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0])
    adj = jnp.stack([jnp.cross(A[1], A[2]), jnp.cross(A[2], A[0]), jnp.cross(A[0], A[1])])
    return J.T @ (adj @ e) / jnp.dot(A[0], adj[0])


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
        if J.shape[0] <= 3:  # points in the plane or in space: the small inverse in closed form
            return dls_step_small(J, e, self.damping)
        return dls_step(J, e, self.damping)

    def resolved(self, length_scale):
        if self.damping is not None:
            return self
        return replace(self, damping=length_scale / DAMPING_PER_LENGTH)
