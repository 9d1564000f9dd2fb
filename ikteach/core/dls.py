"""Damped least squares: minimise ||J delta_theta - e||^2 + lambda^2 ||delta_theta||^2."""
import jax.numpy as jnp

from ._validate import as_number
from .method import JacobianMethod, method, replace
from .._runtime.jit import quick_jit

DAMPING_PER_LENGTH = 6  # default lambda = L / 6 (0.5 for three unit links; L: the arm's size)


@quick_jit
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


@quick_jit
def dls_step_small(J, e, damping):
    """dls_step for J with m <= 3 rows, the m x m inverse in closed form (Cramer's rule):

        B^-1 = adj(B) / det(B),   B = J J^T + lambda^2 I   (B_rc: row r, column c; B_r: row r);
        m = 2:  adj(B) = [[B_22, -B_12], [-B_21, B_11]],   det(B) = B_11 B_22 - B_12 B_21;
        m = 3:  adj(B) has rows B_2 x B_3, B_3 x B_1, B_1 x B_2 (B symmetric), det(B) = B_1 . (B_2 x B_3).

    The same step as dls_step to rounding (lecture 04 checks it); benchmarks/small_solves.py
    times it against dls_step's LU solve. (Arrays index from 0: B[0, 0] is B_11.)
    """
    J, e = jnp.asarray(J), jnp.asarray(e)
    m = J.shape[0]
    B = J @ J.T + damping**2 * jnp.eye(m)
    if m == 1:
        return J.T @ (e / B[0, 0])
    if m == 2:
        adj = jnp.array([[B[1, 1], -B[0, 1]], [-B[1, 0], B[0, 0]]])
        return J.T @ (adj @ e) / (B[0, 0] * B[1, 1] - B[0, 1] * B[1, 0])
    adj = jnp.stack([jnp.cross(B[1], B[2]), jnp.cross(B[2], B[0]), jnp.cross(B[0], B[1])])
    return J.T @ (adj @ e) / jnp.dot(B[0], adj[0])


@quick_jit
def dls_step_normal(J, e, damping):
    """The normal equations (J^T J + lambda^2 I) delta_theta = J^T e: an n x n solve."""
    J, e = jnp.asarray(J), jnp.asarray(e)
    n = J.shape[1]
    return jnp.linalg.solve(J.T @ J + damping**2 * jnp.eye(n), J.T @ e)


def damped_step(J, e, damping):
    """The DLS step: dls_step_small for m <= 3 rows (points in the plane or in space: the
    small inverse in closed form), else dls_step."""
    if J.shape[0] <= 3:
        return dls_step_small(J, e, damping)
    return dls_step(J, e, damping)


@method(data=("damping",))
class DLS(JacobianMethod):
    """Damped least squares with damping lambda (a length: default L / 6)."""
    damping: float = None

    def __post_init__(self):
        if self.damping is not None:
            object.__setattr__(self, "damping", as_number(self.damping, "damping", minimum=0))

    def step(self, J, e):
        return damped_step(J, e, self.damping)

    def resolved(self, length_scale):
        if self.damping is not None:
            return self
        return replace(self, damping=length_scale / DAMPING_PER_LENGTH)
