"""Targets per second on a workspace grid: ik.solve_batch (jit + vmap, timed after compiling)
against the same DLS loop as compiled scalar C (the physical anchor, built here with gcc and
called through ctypes) and as a plain numpy loop, with the same tolerance, iteration cap and
stop rules. Every row prints its iteration total: the rows do the same work.

    .venv/bin/python benchmarks/sweep.py [--n 256] [--numpy-subset 2048] [--repeats 3]

The numpy loop is timed on a subset of the grid (it takes minutes for all 65,536 targets)
and its rate is reported per target; the table says how many targets each row timed.
"""
import argparse
import os
import time

import jax
import numpy as np

import ikteach as ik
from ikteach._runtime import devices
from ikteach._runtime import engine as batch_module
from ikteach.core.stop_rules import STALL_FRACTION

import native  # benchmarks/native: the scalar C loop

LENGTHS = np.array([1.0, 1.0, 1.0])
THETA0 = np.array([0.3, 0.3, 0.3])
TOL, MAX_ITER, DAMPING = 1e-3, 200, 0.5


def numpy_dls(target, theta, lengths=LENGTHS, tol=TOL, max_iter=MAX_ITER, damping=DAMPING):
    """The same loop as ik.solve with method="dls", in plain numpy, for one planar target.

    Converged if |e| < tol (checked before stepping), stalled if the last step had
    sum |dtheta| < stall_tol, max_iter after max_iter steps. Returns (status, iterations).
    """
    stall_tol = STALL_FRACTION * lengths.sum()
    theta = theta.copy()
    last = np.inf
    for i in range(max_iter + 1):
        phi = np.cumsum(theta)
        c, s = lengths * np.cos(phi), lengths * np.sin(phi)
        e = target - np.array([c.sum(), s.sum()])
        if np.linalg.norm(e) < tol:
            return "converged", i
        if i > 0 and last < stall_tol:
            return "stalled", i
        if i == max_iter:
            return "max_iter", i
        # column j: z x (p_e - p_j) = (-(y_e - y_j), x_e - x_j); tails of the cumulative sums
        J = np.vstack([-np.cumsum(s[::-1])[::-1], np.cumsum(c[::-1])[::-1]])
        delta = J.T @ np.linalg.solve(J @ J.T + damping**2 * np.eye(2), e)
        theta += delta
        last = np.abs(delta).sum()
    raise AssertionError("unreachable")


def best_of(repeats, fn):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def best_with_loop(repeats, fn):
    """best_of, and the best time of those runs spent in the engine's loop (engine.run_queue):
    the work the C loop does too (solve_batch then names its stalls: stop_rules.why_stalled)."""
    run_queue, loop_times = batch_module.run_queue, []

    def timed(*args, **kwargs):
        t0 = time.perf_counter()
        try:
            return run_queue(*args, **kwargs)
        finally:
            loop_times.append(time.perf_counter() - t0)
    batch_module.run_queue = timed
    try:
        best, out = best_of(repeats, fn)
    finally:
        batch_module.run_queue = run_queue
    return best, min(loop_times), out


def table_row(name, timed, seconds, iterations):
    rate = timed / seconds
    print(f"| {name:<40} | {timed:>9} | {iterations:>12,} | {seconds:>8.3f} | {rate:>11,.0f} |")
    return rate


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=256, help="grid side: n*n targets")
    ap.add_argument("--numpy-subset", type=int, default=2048)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    # one device per core (setup() asks for one per two: ikteach/_runtime/devices.py); the
    # planar DLS step has no LAPACK call, so it splits safely
    print(f"CPU devices: {devices.use_cores(devices.available_cores())} (one per core)")

    arm = ik.planar_chain(LENGTHS)
    half = 1.1 * LENGTHS.sum()
    xs = np.linspace(-half, half, args.n)
    X, Y = np.meshgrid(xs, xs)
    targets = np.stack([X.ravel(), Y.ravel()], axis=1)
    # the C and numpy loops use the report's stop rule (sum |delta theta_i| < STALL_FRACTION * L)
    kw = dict(method="dls", tol=TOL, max_iter=MAX_ITER, damping=DAMPING, stop_rule="joint_steps",
              stall_tol=STALL_FRACTION * LENGTHS.sum())

    split = batch_module.split_devices(len(targets))
    t0 = time.perf_counter()
    ik.solve_batch(arm, targets, THETA0, **kw)
    compile_and_run = time.perf_counter() - t0
    if split:
        split_time, split_batch = best_of(args.repeats,
                                          lambda: ik.solve_batch(arm, targets, THETA0, **kw))
    batch_module.SPLIT_FROM, keep = 10**12, batch_module.SPLIT_FROM  # one device, one core
    ik.solve_batch(arm, targets, THETA0, **kw)
    jax_time, loop_time, batch = best_with_loop(
        args.repeats, lambda: ik.solve_batch(arm, targets, THETA0, **kw))
    batch_module.SPLIT_FROM = keep
    accelerator = jax.devices()[0].platform != "cpu"
    if accelerator:  # as before the engine sized its queue to the device: 1024 in flight
        batch_module.GPU_SLOTS, keep_slots = batch_module.SLOTS, batch_module.GPU_SLOTS
        ik.solve_batch(arm, targets, THETA0, **kw)
        queued_time, queued = best_of(args.repeats, lambda: ik.solve_batch(arm, targets, THETA0, **kw))
        batch_module.GPU_SLOTS = keep_slots

    lib = native.build()
    if lib is not None:
        stall_tol = STALL_FRACTION * LENGTHS.sum()
        c_time, (c_status, c_iters, _, c_total) = best_of(args.repeats, lambda: native.run(
            lib, LENGTHS, targets, THETA0, TOL, DAMPING, stall_tol, MAX_ITER))

    rng = np.random.default_rng(0)
    subset = rng.choice(len(targets), size=min(args.numpy_subset, len(targets)), replace=False)
    t0 = time.perf_counter()
    ref = [numpy_dls(targets[k], THETA0) for k in subset]
    np_time = time.perf_counter() - t0

    print(f"planar arm {LENGTHS.tolist()}, DLS (damping {DAMPING}), tol {TOL}, max_iter {MAX_ITER}, "
          f"theta0 {THETA0.tolist()}; {os.cpu_count()} CPU cores")
    print(f"grid {args.n} x {args.n} = {len(targets)} targets over [-{half:.2f}, {half:.2f}]^2; "
          f"statuses {batch.counts()}")
    print()
    print(f"| {'implementation':<40} | {'targets':>9} | {'iterations':>12} | {'seconds':>8} | "
          f"{'targets/s':>11} |")
    print(f"|{'-' * 42}|{'-' * 11}|{'-' * 14}|{'-' * 10}|{'-' * 13}|")
    jax_rate = table_row(f"ik.solve_batch (jit+vmap), 1 {jax.devices()[0].platform} device",
                         len(targets), jax_time, int(batch.iterations.sum()))
    loop_rate = table_row("  its loop alone (engine.run_queue)", len(targets), loop_time,
                          int(batch.iterations.sum()))
    if accelerator:
        table_row(f"the same, {batch_module.SLOTS} in flight (as before)", len(targets),
                  queued_time, int(queued.iterations.sum()))
    if split:
        split_rate = table_row(f"ik.solve_batch split over {len(split)} CPU devices", len(targets),
                               split_time, int(split_batch.iterations.sum()))
    if lib is not None:
        c_rate = table_row("scalar C loop (gcc -O3, ctypes), 1 core", len(targets), c_time, c_total)
    if len(subset):  # --numpy-subset 0 leaves the (slow) numpy row out
        np_rate = table_row("plain numpy loop over targets", len(subset), np_time,
                            sum(it for _, it in ref))
    print()
    print(f"first solve_batch call incl. compile: {compile_and_run:.2f} s (goal < 3 s); best of {args.repeats} "
          f"runs after; devices {[str(d) for d in jax.devices()]}")
    if split:
        same = all(np.array_equal(getattr(batch, f), getattr(split_batch, f))
                   for f in ("theta", "status", "iterations", "error"))
        print(f"split and one-device results identical to the bit: {same}")
    if len(subset):
        print(f"solve_batch vs numpy: {jax_rate / np_rate:.0f}x faster")
    if lib is not None:
        names = np.asarray(ik.STATUSES, dtype=object)[c_status]
        same = np.mean((names == batch.status) & (c_iters == batch.iterations))
        print(f"solve_batch vs scalar C: {c_rate / jax_rate:.2f}x slower "
              f"(goal <= 2.5x); same status and iteration count for {same:.2%} of the targets")
        print(f"its loop alone vs scalar C: {c_rate / loop_rate:.2f}x slower; naming the "
              f"{batch.counts()['stalled']} stalls takes the rest: "
              f"{(jax_time - loop_time) / loop_time:.0%} of the loop's time (goal <= 25%)")
        if split:
            print(f"solve_batch split over {len(split)} devices vs scalar C on 1 core: "
                  f"{split_rate / c_rate:.2f}x as fast (stretch goal > 1)")
    else:
        print("scalar C row skipped: no C compiler (gcc or cc) found")
    if len(subset):
        agree = np.mean([s == batch.status[k] and it == batch.iterations[k]
                         for (s, it), k in zip(ref, subset)])
        print(f"numpy and solve_batch agree on status and iteration count for {agree:.1%} of "
              "the subset")


if __name__ == "__main__":
    main()
