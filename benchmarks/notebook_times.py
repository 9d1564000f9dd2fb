"""How long each lecture notebook takes to run top to bottom: cold (an empty compilation cache,
what a student's first run costs) and warm (the same cache again: a second run, or a lecture
after the course was opened once; the median and the slowest of WARM_RUNS runs, since one run
on a busy 2-core machine varies by a second). Kernel start-up included.

    .venv/bin/python benchmarks/notebook_times.py [notebooks/0*.ipynb ...]

Goals (issue 38): each lecture notebook < 10 s cold and < 5 s with the cache warm on a quiet
2-core machine, all ten < 45 s cold.
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import nbformat
from nbclient import NotebookClient

from ikteach.course.notebook import CACHE_ENV

ROOT = Path(__file__).resolve().parents[1]
COLD_GOAL_S, WARM_GOAL_S, TOTAL_COLD_GOAL_S = 10.0, 5.0, 45.0
WARM_RUNS = 3


def run_seconds(path, cache):
    """Wall time of one top-to-bottom run in a fresh kernel using this compilation cache."""
    nb = nbformat.read(path, as_version=4)
    os.environ[CACHE_ENV] = cache  # the kernel inherits it; setup() turns the cache on there
    t0 = time.perf_counter()
    NotebookClient(nb, timeout=900, kernel_name="python3",
                   resources={"metadata": {"path": str(path.parent)}}).execute(
        stderr=subprocess.DEVNULL)  # the kernel's start-up warnings, not the notebook's output
    return time.perf_counter() - t0


def loop_seconds():
    """Seconds for a fixed pure-Python loop (10 million squares): this machine's speed now."""
    t0 = time.perf_counter()
    sum(i * i for i in range(10_000_000))
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("notebooks", nargs="*", type=Path)
    ap.add_argument("--warm-runs", type=int, default=WARM_RUNS)
    args = ap.parse_args()
    paths = args.notebooks or sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
    print(f"{os.cpu_count()} CPU cores; python {sys.version.split()[0]}; "
          f"reference loop {loop_seconds():.2f} s")
    print(f"| {'notebook':<36} | {'cold s':>7} | {'warm s':>7} | {'warm max':>8} | {'goal':>9} |")
    print(f"|{'-' * 38}|{'-' * 9}|{'-' * 9}|{'-' * 10}|{'-' * 11}|")
    totals = [0.0, 0.0]
    for path in paths:
        with tempfile.TemporaryDirectory(prefix="ikteach-cache-") as cache:
            cold = run_seconds(path, cache)
            warms = sorted(run_seconds(path, cache) for _ in range(args.warm_runs))
        warm = warms[len(warms) // 2]
        totals[0] += cold
        totals[1] += warm
        ok = "ok" if cold <= COLD_GOAL_S and warm <= WARM_GOAL_S else "SLOW"
        print(f"| {path.name:<36} | {cold:>7.1f} | {warm:>7.1f} | {warms[-1]:>8.1f} | {ok:>9} |",
              flush=True)
    total_ok = "ok" if totals[0] < TOTAL_COLD_GOAL_S else "SLOW"
    print(f"| {'total':<36} | {totals[0]:>7.1f} | {totals[1]:>7.1f} | {'':>8} | {total_ok:>9} |")
    print(f"reference loop {loop_seconds():.2f} s")


if __name__ == "__main__":
    main()
