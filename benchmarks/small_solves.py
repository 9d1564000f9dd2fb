"""The closed forms for two- and three-row Jacobians against the general solves, in a sweep:
`pinv_two_rows` (one Jacobi rotation, lecture 03) against `pinv_step` (an SVD call), and
`dls_step_small` (Cramer's rule, lecture 04) against `dls_step` (an LU solve per target).

Each pair solves the same n x n grid of targets with ik.solve_batch (timed after compiling,
best of --repeats) and must end with the same statuses. This is the one place these speed-ups
are measured; the lectures and docstrings quote no figure.

    .venv/bin/python benchmarks/small_solves.py [--n 256] [--repeats 3]
"""
import argparse
import time

import numpy as np

import ikteach as ik

LENGTHS = [1.0, 0.5, 0.25]
THETA0 = [0.3, 0.6, 0.6]
DAMPING = 0.1


def best_of(repeats, fn):
    fn()  # compile
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=256, help="grid side: n*n targets")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    arm = ik.planar_chain(LENGTHS)
    half = 1.1 * sum(LENGTHS)
    xs = np.linspace(-half, half, args.n)
    X, Y = np.meshgrid(xs, xs)
    targets = np.stack([X.ravel(), Y.ravel()], axis=1)
    pairs = {
        "pseudoinverse": (("pinv_two_rows (method 'pinv')", "pinv"),
                          ("pinv_step (SVD)", lambda J, e: ik.pinv_step(J, e))),
        f"DLS, lambda {DAMPING}": (("dls_step_small (method 'dls')", ik.DLS(damping=DAMPING)),
                                   ("dls_step (LU)", lambda J, e: ik.dls_step(J, e, DAMPING))),
    }
    print(f"planar arm {LENGTHS}, {len(targets)} targets, theta0 {THETA0}, best of {args.repeats}")
    print(f"| {'step':<32} | {'seconds':>8} | {'iterations':>11} | {'vs general':>10} |")
    print(f"|{'-' * 34}|{'-' * 10}|{'-' * 13}|{'-' * 12}|")
    for name, ((fast_name, fast), (slow_name, slow)) in pairs.items():
        runs = {}
        for label, method in ((fast_name, fast), (slow_name, slow)):
            runs[label] = best_of(args.repeats, lambda: ik.solve_batch(arm, targets, THETA0, method=method))
        t_fast, t_slow = runs[fast_name][0], runs[slow_name][0]
        for label, (seconds, res) in runs.items():
            ratio = f"{t_slow / t_fast:.2f}x" if label == fast_name else ""
            print(f"| {label:<32} | {seconds:>8.3f} | {int(res.iterations.sum()):>11,} | {ratio:>10} |")
        same = np.array_equal(runs[fast_name][1].status, runs[slow_name][1].status)
        print(f"{name}: same statuses on every target: {same}")


if __name__ == "__main__":
    main()
