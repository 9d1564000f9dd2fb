"""Many targets at once: the solve loop under jax.vmap, compiled once with jax.jit."""
import dataclasses
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from .pinv import DEFAULT_RCOND
from .sdls import GAMMA_MAX
from .solve import DEFAULT_DAMPING, STATUSES, check_problem, resolve_method, run_loop


@dataclasses.dataclass(frozen=True)
class BatchResult:
    """One row per target: theta (B, n), status (B,) names, iterations (B,), error (B,)."""
    theta: np.ndarray
    status: np.ndarray
    iterations: np.ndarray
    error: np.ndarray

    def __len__(self):
        return len(self.status)

    def counts(self):
        """How many targets ended in each status."""
        return {s: int(np.sum(self.status == s)) for s in STATUSES[1:]}


@partial(jax.jit, static_argnames=("method", "task", "max_iter"))
def _run_batch(method, task, arm, targets, thetas0, settings, max_iter):
    one = lambda t, q: run_loop(method, task, arm, t, q, settings, max_iter, False)
    return jax.vmap(one)(targets, thetas0)


def solve_batch(arm, targets, theta0, method="dls", tol=1e-3, max_iter=1000,
                damping=DEFAULT_DAMPING, rcond=DEFAULT_RCOND, clamp=None, max_step=None,
                stall_tol=None, gamma_max=GAMMA_MAX, weights=None):
    """Solve for every row of targets (B, d); theta0 is one start (n,) or one per target (B, n).

    A spatial chain takes 4x4 pose targets too: targets (B, 4, 4), with weights as in ik.solve.
    Same loop and stop rules as ik.solve (no trace is kept); method must be a name or a
    step function written with jax.numpy.
    """
    method = resolve_method(method)
    task, targets, theta0, settings, max_iter = check_problem(
        arm, targets, theta0, tol=tol, max_iter=max_iter, damping=damping, rcond=rcond,
        clamp=clamp, max_step=max_step, stall_tol=stall_tol, gamma_max=gamma_max, batch=True,
        weights=weights)
    if theta0.ndim == 1:
        theta0 = jnp.broadcast_to(theta0, (targets.shape[0], theta0.shape[0]))
    state = _run_batch(method, task, arm, targets, theta0, settings, max_iter)
    return BatchResult(
        theta=np.asarray(state.theta),
        status=np.asarray(STATUSES, dtype=object)[np.asarray(state.status)],
        iterations=np.asarray(state.i),
        error=np.asarray(state.error),
    )
