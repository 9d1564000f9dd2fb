"""Interactive latency: how long one solve, one demo update and one live-map redraw take
after the first of their shape (which compiles), and how long the first one took.

    .venv/bin/python benchmarks/latency.py [--n 40] [--map-n 128] [--skip-demo] [--skip-map]
                                           [--skip-new-kernel]

Rows: ik.solve on the 3-link planar arm for each method over random targets (some out
of reach) with varied damping, tolerance and clamp; ik.pictures.demo.Demo().update(x=..., y=...)
per method (solve + PNG render); the notebook-07 live map (128 x 128 solve_batch + redraw)
per method and lambda; the first solve per method in a new process with the compilation
cache warm, with and without the program store.
Goals (issue 9): solve p95 < 10 ms, demo p95 < 50 ms, map < 0.5 s.
"""
import argparse
import time

t_import = time.perf_counter()
import numpy as np  # noqa: E402

import ikteach as ik  # noqa: E402

IMPORT_S = time.perf_counter() - t_import
from ikteach._runtime import devices  # noqa: E402

CPU_DEVICES = devices.use_cores()  # as ik.notebook.setup() does in the course notebooks
METHODS = tuple(ik.core.methods.METHODS)
THETA0 = np.array([0.1, 0.2, 0.3])


def timed(fn):
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def row(name, first, times, goal):
    ms = 1e3 * np.asarray(times)
    p50, p95 = np.percentile(ms, 50), np.percentile(ms, 95)
    verdict = "ok" if p95 < goal else "SLOW"
    print(f"| {name:<24} | {1e3 * first:>9.0f} | {p50:>8.1f} | {p95:>8.1f} | {ms.max():>8.1f} | "
          f"{goal:>7.0f} | {verdict:<4} |")


def header(title):
    print()
    print(title)
    print(f"| {'what':<24} | {'first ms':>9} | {'p50 ms':>8} | {'p95 ms':>8} | {'max ms':>8} | "
          f"{'goal ms':>7} | {'':<4} |")
    print(f"|{'-' * 26}|{'-' * 11}|{'-' * 10}|{'-' * 10}|{'-' * 10}|{'-' * 9}|{'-' * 6}|")


def random_targets(rng, n, radius):
    r = radius * np.sqrt(rng.uniform(0, 1, n))
    a = rng.uniform(-np.pi, np.pi, n)
    return np.stack([r * np.cos(a), r * np.sin(a)], axis=1)


def solve_rows(arm, n, rng):
    header(f"ik.solve, 3-link planar arm, {n} random targets after the first (varied damping, "
           "tol, clamp)")
    for method in METHODS:
        first = timed(lambda: ik.solve(arm, [2.0, 1.0], THETA0, method=method, max_iter=300))
        times = []
        for target in random_targets(rng, n, 3.4):
            kw = dict(damping=rng.uniform(0.1, 1.0), tol=rng.choice([1e-3, 1e-4]),
                      clamp=rng.choice([None, 0.5]))
            times.append(timed(lambda: ik.solve(arm, target, THETA0, method=method,
                                                max_iter=300, **kw)))
        row(method, first, times, 10)


def demo_rows(n, rng):
    header(f"ik.pictures.demo.Demo().update(x=..., y=...), solve + PNG render, {n} slider moves")
    t0 = time.perf_counter()
    demo = ik.pictures.demo.Demo()
    built = time.perf_counter() - t0
    for method in demo.method.options:
        first = timed(lambda: demo.update(method=method))
        times = [timed(lambda: demo.update(x=float(x), y=float(y)))
                 for x, y in random_targets(rng, n, 3.6)]
        row(f"demo {method}", first, times, 50)
    print(f"Demo() built (first solve + render) in {built * 1e3:.0f} ms")


def map_rows(n, grid_n, rng):
    from ikteach.pictures import live_map

    header(f"live workspace map (notebook 07): {grid_n} x {grid_n} solve_batch + redraw, "
           f"{max(n // 4, 5)} lambda changes")
    live = live_map.LiveMap(grid_n=grid_n)
    for method in live.method.options:
        first = timed(lambda: live.update(method=method))
        times = [timed(lambda: live.update(damping=float(lam)))
                 for lam in rng.uniform(0.05, 1.5, max(n // 4, 5))]
        row(f"map {method}", first, times, 500)


NEW_KERNEL = """
import json, sys, time
import numpy as np
import ikteach as ik
ik.notebook.compilation_cache()
arm, out = ik.planar_chain([1.0, 1.0, 1.0]), {}
for method in %r:
    t0 = time.perf_counter()
    ik.solve(arm, [2.0, 1.0], np.array([0.1, 0.2, 0.3]), method=method, max_iter=300)
    out[method] = time.perf_counter() - t0
print(json.dumps(out))
"""


def new_kernel_rows():
    """The first solve per method in a new process (a lecturer reopening the notebook), the
    compilation cache warm: JAX's cache alone, and with ikteach's program store."""
    import json
    import os
    import subprocess
    import sys
    import tempfile

    def run(cache, store):
        env = dict(os.environ, IKTEACH_JAX_CACHE=cache, IKTEACH_PROGRAM_STORE=store)
        done = subprocess.run([sys.executable, "-c", NEW_KERNEL % (METHODS,)], env=env,
                              capture_output=True, text=True, check=True)
        return json.loads(done.stdout.splitlines()[-1])

    print("\nfirst solve per method in a new process, cache warm (the process run once before)")
    print(f"| {'method':<8} | {'cold ms':>8} | {'JAX cache ms':>12} | {'+ program store ms':>18} |")
    print(f"|{'-' * 10}|{'-' * 10}|{'-' * 14}|{'-' * 20}|")
    with tempfile.TemporaryDirectory() as jax_only, tempfile.TemporaryDirectory() as store:
        cold = run(jax_only, "off")
        warm = run(jax_only, "off")
        run(store, "on")
        stored = run(store, "on")
    for m in METHODS:
        print(f"| {m:<8} | {1e3 * cold[m]:>8.0f} | {1e3 * warm[m]:>12.0f} | {1e3 * stored[m]:>18.0f} |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=40, help="timed calls per row")
    ap.add_argument("--map-n", type=int, default=128, help="live map grid side")
    ap.add_argument("--skip-demo", action="store_true")
    ap.add_argument("--skip-map", action="store_true")
    ap.add_argument("--skip-new-kernel", action="store_true")
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    print(f"import ikteach: {IMPORT_S * 1e3:.0f} ms (this process, numpy included); "
          f"CPU devices: {CPU_DEVICES}")
    arm = ik.planar_chain([1.0, 1.0, 1.0])
    solve_rows(arm, args.n, rng)
    if not args.skip_demo:
        demo_rows(args.n, rng)
    if not args.skip_map:
        map_rows(args.n, args.map_n, rng)
    if not args.skip_new_kernel:
        new_kernel_rows()


if __name__ == "__main__":
    main()
