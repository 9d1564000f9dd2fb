"""Grading time for a class: N students x 6 exercise notebooks, python -m ikteach.course.grade --jobs J.

    .venv/bin/python benchmarks/grade_class.py [--students 30] [--jobs 2] [--exercises 6] [--solved]

Each student folder holds exercises 1..6: the instructor's solution for some, the untouched
template for others (a fixed pattern, so every run grades the same class; --solved: every
notebook the solution, the honest class of the grader's issues). Prints the wall
time (start-up, probe and self-check included), seconds per notebook and the score totals
(which the pattern fixes), and a reference loop's time before and after (this shared 2-core
machine's speed drifts: compare runs only with similar loop times). `--label` names the row,
e.g. to compare two checkouts: PYTHONPATH=/other/checkout ... --label before.
"""
import argparse
import csv
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOLUTIONS = ROOT / "instructor" / "solutions"
TEMPLATES = ROOT / "notebooks" / "exercises"


def build_class(folder, students, exercises, solved_only=False):
    """Student s gets the solution of exercise e when (s + e) % 3 != 0, else the template."""
    books = sorted(p.name for p in SOLUTIONS.glob("*.ipynb"))[:exercises]
    solved = 0
    for s in range(students):
        student = folder / f"student{s:02d}"
        student.mkdir(parents=True)
        for e, name in enumerate(books):
            source = SOLUTIONS if (s + e) % 3 or solved_only else TEMPLATES
            solved += source is SOLUTIONS
            shutil.copy(source / name, student / name)
    return len(books), solved


def loop_seconds():
    """Seconds for a fixed pure-Python loop (10 million squares): this machine's speed now."""
    t0 = time.perf_counter()
    sum(i * i for i in range(10_000_000))
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--students", type=int, default=30)
    ap.add_argument("--exercises", type=int, default=6)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--label", default="")
    ap.add_argument("--solved", action="store_true", help="every notebook the solution")
    args = ap.parse_args()
    loop_before = loop_seconds()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        n_books, solved = build_class(tmp / "class", args.students, args.exercises,
                                       args.solved)
        out = tmp / "out" / "grades.csv"
        t0 = time.perf_counter()
        run = subprocess.run([sys.executable, "-m", "ikteach.course.grade", str(tmp / "class"),
                              "--out", str(out), "--jobs", str(args.jobs)],
                             capture_output=True, text=True, cwd=tmp)
        wall = time.perf_counter() - t0
        if run.returncode:
            sys.exit(run.stderr[-2000:])
        rows = list(csv.DictReader(out.open()))
    notebooks = args.students * n_books
    total = sum(float(r["total"]) for r in rows)
    print("| run        | students | notebooks | jobs | wall          | s per notebook | "
          "marks (expected) | loop s before/after |")
    print("|------------|----------|-----------|------|---------------|----------------|"
          "------------------|---------------------|")
    print(f"| {args.label:<10} | {args.students:8d} | {notebooks:9d} | {args.jobs:4d} | "
          f"{int(wall // 60):3d} min {wall % 60:4.1f} s | {wall / notebooks:14.2f} | "
          f"{total:>8.0f} ({solved * 10}) | {loop_before:9.2f} / {loop_seconds():.2f} |")


if __name__ == "__main__":
    main()
