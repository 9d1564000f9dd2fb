"""The engine: runs the course's loop function compiled, vectorised or eagerly, never rewrites it.

Every function here takes `step`, a module-level function of the core (loop.iterate or a thin
adaptor of it), and its arguments `args` (a pytree: the problem, method and options). A state
is a NamedTuple with fields i, theta, error and status; it is running while status == RUNNING.

  run_traced   ik.solve: a jax.lax.while_loop over step, TRACE_CHUNK passes per compiled run,
               recording theta and ||e|| of every pass (memory follows the work, any max_iter
               reuses the program);
  run_eager    the same, one Python pass at a time, for step functions JAX cannot trace;
  run_queue    ik.solve_batch: jax.vmap of step over `slots` targets in flight; a slot whose
               target has finished takes the next one (the work is the sum of the iterations,
               not the batch size times the largest count); batches padded to a few sizes
               (bucket) so a new batch size rarely compiles; one path for one device or several
               (a jax.sharding mesh: each device its share), the whole share in flight on an
               accelerator;
  run_scan     ik.track: jax.lax.scan of one step per time step, SCAN_CHUNK steps per program
               (several paths side by side: jax.vmap of the step);
  run_rows     a per-row function (the stall classifier) over many rows: vmapped, in calls
               of few sizes, split over the devices;
  until_stopped  the loop as one traceable while_loop, for a caller's own compiled program.
"""
import functools
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from . import jit as runtime_jit
from .shared import as_data

RUNNING = 0  # the loop's status while it runs (ikteach/core/loop.py)
TRACE_CHUNK = 256  # passes per compiled run when the trace is kept
SLOTS = 1024  # targets in flight at once on a CPU device (what one core's caches hold)
GPU_SLOTS = 1 << 22  # on a GPU or TPU: the whole batch, up to this many (4 M)
SPLIT_FROM = 512  # targets per device below which a batch stays on one device
MIN_BUCKET = 16  # the smallest padded batch (ikteach/core/batch.py runs up to 8 one by one)
STEPS_PER_REFILL = 4  # passes between refills (a refill costs more than a pass)
SCAN_CHUNK = 128  # time steps per compiled scan: paths of any length reuse one program


def same_types(new, old):
    """new with the dtypes of old (a Python number in a step would otherwise change the
    program's types from one pass to the next)."""
    return jax.tree_util.tree_map(lambda n, o: jnp.asarray(n, dtype=jnp.asarray(o).dtype), new, old)


def host_state(state):
    """A state as numpy values of fixed dtypes (no small device programs to build it)."""
    return jax.tree_util.tree_map(np.asarray, state)


def until_stopped(step, args, state):
    """step until the state stops, as one traceable jax.lax.while_loop (no trace kept): for
    callers that compile a larger program around the loop (a whole clip, frame by frame)."""
    return jax.lax.while_loop(lambda s: s.status == RUNNING,
                              lambda s: same_types(step(*args, s), s), state)


@partial(runtime_jit.jit, static_argnames=("step",))
def _traced_chunk(step, args, state):
    first = state.i
    thetas = jnp.zeros((TRACE_CHUNK + 1,) + state.theta.shape).at[0].set(state.theta)
    errors = jnp.zeros(TRACE_CHUNK + 1)

    def body(carry):
        state, thetas, errors = carry
        new = same_types(step(*args, state), state)
        row = state.i - first
        return new, thetas.at[row + 1].set(new.theta), errors.at[row].set(new.error)

    def more(carry):
        return (carry[0].status == RUNNING) & (carry[0].i < first + TRACE_CHUNK)

    return jax.lax.while_loop(more, body, (state, thetas, errors))


def run_traced(step, args, state):
    """Run step until the state stops, chunk by chunk; returns the last state (numpy) and the
    trace: theta (k + 1, n) and error (k + 1,) for the k steps taken."""
    args, state, thetas, errors = as_data(args), host_state(state), [], []
    while True:
        first = int(state.i)
        state, chunk_thetas, chunk_errors = jax.device_get(_traced_chunk(step, args, state))
        done = int(state.status) != RUNNING
        k = int(state.i) - first
        thetas.append(chunk_thetas[: k + done])
        errors.append(chunk_errors[: k + done])
        if done:
            return state, np.concatenate(thetas), np.concatenate(errors)


def run_eager(step, args, state, stop_exception, on_stop):
    """run_traced's result, one Python pass at a time. When the step raises stop_exception
    (a user's own stop rule), on_stop(state) -> state gives the stopped state."""
    thetas, errors = [np.asarray(state.theta)], []
    while int(state.status) == RUNNING:
        try:
            state = step(*args, state)
        except stop_exception:
            state = on_stop(state)
        errors.append(float(state.error))
        if int(state.status) == RUNNING:
            thetas.append(np.asarray(state.theta))
    return host_state(state), np.stack(thetas), np.asarray(errors)


def _select(mask, a, b):
    """Per slot: a where mask, else b (for every field of a state)."""
    return jax.tree_util.tree_map(
        lambda x, y: jnp.where(mask.reshape(mask.shape + (1,) * (x.ndim - 1)), x, y), a, b)


def bucket(count, queued=False):
    """The row count a batch of `count` rows is padded to: the next power of two, at least
    MIN_BUCKET. Batches of 9, 10 or 16 rows then share one program, 257 and 500 another; the
    padded rows are idle slots, never solved.
    queued: a CPU queue's rows, SLOTS in flight (in_flight). Past SLOTS rows the padding is
    never loaded into a slot, so it costs memory only: the bucket is then the next SLOTS x 8^k
    (8,192, 65,536, 524,288, ...), and the 128 x 128 and 256 x 256 maps share one program."""
    size = max(MIN_BUCKET, 1 << (int(count) - 1).bit_length())
    if not queued or size <= SLOTS:
        return size
    size = SLOTS
    while size < count:
        size *= 8
    return size


def _queue(step, start, args, rows, starts, count, slots):
    """The first `count` rows solved, `slots` at a time (rows past count are padding):
    step(args, row, state) -> state, start(theta0) -> state."""
    count = jnp.reshape(count, ())  # traced: a new batch size in the same bucket compiles nothing
    pick = lambda index: jax.tree_util.tree_map(lambda r: r[jnp.minimum(index, count - 1)], rows)
    one_pass = jax.vmap(lambda row, s: same_types(step(args, row, s), s))
    fresh = jax.vmap(start)
    size = starts.shape[0]

    def load(index):  # fresh states for these rows; an index past the end marks an idle slot
        state = fresh(starts[jnp.minimum(index, count - 1)])
        return state._replace(status=jnp.where(index < count, state.status, -1))

    def body(carry):
        index, state, out, queued = carry
        running = state.status == RUNNING
        row = pick(index)
        state = jax.lax.fori_loop(0, STEPS_PER_REFILL, lambda _, s: _select(
            s.status == RUNNING, one_pass(row, s), s), state)
        done = running & (state.status != RUNNING)
        out = jax.tree_util.tree_map(
            lambda o, x: o.at[jnp.where(done, index, size)].set(x, mode="drop"), out, state)
        free = state.status != RUNNING
        index = jnp.where(free, queued + jnp.cumsum(free) - 1, index)
        state = _select(free, load(index), state)
        return index, state, out, queued + jnp.sum(free)

    index = jnp.arange(slots)
    carry = (index, load(index), fresh(starts), jnp.asarray(slots))
    return jax.lax.while_loop(lambda c: jnp.any(c[1].status == RUNNING), body, carry)[2]


def _all(step, start, args, rows, starts, count):
    """Every row in flight at once (an accelerator's whole batch): jax.vmap of the loop, the
    padding rows (index >= count) idle from the start."""
    def one(index, row, theta0):
        state = start(theta0)
        state = state._replace(status=jnp.where(index < count, state.status, -1))
        return until_stopped(step, (args, row), state)
    return jax.vmap(one)(jnp.arange(starts.shape[0]), rows, starts)


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
    return jax.sharding.Mesh(np.array(devices), ("rows",))


def _on_mesh(share, mesh, shared, *split):
    """share(shared, *split) on every device of the mesh, each on its rows of the `split`
    arrays (`shared` goes to every device whole); outputs split by rows alike."""
    found = _shard_map()
    if found is None:  # a jax without shard_map: one device
        return share(shared, *split)
    shard_map, check_off = found
    P = jax.sharding.PartitionSpec
    return shard_map(share, mesh=mesh, in_specs=(P(),) + (P("rows"),) * len(split),
                     out_specs=P("rows"), **check_off)(shared, *split)


@partial(runtime_jit.jit, static_argnames=("step", "start", "slots", "whole", "mesh"))
def _run_queue(step, start, args, rows, starts, counts, slots, whole, mesh):
    """Each device of the mesh (one or several) solves its share of the rows (counts: how many
    of each device's rows are real): _all when the whole share is in flight on an accelerator,
    else _queue with `slots` in flight."""
    def share(args, rows, starts, count):
        count = jnp.reshape(count, ())  # traced: a new batch size in the same bucket compiles nothing
        if whole:
            return _all(step, start, args, rows, starts, count)
        return _queue(step, start, args, rows, starts, count, slots)
    return _on_mesh(share, mesh, args, rows, starts, counts)


def split_devices(count):
    """The devices a batch of `count` rows is split over: all local devices when there are
    several and every share gets SPLIT_FROM rows or more; else None (one device)."""
    devices = jax.local_devices()
    if len(devices) < 2 or count < SPLIT_FROM * len(devices) or _shard_map() is None:
        return None
    return tuple(devices)


def in_flight(size, device=None):
    """How many of `size` rows a device keeps in flight: SLOTS on a CPU (a pass over more would
    spill its caches), the whole batch up to GPU_SLOTS on an accelerator (it needs them all
    to fill its cores; refills then never happen)."""
    platform = (device or jax.local_devices()[0]).platform
    return min(SLOTS if platform == "cpu" else GPU_SLOTS, size)


def rows_per_call(count, few=8, many=SLOTS):
    """How many of `count` rows one call of a per-row program (the stall classifier) takes:
    one for a handful of rows (up to `few`: a solve's one row, a small batch's few, one call
    each), `many` on a CPU, and on an accelerator all of them at once (padded to
    bucket(count), up to GPU_SLOTS): a host round trip per 1,024 rows would leave it idle.
    Few sizes, so few programs."""
    if count <= few:
        return 1
    if jax.local_devices()[0].platform == "cpu":
        return many
    return min(bucket(count), GPU_SLOTS)


def _rows(fn, shared, rows, mesh):
    """fn(shared, *row) for every row (jax.vmap), each device of the mesh its share."""
    def share(shared, rows):
        return jax.vmap(lambda *row: fn(shared, *row))(*rows)
    return _on_mesh(share, mesh, shared, rows)


_per_row = runtime_jit.jit(_rows, static_argnames=("fn", "mesh"))
_one_row = runtime_jit.jit(_rows, static_argnames=("fn", "mesh"), light=True)  # runs briefly


def run_rows(fn, shared, rows, few=8, many=SLOTS):
    """fn(shared, *row) for every row of `rows` (a tuple of arrays, one row each), as numpy:
    rows_per_call(count, few, many) rows per device and call (the last call padded with
    copies of the last row), over all devices when the rows are many (split_devices). A
    per-row program then compiles for few sizes, whatever the count; the one-row program
    compiles light (ikteach/_runtime/jit.py: it runs briefly)."""
    count, shared = len(rows[0]), as_data(shared)
    devices = split_devices(count) or tuple(jax.local_devices()[:1])
    per_call = rows_per_call(-(-count // len(devices)), few, many)
    block = per_call * len(devices)
    program = _one_row if per_call == 1 else _per_row
    padded = np.minimum(np.arange(count + (-count % block)), count - 1)
    found = [program(fn, shared, tuple(np.asarray(x)[part] for x in rows), _mesh(devices))
             for part in padded.reshape(-1, block)]
    return np.concatenate([np.asarray(f) for f in found])[:count]


def run_queue(step, start, args, rows, starts):
    """Final states of every row (numpy), through one path for one device or several (a
    jax.sharding mesh, _run_queue). Device k of D takes rows k, k + D, k + 2D, ... (neighbouring
    rows cost alike, so the shares take about as long); each share is padded to bucket(share)
    (coarser past SLOTS rows on a CPU), so batches of nearby sizes share one program."""
    count, args = starts.shape[0], as_data(args)
    devices = split_devices(count) or tuple(jax.local_devices()[:1])
    d = len(devices)
    share = bucket(-(-count // d), queued=devices[0].platform == "cpu")
    order = np.minimum(np.arange(d)[:, None] + d * np.arange(share)[None, :], count - 1).ravel()
    counts = np.array([len(range(k, count, d)) for k in range(d)], dtype=np.int64)
    take = lambda x: np.asarray(x)[order]
    slots = in_flight(share, devices[0])
    whole = slots == share and devices[0].platform != "cpu"
    state = _run_queue(step, start, args, jax.tree_util.tree_map(take, rows), take(starts),
                       counts, slots, whole, _mesh(devices))
    back = np.arange(count)
    back = (back % d) * share + back // d  # where row r went
    return jax.tree_util.tree_map(lambda x: np.asarray(x)[back], jax.device_get(state))


@partial(runtime_jit.jit, static_argnames=("step", "paths"))
def _scan(step, args, carry, rows, paths):
    advance = jax.vmap(step, in_axes=(None, 0, 0)) if paths else step  # paths: side by side

    def one(carry, row):
        new, out = advance(args, carry, row)
        return same_types(new, carry), out
    return jax.lax.scan(one, carry, rows)


def run_scan(step, args, carry, rows, paths=False):
    """step(args, carry, row) -> (carry, out) over the rows, SCAN_CHUNK rows per compiled run
    (the last chunk padded with copies of the last row, its extra outputs dropped); returns
    the outputs stacked (numpy). paths: rows (P, T, ...) and carry (P, ...) hold P independent
    runs, stepped side by side in one program (jax.vmap of step); outputs (P, T, ...)."""
    args = as_data(args)
    if paths:  # time first: the scan walks the time steps, every path at once
        rows = jax.tree_util.tree_map(lambda x: np.swapaxes(np.asarray(x), 0, 1), rows)
    count = jax.tree_util.tree_leaves(rows)[0].shape[0]
    pad = lambda x: np.concatenate([x, np.repeat(x[-1:], -count % SCAN_CHUNK, axis=0)])
    rows = jax.tree_util.tree_map(lambda x: pad(np.asarray(x)), rows)
    carry, outs = host_state(carry), []
    for first in range(0, count + (-count % SCAN_CHUNK), SCAN_CHUNK):
        chunk = jax.tree_util.tree_map(lambda x: x[first: first + SCAN_CHUNK], rows)
        carry, out = _scan(step, args, carry, chunk, paths)
        outs.append(jax.device_get(out))
    stacked = jax.tree_util.tree_map(lambda *parts: np.concatenate(parts)[:count], *outs)
    return jax.tree_util.tree_map(lambda x: np.swapaxes(x, 0, 1), stacked) if paths else stacked
