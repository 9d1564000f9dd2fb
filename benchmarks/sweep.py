"""Targets per second: ik.solve_batch (jit + vmap, timed after compiling) against a plain
numpy loop over targets with the same DLS method, tolerance, iteration cap and stop rules.

    .venv/bin/python benchmarks/sweep.py [--n 256] [--numpy-subset 2048]

The numpy loop is timed on a subset of the grid (it takes minutes for all 65,536 targets)
and its rate is reported per target; the table says how many targets each row timed.
"""
import argparse
import time

import numpy as np

import ikteach as ik
from ikteach.solve import STALL_FRACTION

LENGTHS = np.array([1.0, 1.0, 1.0])
THETA0 = np.array([0.3, 0.6, 0.6])
TOL, MAX_ITER, DAMPING = 1e-3, 100, 0.5


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


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=256, help="grid side: n*n targets")
    ap.add_argument("--numpy-subset", type=int, default=2048)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()

    arm = ik.planar_chain(LENGTHS)
    half = 1.1 * LENGTHS.sum()
    xs = np.linspace(-half, half, args.n)
    X, Y = np.meshgrid(xs, xs)
    targets = np.stack([X.ravel(), Y.ravel()], axis=1)
    kw = dict(method="dls", tol=TOL, max_iter=MAX_ITER, damping=DAMPING)

    t0 = time.perf_counter()
    ik.solve_batch(arm, targets, THETA0, **kw)
    compile_and_run = time.perf_counter() - t0
    times = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        batch = ik.solve_batch(arm, targets, THETA0, **kw)
        times.append(time.perf_counter() - t0)
    jax_time = min(times)

    rng = np.random.default_rng(0)
    subset = rng.choice(len(targets), size=min(args.numpy_subset, len(targets)), replace=False)
    t0 = time.perf_counter()
    ref = [numpy_dls(targets[k], THETA0) for k in subset]
    np_time = time.perf_counter() - t0
    agree = np.mean([s == batch.status[k] and it == batch.iterations[k]
                     for (s, it), k in zip(ref, subset)])

    jax_rate = len(targets) / jax_time
    np_rate = len(subset) / np_time
    print(f"planar arm {LENGTHS.tolist()}, DLS (damping {DAMPING}), tol {TOL}, max_iter {MAX_ITER}, "
          f"theta0 {THETA0.tolist()}")
    print(f"grid {args.n} x {args.n} = {len(targets)} targets over [-{half:.2f}, {half:.2f}]^2; "
          f"statuses {batch.counts()}")
    print()
    print(f"| {'implementation':<34} | {'targets timed':>13} | {'seconds':>8} | {'targets/s':>11} |")
    print(f"|{'-' * 36}|{'-' * 15}|{'-' * 10}|{'-' * 13}|")
    print(f"| {'ik.solve_batch (jit+vmap), compiled':<34} | {len(targets):>13} | {jax_time:>8.2f} | "
          f"{jax_rate:>11.0f} |")
    print(f"| {'plain numpy loop over targets':<34} | {len(subset):>13} | {np_time:>8.2f} | "
          f"{np_rate:>11.0f} |")
    print()
    print(f"speed-up: {jax_rate / np_rate:.0f}x   (first call incl. compile: {compile_and_run:.2f} s; "
          f"best of {args.repeats} runs after)")
    print(f"numpy and JAX agree on status and iteration count for {agree:.1%} of the subset")


if __name__ == "__main__":
    main()
