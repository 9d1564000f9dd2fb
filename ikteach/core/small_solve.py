"""Small linear systems in closed form: the m x m solve of DLS for m <= 3 without LU."""
import jax.numpy as jnp


def solve_small(A, b):
    """x = A^-1 b, by the closed-form inverse (adjugate / determinant) for 1 x 1, 2 x 2 and
    3 x 3 matrices, by LU (jnp.linalg.solve) for larger ones."""
    m = A.shape[0]
    if m == 1:
        return b / A[0, 0]
    if m == 2:
        det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
        return jnp.stack([A[1, 1] * b[0] - A[0, 1] * b[1], A[0, 0] * b[1] - A[1, 0] * b[0]]) / det
    if m == 3:
        adj = jnp.stack([jnp.cross(A[1], A[2]), jnp.cross(A[2], A[0]), jnp.cross(A[0], A[1])])
        return adj.T @ b / jnp.dot(A[0], adj[0])
    return jnp.linalg.solve(A, b)
