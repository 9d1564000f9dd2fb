"""Selectively damped least squares (Buss & Kim 2005): damp each singular direction by itself.

With J = sum_i sigma_i u_i v_i^T, the pseudoinverse step is sum_i (c_i / sigma_i) v_i,
c_i = u_i . e. SDLS bounds how far each term may turn the joints, by comparing how far
the end effectors are asked to move along u_i (n_hat_i; Buss & Kim's N_i) with how far they
would move if the joints turned as 1/sigma_i v_i asks (m_hat_i; their M_i):

  n_hat_i = sum_k ||u_i^(k)||                    (u_i^(k): effector k's rows of u_i)
  m_hat_i = (1/sigma_i) sum_l |[v_i]_l| sum_k ||J^(k)_l||   (J^(k)_l: effector k's rows of column l)
  gamma_i = min(1, n_hat_i / m_hat_i) gamma_max  (n_hat_i <= m_hat_i: the min is the ratio)
  Delta_i = ClampMaxAbs((c_i / sigma_i) v_i, gamma_i)
  delta_theta = ClampMaxAbs(sum_i Delta_i, gamma_max)

ClampMaxAbs(w, d) scales w down so that max_l |w_l| <= d (ik.cap_step). The paper uses
gamma_max = pi/4; so no joint ever turns by more than gamma_max in one step.

Buss's own demo code (Jacobian.cpp, CalcDeltaThetasSDLS) rescales softly instead, and that
is what soft=True does: each direction's term w is added as w gamma_i / (gamma_i + max|w|)
(always, not only when max|w| > gamma_i), and a sum with max|.| = c > gamma_max is scaled by
gamma_max / (gamma_max + c) (so its largest turn is below gamma_max, not equal to it).
"""
import functools

import jax
import jax.numpy as jnp
import numpy as np

from ._validate import as_number
from .method import JacobianMethod, method
from .safeguards import cap_step
from .._runtime.jit import quick_jit

GAMMA_MAX = np.pi / 4   # Buss & Kim 2005, section 4
# Singular values below NEAR_ZERO sigma_max are skipped. Buss's demo code skips those below
# 1e-10 absolute, for arms of unit size; relative to sigma_max (a length, like J) the same
# directions are skipped at every scale: an arm of 1e-11 gets its steps, as one of 1 does.
NEAR_ZERO = 1e-10


def kept(sigma):
    """The singular directions SDLS uses: sigma_i > NEAR_ZERO sigma_max (scale-free)."""
    return sigma > NEAR_ZERO * jnp.max(sigma, initial=0.0)


def block_norms(A, block):
    """Norms of the `block`-row pieces of every column of A (rows = effectors x block): (k, cols)."""
    k = A.shape[0] // block
    return jnp.linalg.norm(A.reshape(k, block, A.shape[1]), axis=1)


def sdls_gamma(U, sigma, Vt, J, gamma_max, block):
    """gamma_i = min(1, n_hat_i / m_hat_i) gamma_max for every singular direction i (module doc)."""
    n_hat = block_norms(U, block).sum(axis=0)
    column_size = block_norms(J, block).sum(axis=0)              # sum_k ||J^(k)_l||
    safe_sigma = jnp.where(kept(sigma), sigma, 1.0)
    m_hat = (jnp.abs(Vt) @ column_size) / safe_sigma
    ratio = jnp.where(m_hat > 0, n_hat / jnp.where(m_hat > 0, m_hat, 1.0), 1.0)
    return gamma_max * jnp.minimum(1.0, ratio)


def soft_rescale(w, gamma):
    """Buss's demo code: w gamma / (gamma + max_l |w_l|)."""
    return w * (gamma / (gamma + jnp.max(jnp.abs(w))))


@functools.partial(quick_jit, static_argnames=("block", "soft"))
def sdls_step(J, e, gamma_max=GAMMA_MAX, block=None, soft=False):
    """delta_theta = ClampMaxAbs(sum_i ClampMaxAbs((u_i.e / sigma_i) v_i, gamma_i), gamma_max).

    J has one block of `block` rows per end effector (default: all rows, one effector).
    soft=True: Buss's demo code's soft rescales in place of both ClampMaxAbs (module doc).
    """
    J, e = jnp.asarray(J), jnp.asarray(e)
    block = J.shape[0] if block is None else block
    U, sigma, Vt = jnp.linalg.svd(J, full_matrices=False)
    gamma = sdls_gamma(U, sigma, Vt, J, gamma_max, block)
    keep = kept(sigma)
    coeff = jnp.where(keep, (U.T @ e) / jnp.where(keep, sigma, 1.0), 0.0)
    if soft:
        total = jax.vmap(soft_rescale)(coeff[:, None] * Vt, gamma).sum(axis=0)
        largest = jnp.max(jnp.abs(total))
        return jnp.where(largest > gamma_max, total * (gamma_max / (gamma_max + largest)), total)
    terms = jax.vmap(cap_step)(coeff[:, None] * Vt, gamma)        # Delta_i, one row per direction
    return cap_step(terms.sum(axis=0), gamma_max)


@method(data=("gamma_max",))
class SDLS(JacobianMethod):
    """SDLS with largest joint turn gamma_max per step; J's blocks are the end effectors."""
    gamma_max: float = GAMMA_MAX

    def __post_init__(self):
        object.__setattr__(self, "gamma_max",
                           as_number(self.gamma_max, "gamma_max", minimum=0, strict=True))

    def delta(self, problem, theta, e, J, free=None):
        return sdls_step(J, e, self.gamma_max, problem.rows_per_effector(J.shape[0]))

    def step(self, J, e):
        return sdls_step(J, e, self.gamma_max)
