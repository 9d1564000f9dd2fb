"""How long each lecture notebook takes to run top to bottom: cold (an empty compilation cache,
what a student's first run costs) and warm (the same cache again: a second run, or a lecture
after the course was opened once; the median and the slowest of WARM_RUNS runs, since one run
on a busy 2-core machine varies by a second). Kernel start-up included.

    .venv/bin/python benchmarks/notebook_times.py [notebooks/0*.ipynb ...] [--cells]

--cells adds, per lecture, every code cell's time cold and warm (nbclient's record of when
the kernel began and ended it), longest first: the cells that make the lecture hall wait.

Goals (issue 47), quiet 2-core machine, empty cache, kernel start-up included: each lecture
< 12 s cold, all ten < 75 s cold and < 50 s warm; no cell over CELL_GOAL_S cold except one the
lecture announces as long (its source holds LONG_CELL).
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import nbformat
from dateutil.parser import isoparse
from nbclient import NotebookClient

from ikteach.course.notebook import CACHE_ENV
from ikteach.course.notebook_header import BLOCK

ROOT = Path(__file__).resolve().parents[1]
COLD_GOAL_S, TOTAL_COLD_GOAL_S, TOTAL_WARM_GOAL_S, CELL_GOAL_S = 12.0, 75.0, 50.0, 4.0
LONG_CELL = "(a long cell"  # a cell's source that announces it: exempt from CELL_GOAL_S
WARM_RUNS = 3


def run(path, cache):
    """One top-to-bottom run in a fresh kernel using this compilation cache: its wall time and
    each code cell's seconds (the kernel's own start and end of the cell)."""
    nb = nbformat.read(path, as_version=4)
    os.environ[CACHE_ENV] = cache  # the kernel inherits it; setup() turns the cache on there
    t0 = time.perf_counter()
    NotebookClient(nb, timeout=900, kernel_name="python3", record_timing=True,
                   resources={"metadata": {"path": str(path.parent)}}).execute(
        stderr=subprocess.DEVNULL)  # the kernel's start-up warnings, not the notebook's output
    wall = time.perf_counter() - t0
    cells = {}
    for k, cell in enumerate(nb.cells):
        when = cell.metadata.get("execution", {})
        if cell.cell_type == "code" and "shell.execute_reply" in when:
            start = when.get("iopub.execute_input", when.get("shell.execute_reply.started"))
            cells[k] = (isoparse(when["shell.execute_reply"]) - isoparse(start)).total_seconds()
    return wall, cells


def first_line(path, k):
    """The cell's first line that is not a comment (what a lecturer recognises it by)."""
    source = BLOCK.sub("", nbformat.read(path, as_version=4).cells[k].source, count=1)
    lines = source.splitlines()
    code = [line for line in lines if line.strip() and not line.lstrip().startswith("#")]
    return (code or lines or [""])[0].strip()[:56]


def long_cells(path, cold, warm):
    """Rows for the per-cell table: cells over a second cold, longest first; a cell over
    CELL_GOAL_S cold that the lecture does not announce (LONG_CELL in its source) says SLOW."""
    nb = nbformat.read(path, as_version=4)
    rows = []
    for k in sorted(cold, key=cold.get, reverse=True):
        if cold[k] < 1.0:
            break
        announced = LONG_CELL in nb.cells[k].source
        flag = "SLOW" if cold[k] > CELL_GOAL_S and not announced else "long" if announced else ""
        rows.append(f"|   cell {k:>3}: {first_line(path, k):<56} | {cold[k]:>6.1f} | "
                    f"{warm.get(k, float('nan')):>6.1f} | {flag:>4} |")
    return rows


def loop_seconds():
    """Seconds for a fixed pure-Python loop (10 million squares): this machine's speed now."""
    t0 = time.perf_counter()
    sum(i * i for i in range(10_000_000))
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("notebooks", nargs="*", type=Path)
    ap.add_argument("--warm-runs", type=int, default=WARM_RUNS)
    ap.add_argument("--cells", action="store_true", help="each lecture's cells over 1 s, cold and warm")
    args = ap.parse_args()
    paths = args.notebooks or sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
    print(f"{os.cpu_count()} CPU cores; python {sys.version.split()[0]}; "
          f"reference loop {loop_seconds():.2f} s")
    print(f"| {'notebook':<36} | {'cold s':>7} | {'warm s':>7} | {'warm max':>8} | {'goal':>9} |")
    print(f"|{'-' * 38}|{'-' * 9}|{'-' * 9}|{'-' * 10}|{'-' * 11}|")
    totals, tables = [0.0, 0.0], []
    for path in paths:
        with tempfile.TemporaryDirectory(prefix="ikteach-cache-") as cache:
            cold, cold_cells = run(path, cache)
            warms = sorted((run(path, cache) for _ in range(args.warm_runs)), key=lambda r: r[0])
        warm, warm_cells = warms[len(warms) // 2]
        totals[0] += cold
        totals[1] += warm
        ok = "ok" if cold <= COLD_GOAL_S else "SLOW"
        print(f"| {path.name:<36} | {cold:>7.1f} | {warm:>7.1f} | {warms[-1][0]:>8.1f} | {ok:>9} |",
              flush=True)
        if args.cells:
            tables.append((path, long_cells(path, cold_cells, warm_cells)))
    total_ok = "ok" if totals[0] < TOTAL_COLD_GOAL_S and totals[1] < TOTAL_WARM_GOAL_S else "SLOW"
    print(f"| {'total':<36} | {totals[0]:>7.1f} | {totals[1]:>7.1f} | {'':>8} | {total_ok:>9} |")
    for path, rows in tables:
        print(f"\n| {path.name + ' (cells over 1 s cold)':<66} | {'cold s':>6} | {'warm s':>6} | "
              f"{'goal':>4} |")
        print(f"|{'-' * 68}|{'-' * 8}|{'-' * 8}|{'-' * 6}|")
        print("\n".join(rows) or f"| {'(none)':<66} | {'':>6} | {'':>6} | {'':>4} |")
    print(f"reference loop {loop_seconds():.2f} s")


if __name__ == "__main__":
    main()
