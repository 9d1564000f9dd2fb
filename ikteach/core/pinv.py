"""Pseudoinverse step by the SVD, with a cut-off for small singular values."""
import jax.numpy as jnp

from ._validate import as_number
from .method import JacobianMethod, method
from .._runtime.jit import quick_jit

DEFAULT_RCOND = 1e-6


@quick_jit
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


@quick_jit
def pinv_two_rows(J, e, rcond=DEFAULT_RCOND):
    """pinv_step for a 2 x n Jacobian (planar position targets) without an SVD call.

    One plane rotation R_psi makes the rows of S = R_psi J orthogonal (R_psi J J^T R_psi^T
    diagonal): then row i of S is sigma_i v_i^T (in some order), the singular values are the
    row lengths and J^+ e = sum_i (R_psi e)_i / sigma_i^2 (row i of S), with pinv_step's cut-off.
    tan(psi) is the root of tan^2 + 2 zeta tan - 1 = 0 of magnitude <= 1, with
    zeta = ([JJ^T]_22 - [JJ^T]_11) / (2 [JJ^T]_12) (lecture 03 derives it and checks it against
    pinv_step; benchmarks/small_solves.py times it against the SVD).
    """
    J, e = jnp.asarray(J), jnp.asarray(e)
    JJt = J @ J.T
    zeta = (JJt[1, 1] - JJt[0, 0]) / (2.0 * jnp.where(JJt[0, 1] == 0, 1.0, JJt[0, 1]))
    tan_psi = jnp.where(zeta >= 0, 1.0, -1.0) / (jnp.abs(zeta) + jnp.sqrt(1.0 + zeta * zeta))
    tan_psi = jnp.where(JJt[0, 1] == 0, 0.0, tan_psi)  # rows already orthogonal
    cos = 1.0 / jnp.sqrt(1.0 + tan_psi * tan_psi)
    sin = cos * tan_psi
    R_psi = jnp.stack([jnp.stack([cos, -sin]), jnp.stack([sin, cos])])
    S = R_psi @ J                                      # rows sigma_i v_i^T
    sigma = jnp.sqrt(jnp.diagonal(S @ S.T))
    keep = (sigma >= rcond * jnp.max(sigma)) & (sigma > 0)
    weight = jnp.where(keep, (R_psi @ e) / jnp.where(keep, sigma * sigma, 1.0), 0.0)
    return S.T @ weight


@method(data=("rcond",))
class Pinv(JacobianMethod):
    """The pseudoinverse step J^+ e with relative cut-off rcond: the SVD (pinv_step), or for a
    planar position target (two rows) the same J^+ e by one rotation (pinv_two_rows)."""
    rcond: float = DEFAULT_RCOND

    def __post_init__(self):
        rcond = as_number(self.rcond, "rcond", minimum=0)
        if rcond >= 1:
            raise ValueError(f"rcond: expected a relative cut-off 0 <= rcond < 1 (singular values "
                             f"below rcond sigma_max are dropped; from 1 on every step is 0), "
                             f"got {rcond:g}")
        object.__setattr__(self, "rcond", rcond)

    def step(self, J, e):
        if J.shape[0] == 2:
            return pinv_two_rows(J, e, self.rcond)
        return pinv_step(J, e, self.rcond)
