"""Grade the students' exercise notebooks.

    python -m ikteach.course.grade SUBMISSIONS_DIR --out grades.csv [--feedback DIR] [--timeout S]
                            [--jobs N] [--memory-mb M] [--no-bwrap]
    python -m ikteach.course.grade --gradescope OUT.zip      (a Gradescope autograder bundle)

SUBMISSIONS_DIR holds one folder per student (the folder name is the student), each with that
student's exercise notebooks (NN_name.ipynb, as handed out). For each notebook:

1. its cells run in a kernel in a sandbox (ikteach.course.grading.sandbox: own temporary folder and
   HOME, resource limits, and with bubblewrap no network, read-only file system, solutions and
   other students hidden), for its errors and notes only - nothing it prints counts;
2. the student's functions are taken from the notebook's source (top-level imports,
   definitions and assignments, by the AST) into a second sandboxed process, and ik.check runs
   in the grader's own process, calling them there through a pipe (each call under its time
   limit). So nothing a notebook does to modules, builtins, stdout or files changes a score.

Writes one CSV row per student (ex1..ex6 and total) and a feedback file per student
(FEEDBACK/<student>.txt, by default a `feedback` folder next to the CSV); the log starts with
what the sandbox enforces and what it cannot on this machine.
"""
import argparse
import csv
import json
import os
import re
import select
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

from .exercises import ANSWER_PLACEHOLDER

NOTEBOOK_TIMEOUT = 120.0  # seconds for all of a student's cells
GRADE_TIMEOUT = 180.0     # kept for the command line; each check call has its own limit
EXERCISE_NUMBERS = range(1, 8)
POINTS = 10
MAX_NOTEBOOK_BYTES = 20 << 20
RUNNER = Path(__file__).with_name("grading") / "run_notebook.py"
INSTRUCTOR = Path(__file__).resolve().parents[2] / "instructor"  # the solutions: hidden


def exercise_number(path, book):
    """The exercise a notebook answers: its metadata (ikteach.exercise), else NN_ in its name."""
    meta = book.get("metadata") if isinstance(book, dict) else None
    meta = meta.get("ikteach") if isinstance(meta, dict) else None
    number = meta.get("exercise") if isinstance(meta, dict) else None
    if isinstance(number, int) and number in EXERCISE_NUMBERS:
        return number
    match = re.match(r"(\d+)_", Path(path).name)
    if match and int(match.group(1)) in EXERCISE_NUMBERS:
        return int(match.group(1))
    return None


def _read_book(path):
    """The notebook as a dict, or a message saying why it is not one."""
    if path.stat().st_size > MAX_NOTEBOOK_BYTES:
        return None, f"the notebook is larger than {MAX_NOTEBOOK_BYTES >> 20} MB"
    try:
        book = json.loads(path.read_text(encoding="utf-8", errors="replace"))
    except ValueError as exc:
        return None, f"could not read the notebook: it is not JSON ({exc})"
    if not isinstance(book, dict) or not isinstance(book.get("cells"), list):
        return None, "could not read the notebook: no list of cells in it"
    return book, None


def _run_cells(path, work, sandbox, timeout):
    """Run the notebook's cells in the sandbox; (error lines, notes) from the runner's report."""
    run_dir = work / "run"
    run_dir.mkdir()
    copy = run_dir / path.name
    shutil.copy(path, copy)
    read_end, write_end = os.pipe()
    try:
        process = sandbox.start([sys.executable, str(RUNNER), str(copy), f"{timeout:g}",
                                 str(write_end)], run_dir, pass_fds=(write_end,),
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
    finally:
        os.close(write_end)
    try:
        status = process.wait(timeout + 60)
    finally:
        process.end()
    report = b""
    with os.fdopen(read_end, "rb") as pipe:
        while select.select([pipe], [], [], 0)[0]:
            chunk = os.read(pipe.fileno(), 1 << 16)
            if not chunk or len(report) > 1 << 20:
                break
            report += chunk
    try:
        data = json.loads(report.decode(errors="replace").splitlines()[0])
        return [str(e)[:400] for e in data["errors"]][:30], [str(n)[:400] for n in data["notes"]][:10]
    except (ValueError, IndexError, KeyError, TypeError):
        why = "it ran past its time limit" if status is None else f"exit status {status}"
        return [], [f"the notebook's run ended without a report ({why}: a crash, or a CPU, "
                    "memory or file-size limit)"]


def _answer_text(book):
    """The student's written answer (Markdown cells tagged `answer`), for the instructor."""
    texts = []
    for cell in (c for c in book["cells"] if isinstance(c, dict)):
        meta = cell.get("metadata")
        tags = meta.get("tags") if isinstance(meta, dict) else None
        if cell.get("cell_type") == "markdown" and isinstance(tags, list) and "answer" in tags:
            source = cell.get("source", "")
            text = "".join(source) if isinstance(source, list) else str(source)
            if text.strip() != ANSWER_PLACEHOLDER:  # the template's, untouched
                texts.append(text)
    return "\n".join(texts)[:4000]


def _check(number, book, work, sandbox):
    """The verdict from ik.check in this process, on the student's functions in a worker."""
    from . import check
    from .grading.extract import code_cells
    from .grading.remote import ProcessEnded, Worker

    check_dir = work / "check"
    check_dir.mkdir()
    worker = Worker(code_cells(book), sandbox, check_dir)
    try:
        try:
            worker.start()
        except (ProcessEnded, ValueError) as exc:  # died, hung, or answered garbage
            return None, [f"your code could not be loaded for the checks: {exc}"]
        namespace = {name: worker.function(name) for name in worker.names}
        return check.grade(number, namespace), worker.notes
    finally:
        worker.end()


def grade_notebook(path, timeout=NOTEBOOK_TIMEOUT, grade_timeout=GRADE_TIMEOUT, sandbox=None):
    """Grade one notebook; returns a dict: file, exercise, score, max, status, message,
    notes (what went wrong on the way), answer (the written answer, if any)."""
    from .grading.sandbox import Sandbox

    sandbox = sandbox or Sandbox()
    path = Path(path)
    result = {"file": path.name, "exercise": None, "score": 0.0, "max": float(POINTS),
              "status": "not graded", "message": "", "notes": [], "answer": ""}
    book, problem = _read_book(path)
    if book is None:
        result["message"] = problem
        return result
    number = exercise_number(path, book)
    result["exercise"] = number
    if number is None:
        result["message"] = ("not an exercise notebook (no ikteach exercise number in its "
                             "metadata or name)")
        return result
    work = Path(tempfile.mkdtemp(prefix="nb-", dir=sandbox.work_root))
    try:
        result["answer"] = _answer_text(book)
        errors, notes = _run_cells(path, work, sandbox, timeout)
        verdict, check_notes = _check(number, book, work, sandbox)
        result["notes"] = errors + notes + check_notes
        if verdict is None:
            result["message"] = "no grade: your code could not be loaded for the checks"
        else:
            result.update(score=float(verdict.score), max=float(verdict.max_score),
                          status=verdict.status, message=verdict.message)
    except Exception as exc:  # the grader's own failure on this notebook: report, go on
        result["message"] = f"could not grade the notebook: {type(exc).__name__}: {exc}"
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return result


def _students(submissions):
    if submissions is None or not Path(submissions).is_dir():
        raise ValueError(f"SUBMISSIONS_DIR: expected a folder of student folders, "
                         f"got {str(submissions)!r}")
    return sorted(p for p in Path(submissions).iterdir() if p.is_dir() and not p.name.startswith("."))


def _feedback_text(student, results):
    lines = [f"Feedback for {student}", ""]
    by_number = {r["exercise"]: r for r in results if r["exercise"] is not None}
    for number in EXERCISE_NUMBERS:
        r = by_number.get(number)
        if r is None:
            lines.append(f"Exercise {number}: 0/{POINTS} - no notebook submitted")
            continue
        lines.append(f"Exercise {number} ({r['file']}): {r['score']:g}/{r['max']:g}")
        for text in r["message"].splitlines():
            lines.append(f"  {text}")
        for note in r["notes"]:
            lines.append(f"  note: {note}")
        if r.get("answer", "").strip():
            lines.append("  your written answer (not marked by the checker; read by the "
                         "instructor):")
            lines += [f"    | {text}" for text in r["answer"].strip().splitlines()]
    for r in results:
        if r["exercise"] is None:
            lines.append(f"{r['file']}: {r['message']}")
    total = sum(r["score"] for r in by_number.values())
    lines += ["", f"Total: {total:g}/{POINTS * len(EXERCISE_NUMBERS)}"]
    return "\n".join(lines) + "\n"


def _best(results):
    """One result per exercise (the best, if a student handed in two for the same one)."""
    best = {}
    for r in results:
        number = r["exercise"]
        if number is not None and (number not in best or r["score"] > best[number]["score"]):
            best[number] = r
    return best


def grade_all(submissions, out, feedback=None, timeout=NOTEBOOK_TIMEOUT, jobs=1,
              grade_timeout=GRADE_TIMEOUT, log=print, limits=None, bwrap=None, collect=None):
    """Grade every student folder; write the CSV and the feedback files; return the rows
    (`collect`: a list that receives every notebook's result dict)."""
    from .grading.sandbox import Limits, Sandbox

    students = _students(submissions)
    out = Path(out)
    feedback = Path(feedback) if feedback else out.parent / "feedback"
    feedback.mkdir(parents=True, exist_ok=True)
    hidden = [submissions, out.parent, feedback, INSTRUCTOR]
    sandbox = Sandbox(hidden, limits or Limits(), bwrap=bwrap)
    enforced, not_enforced = sandbox.report()
    log("sandbox: enforced:")
    for line in enforced:
        log(f"  + {line}")
    log("sandbox: NOT enforced:")
    for line in not_enforced:
        log(f"  - {line}")
    jobs_list = [(s.name, nb) for s in students for nb in sorted(s.glob("*.ipynb"))]
    try:
        if jobs > 1:
            with ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("spawn")) as pool:
                futures = [pool.submit(grade_notebook, nb, timeout, grade_timeout, sandbox)
                           for _, nb in jobs_list]
                outcomes = [f.result() for f in futures]
        else:
            outcomes = [grade_notebook(nb, timeout, grade_timeout, sandbox) for _, nb in jobs_list]
    finally:
        sandbox.close()
    if collect is not None:
        collect.extend(outcomes)
    per_student = {s.name: [] for s in students}
    for (student, _), result in zip(jobs_list, outcomes):
        per_student[student].append(result)
        log(f"{student}/{result['file']}: {result['score']:g}/{result['max']:g} {result['status']}")

    rows = []
    for student, results in per_student.items():
        best = _best(results)
        row = {"student": student}
        for number in EXERCISE_NUMBERS:
            row[f"ex{number}"] = best[number]["score"] if number in best else 0.0
        row["total"] = sum(row[f"ex{n}"] for n in EXERCISE_NUMBERS)
        rows.append(row)
        (feedback / f"{student}.txt").write_text(_feedback_text(student, results))
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=["student"]
                                + [f"ex{n}" for n in EXERCISE_NUMBERS] + ["total"])
        writer.writeheader()
        for row in rows:
            writer.writerow({k: (f"{v:g}" if isinstance(v, float) else v) for k, v in row.items()})
    return rows


def main(argv=None):
    from .grading.sandbox import Limits

    parser = argparse.ArgumentParser(prog="python -m ikteach.course.grade",
                                     description="Grade exercise notebooks, one folder per "
                                                 "student.")
    parser.add_argument("submissions", metavar="SUBMISSIONS_DIR", nargs="?")
    parser.add_argument("--out", help="the CSV to write (one row per student)")
    parser.add_argument("--feedback", default=None,
                        help="folder for <student>.txt (default: feedback/ next to --out)")
    parser.add_argument("--timeout", type=float, default=NOTEBOOK_TIMEOUT,
                        help="seconds allowed for one notebook's cells (default %(default)s)")
    parser.add_argument("--grade-timeout", type=float, default=GRADE_TIMEOUT,
                        help="seconds allowed for the grader's checks (default %(default)s)")
    parser.add_argument("--jobs", type=int, default=1, help="notebooks graded at once")
    parser.add_argument("--memory-mb", type=int, default=Limits.memory_mb,
                        help="address space of one student process (default %(default)s)")
    parser.add_argument("--cpu-s", type=int, default=Limits.cpu_seconds,
                        help="CPU seconds of one student process (default %(default)s)")
    parser.add_argument("--no-bwrap", action="store_true",
                        help="do not use bubblewrap even where it works")
    parser.add_argument("--gradescope", metavar="OUT.zip",
                        help="write a Gradescope autograder bundle instead of grading")
    args = parser.parse_args(argv)
    if args.gradescope:
        from .grading.gradescope import bundle
        print(f"wrote {bundle(args.gradescope)}")
        return 0
    if not args.out:
        parser.error("--out is required (the CSV to write)")
    limits = Limits(cpu_seconds=args.cpu_s, memory_mb=args.memory_mb)
    try:
        rows = grade_all(args.submissions, args.out, args.feedback, args.timeout, args.jobs,
                         args.grade_timeout, limits=limits,
                         bwrap=False if args.no_bwrap else None)
    except ValueError as exc:
        parser.error(str(exc))
    print(f"wrote {args.out}: {len(rows)} student(s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
