"""How many XLA programs each lecture's Run All needs, and what they cost: compiled with an empty
cache (a student's first run on Colab or Binder), then again with the cache that run filled
(a second run, or a run after `ikteach warm`). Kernel start-up included in the wall times.

    .venv/bin/python benchmarks/compile_counts.py [notebooks/0*.ipynb ...]

The program counts are deterministic; the tests hold each lecture to its budget
(ikteach/course/warm.py: BUDGETS) on nbval's run of it (tests/lecture_budgets.py); the times
are this machine's, now.
"""
import argparse
import sys
import tempfile
from pathlib import Path

from ikteach.course.warm import BUDGETS, ROOT, count_programs, lectures


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("notebooks", nargs="*", type=Path)
    ap.add_argument("--cold-only", action="store_true", help="skip the second (warm) run")
    ap.add_argument("--exercises", action="store_true",
                    help="the instructor's solutions too (each runs its exercise's checks)")
    args = ap.parse_args()
    paths = args.notebooks or lectures()
    if args.exercises:
        paths += sorted(ROOT.glob("instructor/solutions/*.ipynb"))
    print(f"| {'notebook':<30} | {'programs':>8} | {'budget':>6} | {'compile s':>9} | "
          f"{'trace s':>7} | {'cold s':>6} | {'warm s':>6} | {'loaded':>6} |")
    print(f"|{'-' * 32}|{'-' * 10}|{'-' * 8}|{'-' * 11}|{'-' * 9}|{'-' * 8}|{'-' * 8}|{'-' * 8}|")
    total = {"programs": 0, "compile_s": 0.0, "cold": 0.0, "warm": 0.0}
    for path in paths:
        with tempfile.TemporaryDirectory(prefix="ikteach-cache-") as cache:
            cold = count_programs(path, cache)
            warm = None if args.cold_only else count_programs(path, cache)
        budget = BUDGETS.get(path.stem, "-") if path.parent.name == "notebooks" else "-"
        warm_s = f"{warm['wall_s']:6.1f}" if warm else "     -"
        loaded = f"{warm['loaded']:6d}" if warm else "     -"
        print(f"| {path.stem:<30} | {cold['programs']:>8} | {budget:>6} | {cold['compile_s']:>9.1f} | "
              f"{cold['trace_s']:>7.1f} | {cold['wall_s']:>6.1f} | {warm_s} | {loaded} |", flush=True)
        total["programs"] += cold["programs"]
        total["compile_s"] += cold["compile_s"]
        total["cold"] += cold["wall_s"]
        total["warm"] += warm["wall_s"] if warm else 0.0
    print(f"| {'total':<30} | {total['programs']:>8} | {'':>6} | {total['compile_s']:>9.1f} | "
          f"{'':>7} | {total['cold']:>6.1f} | {total['warm']:>6.1f} | {'':>6} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
