"""Pose targets per second for a 7-joint arm (the iiwa14, DLS), on the device JAX has (a GPU
where there is one): reachable poses from forward kinematics of random joint angles, solved
from one start by ik.solve_batch, timed after compiling.

    .venv/bin/python benchmarks/pose_rate.py [--count 4096] [--repeats 2]
"""
import argparse
import time

import jax
import numpy as np

import ikteach as ik
from ikteach._runtime import engine


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--count", type=int, default=4096)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    arm = ik.core.robots.iiwa14()
    rng = np.random.default_rng(0)
    angles = rng.uniform(-1.5, 1.5, size=(args.count, arm.n_joints))
    poses = np.asarray(jax.jit(jax.vmap(lambda q: ik.fk_pose(arm, q)))(angles))
    start = np.full(arm.n_joints, 0.2)
    kw = dict(method="dls", max_iter=200)
    t0 = time.perf_counter()
    ik.solve_batch(arm, poses, start, **kw)
    first = time.perf_counter() - t0
    times = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        res = ik.solve_batch(arm, poses, start, **kw)
        times.append(time.perf_counter() - t0)
    best = min(times)
    print(f"iiwa14 pose targets, DLS, {args.count} targets on {jax.devices()[0]} "
          f"({engine.in_flight(engine.bucket(args.count))} in flight): first call {first:.2f} s, "
          f"best of {args.repeats} {best:.3f} s = {args.count / best:,.0f} targets/s, "
          f"{int(res.iterations.sum()):,} iterations; statuses {res.counts()}")


if __name__ == "__main__":
    main()
