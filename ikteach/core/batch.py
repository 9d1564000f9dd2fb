"""Many targets at once: the solve loop under jax.vmap, compiled once with jax.jit.

Targets differ in how many iterations they need. A vmapped while-loop would keep every
lane busy until the slowest target is done, so instead a fixed number of slots run side
by side and a slot whose target has finished takes the next target from the queue:
the work is the sum of the iterations, not the batch size times the largest count.
Slots are refilled every STEPS_PER_REFILL steps; a slot that finishes in between idles.

With several devices (one CPU device per core, when ik.notebook.setup() asked for them:
ikteach/_runtime/devices.py) a large batch is
split into equal shares, one per device, each running its own queue: every core works, and
each target still gets the same arithmetic (the same iterates to the last bit).

A handful of targets (SMALL_BATCH or fewer) run one by one through ik.solve's compiled loop
(a batch of one, the same arithmetic again): that program compiles in about 2/3 of the
queue's time, and a class waits for the compile, not for five solves.
"""
import dataclasses
import functools
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from .pinv import DEFAULT_RCOND
from .sdls import GAMMA_MAX
from .methods import require_traceable
from .solve import (RUNNING, STATUSES, _run_jit, advance, check_problem, explain_stalls,
                    initial_state, resolve_method, run_chunks, status_counts, with_extras)
from .stop_rules import DEFAULT_STOP_RULE
from .._runtime import jit as runtime_jit

SLOTS = 1024  # targets in flight at once (per device)
SPLIT_FROM = 512  # targets per device below which a batch stays on one device
STEPS_PER_REFILL = 4  # loop steps between refills (a refill costs more than a step)
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


def _select(mask, a, b):
    """Per slot: a where mask, else b (for every field of a state)."""
    return jax.tree_util.tree_map(
        lambda x, y: jnp.where(mask.reshape(mask.shape + (1,) * (x.ndim - 1)), x, y), a, b)


def _queue(method, task, arm, targets, thetas0, settings, max_iter, slots):
    """Solve every target; `slots` of them in flight, refilled from the queue as they finish."""
    count = targets.shape[0]
    step = jax.vmap(lambda t, s: advance(method, task, arm, t, settings, max_iter, s))
    start = jax.vmap(lambda q: initial_state(q, False))

    def load(index):  # fresh states for these targets; an index past the end marks an idle slot
        state = start(thetas0[jnp.minimum(index, count - 1)])
        return state._replace(status=jnp.where(index < count, state.status, -1))

    def body(carry):
        index, state, out, queued = carry
        running = state.status == RUNNING
        target = targets[jnp.minimum(index, count - 1)]
        state = jax.lax.fori_loop(
            0, STEPS_PER_REFILL, lambda _, s: _select(s.status == RUNNING, step(target, s), s), state)
        done = running & (state.status != RUNNING)
        out = jax.tree_util.tree_map(
            lambda o, x: o.at[jnp.where(done, index, count)].set(x, mode="drop"), out, state)
        free = state.status != RUNNING
        new_index = queued + jnp.cumsum(free) - 1
        index = jnp.where(free, new_index, index)
        state = _select(free, load(index), state)
        return index, state, out, queued + jnp.sum(free)

    index = jnp.arange(slots)
    carry = (index, load(index), start(thetas0), jnp.asarray(slots))
    return jax.lax.while_loop(lambda c: jnp.any(c[1].status == RUNNING), body, carry)[2]


_run_queue = partial(runtime_jit.jit, static_argnames=("method", "slots"))(_queue)


def _shard_map():
    """jax.shard_map and the keyword that turns its replication check off (older jax: the
    experimental one); None when this jax has neither."""
    if hasattr(jax, "shard_map"):
        return jax.shard_map, {"check_vma": False}
    try:
        from jax.experimental.shard_map import shard_map
    except ImportError:
        return None
    return shard_map, {"check_rep": False}


@functools.lru_cache(maxsize=None)
def _mesh(devices):
    return jax.sharding.Mesh(np.array(devices), ("targets",))


@partial(runtime_jit.jit, static_argnames=("method", "slots", "mesh"))
def _run_split(method, task, arm, targets, thetas0, settings, max_iter, slots, mesh):
    """_queue on every device of the mesh, each on its share of the rows of targets."""
    shard_map, check_off = _shard_map()
    P = jax.sharding.PartitionSpec

    def share(task, arm, settings, max_iter, targets, thetas0):
        return _queue(method, task, arm, targets, thetas0, settings, max_iter, slots)

    return shard_map(share, mesh=mesh, in_specs=(P(), P(), P(), P(), P("targets"), P("targets")),
                     out_specs=P("targets"), **check_off)(task, arm, settings, max_iter, targets, thetas0)


def split_devices(count):
    """The devices a batch of `count` targets is split over: all local devices when there are
    several and every share gets SPLIT_FROM targets or more; else None (one device)."""
    devices = jax.local_devices()
    if len(devices) < 2 or count < SPLIT_FROM * len(devices) or _shard_map() is None:
        return None
    return tuple(devices)


def _run(method, task, arm, targets, thetas0, settings, max_iter):
    """_run_queue on one device, or _run_split over all of them: device k takes rows k, k + D,
    k + 2D, ... (neighbouring targets cost alike, so the shares take about as long), the rows
    padded to a multiple of D with copies of the last one, dropped again."""
    count, max_iter = targets.shape[0], np.int64(max_iter)  # traced: any max_iter, one program
    if count <= SMALL_BATCH:
        return _one_by_one(method, task, arm, targets, thetas0, settings, max_iter)
    devices = split_devices(count)
    if devices is None:
        return _run_queue(method, task, arm, targets, thetas0, settings, max_iter,
                          min(SLOTS, count))
    d = len(devices)
    share = -(-count // d)
    rows = np.minimum(np.arange(share * d).reshape(share, d).T.ravel(), count - 1)
    state = _run_split(method, task, arm, np.asarray(targets)[rows], np.asarray(thetas0)[rows],
                       settings, max_iter, min(SLOTS, share), _mesh(devices))
    back = np.arange(count)
    back = (back % d) * share + back // d  # where row r went
    return jax.tree_util.tree_map(lambda x: np.asarray(x)[back], state)


def _one_by_one(method, task, arm, targets, thetas0, settings, max_iter):
    """ik.solve's own compiled loop on each row (its trace dropped), the states stacked row by
    row. The rows are cut on the host: indexing a device array would dispatch two small
    programs per row."""
    rows, starts = np.asarray(targets), np.asarray(thetas0)
    states = [run_chunks(_run_jit, method, task, arm, rows[k], starts[k], settings, max_iter)[0]
              for k in range(rows.shape[0])]
    return jax.tree_util.tree_map(lambda *rows: np.stack([np.asarray(r) for r in rows]), *states)


def solve_batch(arm, targets, theta0, method="dls", tol=None, max_iter=1000,
                damping=None, rcond=DEFAULT_RCOND, clamp=None, max_step=None,
                stall_tol=None, gamma_max=GAMMA_MAX, weights=None, stop_rule=DEFAULT_STOP_RULE,
                joint_limits=None, limit_mode=None, levels=None, rest_pose=None,
                rest_gain=None):
    """Solve for every row of targets (B, d); theta0 is one start (n,) or one per target (B, n).

    A spatial chain takes 4x4 pose targets too: targets (B, 4, 4), with weights as in ik.solve.
    Same loop, defaults, stop rules and statuses as ik.solve (no trace is kept); method must
    be a name or a step function written with jax.numpy. Every row ends where ik.solve ends
    from the same start, to the bit with jax 0.10 (tests/test_batch.py: every method on planar,
    spatial and pose targets, trees, priority levels and joint limits, batches of 12; with
    jax 0.12 the same statuses and iterations, angles within 1e-12). The queue's
    arithmetic is vectorised over its slots; at several hundred slots XLA may vectorise some
    sums of pose and tree tasks differently, and their last bits can then differ (seen: 2e-15
    rad for SDLS on UR5 poses, 1,100 targets; a JT run to max_iter amplifies it). stop_rule,
    joint_limits, limit_mode, levels, rest_pose and rest_gain as in ik.solve. Bad input raises
    a ValueError as in ik.solve; an empty batch (no rows) too.
    """
    method = resolve_method(method)
    task, targets, theta0, settings, max_iter = check_problem(
        arm, targets, theta0, tol=tol, max_iter=max_iter, damping=damping, rcond=rcond,
        clamp=clamp, max_step=max_step, stall_tol=stall_tol, gamma_max=gamma_max, batch=True,
        weights=weights, stop_rule=stop_rule, method=method)
    method, settings, theta0 = with_extras(method, task, arm, targets, theta0, settings, levels,
                                           rest_pose, rest_gain, joint_limits, limit_mode, batch=True)
    require_traceable(method, task, arm, targets[0], theta0.reshape(-1, arm.n_joints)[0], settings)
    if theta0.ndim == 1:
        theta0 = jnp.broadcast_to(theta0, (targets.shape[0], theta0.shape[0]))
    state = _run(method, task, arm, targets, theta0, settings, max_iter)
    status = explain_stalls(method, task, arm, targets, state.theta, state.status, settings)
    return BatchResult(
        theta=np.asarray(state.theta),
        status=np.asarray(STATUSES, dtype=object)[status],
        iterations=np.asarray(state.i),
        error=np.asarray(state.error),
    )
