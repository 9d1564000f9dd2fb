"""A long session: 10,000 varied solves in one process (every built-in method, chains of 1-12
joints, max_iter anywhere from 1 to 5,000, planar and spatial arms, clamps, step caps, joint
limits and rest poses, UR5 pose targets with varied weights, batches of varied sizes), with the
memory mappings and resident memory it holds as it goes. Before issue 23 every new max_iter,
joint count and method compiled a program of its own (about 140 mappings and 5 MB each) and a
session like this one died at the system's limit on mappings (vm.max_map_count, 65530 on
Debian) after about 430 programs.

    .venv/bin/python benchmarks/many_programs.py [--solves 10000] [--bound N]

--bound sets IKTEACH_MAX_PROGRAMS for the run (0: no bound) to compare. JAX's persistent
compilation cache is on, in an empty folder, as ik.notebook.setup() turns it on in a notebook:
after the bound clears JAX's caches, the programs still in use load from it (--no-cache: they
compile again).
"""
import argparse
import os
import resource
import shutil
import tempfile
import time

import numpy as np


def mappings():
    with open("/proc/self/maps") as f:
        return sum(1 for _ in f)


def rss_mb():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--solves", type=int, default=10_000)
    ap.add_argument("--bound", type=int, default=None)
    ap.add_argument("--no-cache", action="store_true",
                    help="without JAX's persistent compilation cache (a notebook has it on: "
                         "ik.notebook.setup()); a clear then compiles again what it loads")
    args = ap.parse_args()
    if args.bound is not None:
        os.environ["IKTEACH_MAX_PROGRAMS"] = str(args.bound)
    import ikteach as ik
    from jax import monitoring
    from ikteach._runtime import jit as runtime_jit

    cache = None if args.no_cache else tempfile.mkdtemp(prefix="ikteach-cache-")
    if cache:  # as ik.notebook.setup() does, with an empty cache: a first run
        ik.notebook.compilation_cache(cache)

    compiles = []
    monitoring.register_event_duration_secs_listener(
        lambda event, duration, **kw: compiles.append(duration)
        if event.endswith("backend_compile_duration") else None)
    rng = np.random.default_rng(0)
    methods = tuple(ik.core.methods.METHODS)
    spatial = {n: ik.serial_chain(np.tile([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0]], (n, 1))[:n],
                                  [[0.0, 0.0, 0.3]] * n) for n in range(1, 13)}
    ur5 = ik.core.robots.ur5()
    print(f"bound: {runtime_jit.max_programs() or 'none'} programs; "
          f"persistent cache: {'on (empty at the start)' if cache else 'off'}; "
          f"vm.max_map_count {open('/proc/sys/vm/max_map_count').read().strip()}")
    print(f"| {'solves':>7} | {'seconds':>8} | {'compiles':>8} | {'clears':>6} | "
          f"{'mappings':>8} | {'RSS MB':>7} |")
    print(f"|{'-' * 9}|{'-' * 10}|{'-' * 10}|{'-' * 8}|{'-' * 10}|{'-' * 9}|")
    t0 = time.perf_counter()
    statuses = {}
    for k in range(1, args.solves + 1):
        n = int(rng.integers(1, 13))
        method = methods[k % len(methods)]
        max_iter = int(rng.choice([1, 7, 50, 300, 1000, 5000]))
        if k % 7 == 0 and method not in ("ccd", "fabrik"):
            arm = spatial[n]
            target = rng.uniform(-0.3, 0.3, size=3) * n
        else:
            arm = ik.planar_chain(rng.uniform(0.2, 1.0, size=n))
            target = rng.uniform(-1.0, 1.0, size=2) * n * 0.6
        options = {}
        if k % 3 == 0:
            options["clamp"] = float(rng.choice([0.1, 0.5])) * n
        if k % 5 == 0:
            options["max_step"] = float(rng.choice([0.1, 0.3]))
        if k % 13 == 0 and method not in ("ccd", "fabrik"):
            options["joint_limits"] = (-2.0, 2.0)
        if k % 17 == 0 and method == "dls":
            options["rest_pose"] = np.zeros(n)
            options["rest_gain"] = float(rng.uniform(0.05, 0.5))
        if k % 11 == 0 and method not in ("ccd", "fabrik"):
            target = np.asarray(ik.fk_pose(ur5, rng.uniform(-1.5, 1.5, size=6)))
            status = ik.solve(ur5, target, np.full(6, 0.1), method=method, max_iter=max_iter,
                              weights=tuple(rng.uniform(0.2, 2.0, size=2))).status
        elif k % 250 == 0:
            size = int(rng.integers(9, 700))
            res = ik.solve_batch(arm, rng.uniform(-1, 1, size=(size, arm.dim)) * n * 0.6,
                                 np.zeros(n), method=method, max_iter=max_iter, **options)
            status = res.status[0]
        else:
            status = ik.solve(arm, target, rng.uniform(-1, 1, size=n), method=method,
                              max_iter=max_iter, **options).status
        statuses[status] = statuses.get(status, 0) + 1
        if k % (args.solves // 10) == 0:
            print(f"| {k:>7,} | {time.perf_counter() - t0:>8.1f} | {len(compiles):>8} | "
                  f"{runtime_jit.clears[0]:>6} | {mappings():>8,} | {rss_mb():>7.0f} |", flush=True)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"statuses: {statuses}; peak RSS {peak:.0f} MB")
    if cache:
        shutil.rmtree(cache, ignore_errors=True)


if __name__ == "__main__":
    main()
