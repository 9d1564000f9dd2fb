"""Where a notebook's grading time goes: N students x the 7 instructor solutions, graded in this
process (--jobs 1), each phase timed around the grader's own functions.

    IKTEACH_JAX_CACHE=$(mktemp -d) .venv/bin/python benchmarks/grade_phases.py [--students 3]

Run it twice with the same IKTEACH_JAX_CACHE: cold, then warm (the checks' compiled programs
loaded). Phases, which overlap: the probe and the self-check (once per run); fork server starts
(bubblewrap, Python, JAX and ikteach imported: one per exercise, inside the first fingerprints
job of each); the fingerprints job; the notebook's job (fork and cells); the checks (in this
process, the student's calls through the pipe, whose round trips are shown apart); job ends.
"""
import argparse
import collections
import functools
import shutil
import tempfile
import time
from pathlib import Path

from ikteach.course import check, grade
from ikteach.course.grading import remote, sandbox, selfcheck, servers

SOLUTIONS = Path(__file__).resolve().parents[1] / "instructor" / "solutions"
PHASES = [(sandbox.Sandbox, "verify", "probe"), (selfcheck, "run", "self-check"),
          (servers.Server, "__init__", "fork server start"),
          (remote.Worker, "held", "fingerprints job"),
          (remote.Worker, "start", "notebook job: fork and cells"),
          (check, "grade", "checks"), (remote.Worker, "call", "  their calls (round trips)"),
          (servers.Job, "end", "job ends")]
seconds, counts = collections.Counter(), collections.Counter()


def timed(owner, name, label):
    fn = getattr(owner, name)

    @functools.wraps(fn)
    def run(*args, **kwargs):
        start = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            seconds[label] += time.perf_counter() - start
            counts[label] += 1
    setattr(owner, name, run)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--students", type=int, default=3)
    args = ap.parse_args()
    for owner, name, label in PHASES:
        timed(owner, name, label)
    books = args.students * len(list(SOLUTIONS.glob("*.ipynb")))
    with tempfile.TemporaryDirectory() as tmp:
        for s in range(args.students):
            shutil.copytree(SOLUTIONS, Path(tmp) / "class" / f"student{s:02d}")
        start = time.perf_counter()
        rows = grade.grade_all(Path(tmp) / "class", Path(tmp) / "out.csv", seed=1,
                               log=lambda line: None)
        wall = time.perf_counter() - start
    marks = sum(float(r["total"]) for r in rows)
    print(f"{books} notebooks in {wall:.1f} s ({wall / books:.2f} s a notebook), "
          f"{marks:g} of {books * 10} marks")
    print("| phase                                   | calls |      s | s per notebook |")
    print("|-----------------------------------------|-------|--------|----------------|")
    for _, _, label in PHASES:
        print(f"| {label:<39} | {counts[label]:5d} | {seconds[label]:6.1f} | "
              f"{seconds[label] / books:14.3f} |")

if __name__ == "__main__":
    main()
