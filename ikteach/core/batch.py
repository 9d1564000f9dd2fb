"""ik.solve_batch: many targets at once, each through the same loop as ik.solve.

The engine (ikteach/_runtime/engine.py) runs loop.iterate under jax.vmap on a queue of
targets; a handful of targets (SMALL_BATCH or fewer) run one by one through ik.solve's
compiled loop, whose program a class has usually compiled already.
"""
import dataclasses

import numpy as np

from ._pytree import replace
from .loop import STATUSES, iterate, start
from .methods import require_traceable
from .solve import as_options, explain_stalls, prepare, status_counts
from .._runtime import engine

SMALL_BATCH = 8  # up to this many targets: ik.solve's loop, target by target


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
        return status_counts(self.status)


def iterate_row(args, target, state):
    """loop.iterate for one row of the batch: the problem with this row's target."""
    problem, method, options = args
    return iterate(replace(problem, target=target), method, options, state)


def solve_batch(arm, targets, theta0, method="dls", options=None, *, damping=None, rcond=None,
                gamma_max=None, **option_values):
    """Solve for every row of targets (B, d), or (B, 4, 4) poses; theta0 is one start (n,) or
    one per target (B, n). Method, parameters and options as in ik.solve (no trace is kept);
    a step function must be written with jax.numpy.

    Each row runs ik.solve's loop: the same status and iterations as ik.solve from the same
    start, theta within 1e-12 (the vectorised arithmetic may round differently in the last
    bits; a chaotic run, e.g. the Jacobian transpose to max_iter at a singular pose, can
    amplify that: tests/test_batch.py shows such a case).
    """
    options = as_options(options, option_values)
    problem, method, options, theta0, targets = prepare(
        arm, targets, theta0, method, options,
        {"damping": damping, "rcond": rcond, "gamma_max": gamma_max}, rows="targets")
    count, n = targets.shape[0], arm.n_joints
    require_traceable(method, problem, theta0.reshape(-1, n)[0], "ik.solve_batch")
    starts = np.broadcast_to(theta0, (count, n))
    args = (problem, method, options)
    if count <= SMALL_BATCH:
        states = [engine.run_traced(iterate, (replace(problem, target=targets[k]), method,
                                              options), start(starts[k]))[0]
                  for k in range(count)]
        theta, status = np.stack([s.theta for s in states]), np.array([s.status for s in states])
        iterations, error = np.array([s.i for s in states]), np.array([s.error for s in states])
    else:
        state = engine.run_queue(iterate_row, start, args, targets, np.ascontiguousarray(starts))
        theta, status, iterations, error = state.theta, state.status, state.i, state.error
    status = explain_stalls(problem, method, options, targets, theta, status)
    return BatchResult(theta=np.asarray(theta), status=np.asarray(STATUSES, dtype=object)[status],
                       iterations=np.asarray(iterations), error=np.asarray(error))
