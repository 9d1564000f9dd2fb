"""Does DLS settle on an out-of-reach target? The stretched pose as a fixed point.

Out of reach, d beyond the reach of a planar chain, DLS's fixed point is the arm stretched
toward the target: there every column of J is tangential, e = d r (r the radial unit vector)
is orthogonal to J's range, so J^T e = 0 and the step is 0. Near it, for a small joint
deviation delta, the DLS step is linear in delta:

    delta <- M delta,   M = (J^T J + lambda^2 I)^-1 (lambda^2 I - d C),

where C_ij = sum of the lengths of links k >= max(i, j) (-C is the Hessian of r^T F, the tip's
reach along r, at the stretched pose; the Hessian of the tip's distance from the base is
J^T J / L - C, L the reach: lecture 05). DLS settles (the step shrinks, the stall rule fires:
"stalled") when the spectral radius of M is below 1; otherwise the stretched pose repels it and
it runs to max_iter, swinging about that pose when lambda is just below the threshold or
wandering far from it, even folding up, when lambda is small (lecture 04). This linear model
covers only the neighbourhood of the stretched pose. A larger lambda settles; a larger d needs
a larger lambda.
Buss's clamp limits the error the step sees to D_max, so d is replaced by min(d, D_max).
"""
import numpy as np

from .chain import Chain


def _lengths(arm):
    if not isinstance(arm, Chain) or arm.dim != 2:
        raise ValueError("arm: expected a planar chain from ik.planar_chain")
    return np.linalg.norm(np.asarray(arm.offsets), axis=1)


def stretched_matrices(arm):
    """(J^T J, C) at the stretched pose, in the frame of the stretch direction."""
    tail = np.cumsum(_lengths(arm)[::-1])[::-1]  # tail[i] = sum of the lengths of links k >= i
    n = len(tail)
    C = tail[np.maximum.outer(np.arange(n), np.arange(n))]
    return np.outer(tail, tail), C


def settle_matrix(arm, distance, damping, clamp=None):
    """M, the DLS step's map delta <- M delta near the stretched pose (joint angles).

    Unclamped, J^T e = -(J^T J + d C) delta to first order. Buss's clamp scales e by D / ||e||,
    D = min(d, D_max), and J^T e is already first order, so the step sees D / d of it:
        M = (J^T J + lambda^2 I)^-1 ((1 - D/d) J^T J + lambda^2 I - D C),
    which is (J^T J + lambda^2 I)^-1 (lambda^2 I - d C) when the clamp does not act (D = d)."""
    D = distance if clamp is None else min(distance, clamp)
    JtJ, C = stretched_matrices(arm)
    eye = np.eye(len(C))
    return np.linalg.solve(JtJ + damping**2 * eye, (1 - D / distance) * JtJ + damping**2 * eye - D * C)


def settle_factor(arm, distance, damping, clamp=None):
    """Spectral radius of M (settle_matrix): below 1, DLS settles stretched; above 1, it does not."""
    return float(np.abs(np.linalg.eigvals(settle_matrix(arm, distance, damping, clamp))).max())


def smallest_settling_damping(arm, distance, clamp=None):
    """The lambda above which DLS settles at this distance beyond the reach (bisection)."""
    lo, hi = 0.0, 1.0
    while settle_factor(arm, distance, hi, clamp) >= 1:
        hi *= 2
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if settle_factor(arm, distance, mid, clamp) < 1 else (mid, hi)
    return hi
