"""Damped least squares: minimise ||J delta_theta - e||^2 + lambda^2 ||delta_theta||^2."""
import jax
import jax.numpy as jnp

from .small_solve import solve_small

WELL_POSED = 1e-10  # det(A) / prod(diag A) above this: the m x m solve is far above rounding
FLOOR = 1e-6        # lambda^2 below FLOOR * trace(J J^T) / m on an ill-posed A: raised by that


def well_posed(A):
    """Is det(A) clearly above rounding? For A = J J^T + lambda^2 I (symmetric, positive
    semidefinite) det(A) <= prod(diag A), with equality when the rows of J are orthogonal;
    the ratio falls to rounding (about 1e-16) when A is singular to working precision."""
    m = A.shape[0]
    diag = jnp.diagonal(A)
    det = solve_small_det(A) if m <= 3 else jnp.linalg.det(A)
    return det > WELL_POSED * jnp.prod(diag)


def solve_small_det(A):
    """det(A) for m <= 3, the same products as solve_small's closed form."""
    m = A.shape[0]
    if m == 1:
        return A[0, 0]
    if m == 2:
        return A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    return jnp.dot(A[0], jnp.cross(A[1], A[2]))


@jax.jit
def dls_step(J, e, damping):
    """delta_theta = J^T (J J^T + lambda^2 I)^-1 e: an m x m solve (m = rows of J).

    Equal to dls_step_normal by (J^T J + lambda^2 I)^-1 J^T = J^T (J J^T + lambda^2 I)^-1,
    and cheaper when n >> m. solve_small: closed form for m <= 3, LU above.
    With lambda = 0 (or tiny) at a singular J the system is singular: then, and only then
    (lambda^2 < FLOOR trace(J J^T) / m and det(A) lost in rounding), lambda^2 is raised by
    FLOOR trace(J J^T) / m, so the step stays finite; every other step is the plain formula.
    """
    J, e = jnp.asarray(J), jnp.asarray(e)
    m = J.shape[0]
    G = J @ J.T
    A = G + damping**2 * jnp.eye(m)
    floor = FLOOR * jnp.trace(G) / m
    A = jnp.where((damping**2 < floor) & ~well_posed(A), A + floor * jnp.eye(m), A)
    return J.T @ solve_small(A, e)


@jax.jit
def dls_step_normal(J, e, damping):
    """The normal equations (J^T J + lambda^2 I) delta_theta = J^T e: an n x n solve."""
    J, e = jnp.asarray(J), jnp.asarray(e)
    n = J.shape[1]
    return jnp.linalg.solve(J.T @ J + damping**2 * jnp.eye(n), J.T @ e)
