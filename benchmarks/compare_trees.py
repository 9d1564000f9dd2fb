"""Buss's protocol on the Y and double-Y trees: one IK step per time step of 0.005 while the
targets move (sums of sines), 400 warm-up steps then 2000 measured steps (RunTestB in Buss's
demo). Prints mean end-effector error (sum over effectors) and joint jitter per method, and
how DLS's damping lambda trades error for jitter.

    python benchmarks/compare_trees.py [--steps 2000] [--warmup 400]
"""
import argparse

import numpy as np

import ikteach as ik
from ikteach.core import buss_trees as bt

TREES = {"y": (bt.y_tree, bt.y_targets), "double_y": (bt.double_y_tree, bt.double_y_targets)}


def methods(tree_name):
    """Buss's settings per method (Jacobian.cpp of his demo): ikteach/core/buss_trees.py."""
    return bt.demo_methods(tree_name)


def run(tree_name, steps, warmup, **kw):
    make, targets_at = TREES[tree_name]
    res = ik.track(make(), targets_at(bt.times(warmup + steps)), **kw)
    measured = ik.core.track.TrackResult(res.theta[warmup:], res.error[warmup:])
    return measured


def method_table(steps, warmup):
    rows = []
    for name in TREES:
        for label, kw in methods(name).items():
            r = run(name, steps, warmup, **kw)
            rows.append((name, label, r.mean_error, r.jitter))
    return rows


def damping_table(tree_name, lambdas, steps, warmup):
    return [(lam, *(lambda r: (r.mean_error, r.jitter))(
        run(tree_name, steps, warmup, method="dls", damping=lam, max_step=bt.MAX_STEP["dls"])))
        for lam in lambdas]


def print_method_table(rows):
    print(f"{'tree':<9} {'method':<14} {'mean error':>10} {'jitter':>9}")
    for tree_name, label, err, jit in rows:
        print(f"{tree_name:<9} {label:<14} {err:>10.4f} {jit:>9.4f}")


def print_damping_table(rows, tree_name):
    print(f"DLS on the {tree_name} tree: damping lambda vs error and jitter")
    print(f"{'lambda':>7} {'mean error':>10} {'jitter':>9}")
    for lam, err, jit in rows:
        print(f"{lam:>7.2f} {err:>10.4f} {jit:>9.4f}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--warmup", type=int, default=400)
    a = ap.parse_args()
    print(f"Buss's protocol: {a.warmup} warm-up steps, then {a.steps} measured steps of T = 0.005")
    print("mean error = mean over steps of sum_k |t_k - x_k|; "
          "jitter = ik.core.jitter.jitter: mean over steps of sum_j |theta_j(t+1) - 2 theta_j(t) + theta_j(t-1)|\n")
    print_method_table(method_table(a.steps, a.warmup))
    print()
    print_damping_table(damping_table("double_y", [0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.5], a.steps, a.warmup),
                        "double_y")
