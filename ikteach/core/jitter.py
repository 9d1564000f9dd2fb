"""Jitter: how much the joint velocities change from one step to the next.

One definition for the whole course (notebooks 04, 07, 08 and benchmarks/compare_trees.py):
the jitter of step k is the 1-norm of the joints' second difference,

    j_k = sum_i |theta_i(k+1) - 2 theta_i(k) + theta_i(k-1)|    (radians; 0 for steady motion),

and the jitter of a run is the mean of j_k over its steps.
"""
import numpy as np


def jitter_per_step(theta):
    """j_k for a sequence of joint vectors theta (T, n): an array of T - 2 values."""
    theta = np.asarray(theta, dtype=float)
    if theta.ndim != 2:
        raise ValueError(f"theta: expected one joint vector per row (T, n), got shape {theta.shape}")
    return np.abs(np.diff(theta, n=2, axis=0)).sum(axis=1)


def jitter(theta):
    """The mean of j_k over the run (0 when there are fewer than 3 rows)."""
    steps = jitter_per_step(theta)
    return float(steps.mean()) if steps.size else 0.0
