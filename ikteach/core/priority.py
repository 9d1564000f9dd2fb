"""Task priorities: solve a secondary task only in the freedom the primary leaves (its null space).

    delta_theta = J1+ e1 + N1 (J2 N1)+ (e2 - J2 J1+ e1),    N1 = I - J1+ J1

The first term solves the primary task; the second moves only inside the null space of J1
(J1 N1 = 0), so it changes nothing the primary can see to first order. The inverses are
damped pseudoinverses (DLS-style, sigma / (sigma^2 + lambda^2)) so that nothing blows up
where J1 or J2 N1 is singular; the projector N1 is the exact one (from J1's SVD, with a
relative cut-off), so J1 delta_theta = J1 J1+ e1 holds for any damping.
"""
import jax
import jax.numpy as jnp

from ._validate import as_array, as_number
from .._runtime.jit import quick_jit

RANK_RCOND = 1e-10  # singular values below RANK_RCOND * sigma_max count as zero (the null space)


@quick_jit
def damped_pinv(A, damping, scale=None):
    """A's damped pseudoinverse V diag(sigma / (sigma^2 + lambda^2)) U^T = A^T (A A^T + lambda^2 I)^-1.

    lambda = 0 gives the Moore-Penrose pseudoinverse. Singular values below RANK_RCOND * scale
    (default scale: A's largest singular value) count as zero and are dropped.
    """
    U, sigma, Vt = jnp.linalg.svd(A, full_matrices=False)
    scale = jnp.max(sigma, initial=0.0) if scale is None else scale
    keep = sigma > RANK_RCOND * scale
    inv = jnp.where(keep, sigma / jnp.where(keep, sigma**2 + damping**2, 1.0), 0.0)
    return Vt.T @ (inv[:, None] * U.T)


@quick_jit
def null_projector(A):
    """N = I - A+ A: projects onto the null space of A (A N = 0), from A's SVD."""
    _, sigma, Vt = jnp.linalg.svd(A, full_matrices=True)
    n = A.shape[1]
    rank_sigma = jnp.zeros(n).at[: sigma.shape[0]].set(sigma)
    row_space = rank_sigma > RANK_RCOND * jnp.max(sigma, initial=0.0)
    V_row = Vt.T * row_space[None, :]
    return jnp.eye(n) - V_row @ V_row.T


def null_space_step(J_done, delta_done, J, e, damping):
    """The correction N (J N)+ (e - J delta_done) for a lower-priority task (J, e), where N
    projects onto the null space of J_done (the Jacobians of the tasks already served)."""
    N = null_projector(J_done)
    # rank of J N judged against J's own size: J N ~ 1e-16 when the null space is empty
    return N @ (damped_pinv(J @ N, damping, scale=jnp.linalg.norm(J)) @ (e - J @ delta_done))


def priority_step(J1, e1, J2, e2, damping):
    """Two-level step: delta = J1+ e1 + N1 (J2 N1)+ (e2 - J2 J1+ e1), N1 = I - J1+ J1.

    J1 (m1, n), e1 (m1,): the primary task; J2 (m2, n), e2 (m2,): the secondary task.
    J1+ and (J2 N1)+ are damped pseudoinverses with damping lambda >= 0 (lambda = 0: exact);
    N1 is the exact null-space projector of J1, so J1 delta = J1 J1+ e1 whatever the
    secondary task asks for.
    """
    J1, e1, J2, e2 = _check_levels(J1, e1, J2, e2, damping)
    return multilevel_step([(J1, e1), (J2, e2)], damping)


def _check_levels(J1, e1, J2, e2, damping):
    """Shapes always (they are known while tracing); values too when they are concrete."""
    traced = any(isinstance(x, jax.core.Tracer) for x in (J1, e1, J2, e2, damping))
    if not traced:
        J1, e1, J2, e2 = (as_array(x, name) for x, name in
                          ((J1, "J1"), (e1, "e1"), (J2, "J2"), (e2, "e2")))
        as_number(damping, "damping", minimum=0)
    for name, J in (("J1", J1), ("J2", J2)):
        if jnp.ndim(J) != 2:
            raise ValueError(f"{name}: expected a matrix (rows, joints), got shape {jnp.shape(J)}")
    if J2.shape[1] != J1.shape[1]:
        raise ValueError(f"J2: expected {J1.shape[1]} columns (one per joint, like J1), "
                         f"got shape {tuple(J2.shape)}")
    for name, e, J in (("e1", e1, J1), ("e2", e2, J2)):
        if jnp.shape(e) != (J.shape[0],):
            raise ValueError(f"{name}: expected shape ({J.shape[0]},) (one entry per row of "
                             f"J{name[1]}), got shape {tuple(jnp.shape(e))}")
    return tuple(jnp.asarray(x, dtype=float) for x in (J1, e1, J2, e2))


@quick_jit
def multilevel_step(levels, damping):
    """delta for levels [(J_1, e_1), (J_2, e_2), ...], level k solved in the null space of
    the stacked Jacobians of levels 1..k-1:  delta_k = delta_{k-1} + N_{<k} (J_k N_{<k})+ (e_k - J_k delta_{k-1})."""
    J_done, e_done = levels[0]
    delta = damped_pinv(J_done, damping) @ e_done
    for J, e in levels[1:]:
        delta = delta + null_space_step(J_done, delta, J, e, damping)
        J_done = jnp.vstack([J_done, J])
    return delta

