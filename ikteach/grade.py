"""Grade the students' exercise notebooks.

    python -m ikteach.grade SUBMISSIONS_DIR --out grades.csv [--feedback DIR] [--timeout S]
                            [--jobs N]

SUBMISSIONS_DIR holds one folder per student (the folder name is the student), each with that
student's exercise notebooks (NN_name.ipynb, as handed out). Every notebook runs in its own
kernel process, in a fresh temporary working directory holding only a copy of it, under a time
limit for the whole notebook. After the student's cells the grader runs its own cell, which
calls ik.check on the student's functions (each call under its own time limit) and hands the
score back through a one-time token. The notebook's own outputs are never trusted for marks.

Writes one CSV row per student (ex1..ex6 and total) and a feedback file per student
(FEEDBACK/<student>.txt, by default a `feedback` folder next to the CSV). A submission that
raises, loops forever, kills its kernel or deletes files in its working directory loses only
its own marks; the grader finishes and says what happened in the feedback.
"""
import argparse
import csv
import json
import logging
import re
import secrets
import shutil
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

NOTEBOOK_TIMEOUT = 120.0  # seconds for all of a student's cells
GRADE_TIMEOUT = 180.0     # seconds for the grader's own cell
EXERCISE_NUMBERS = range(1, 8)
POINTS = 10

_GRADE_CELL = """\
import json as _ikteach_json
import ikteach.check as _ikteach_check
_ikteach_verdict = _ikteach_check.grade({number}, globals())
print({token!r} + _ikteach_json.dumps({{
    "score": _ikteach_verdict.score, "max": _ikteach_verdict.max_score,
    "status": _ikteach_verdict.status, "message": _ikteach_verdict.message}}))
"""


def exercise_number(path, book):
    """The exercise a notebook answers: its metadata (ikteach.exercise), else NN_ in its name."""
    meta = book.get("metadata", {}).get("ikteach", {})
    number = meta.get("exercise") if isinstance(meta, dict) else None
    if isinstance(number, int) and number in EXERCISE_NUMBERS:
        return number
    match = re.match(r"(\d+)_", Path(path).name)
    if match and int(match.group(1)) in EXERCISE_NUMBERS:
        return int(match.group(1))
    return None


def _error_lines(book, upto):
    """'cell k raised Name: value' for the student's cells that ended in an error."""
    lines = []
    for index, cell in enumerate(book.cells[:upto]):
        for out in cell.get("outputs", []) if cell.cell_type == "code" else []:
            if out.get("output_type") == "error":
                value = str(out.get("evalue", "")).splitlines()
                lines.append(f"cell {index + 1} raised {out.get('ename')}"
                             f"{': ' + value[0][:200] if value and value[0] else ''}")
    return lines


def grade_notebook(path, timeout=NOTEBOOK_TIMEOUT, grade_timeout=GRADE_TIMEOUT):
    """Run one notebook in its own kernel and temp dir; returns a dict:
    exercise, score, max, status, message, notes (list of what went wrong on the way)."""
    import nbformat
    from nbclient import NotebookClient
    from nbclient.exceptions import CellTimeoutError, DeadKernelError

    logging.getLogger("asyncio").setLevel(logging.CRITICAL)  # nbclient noise after a timeout
    path = Path(path)
    result = {"file": path.name, "exercise": None, "score": 0.0, "max": float(POINTS),
              "status": "not graded", "message": "", "notes": []}
    try:
        book = nbformat.read(path, as_version=4)
    except Exception as exc:  # not a notebook at all
        result["message"] = f"could not read the notebook: {type(exc).__name__}: {exc}"
        return result
    number = exercise_number(path, book)
    result["exercise"] = number
    if number is None:
        result["message"] = ("not an exercise notebook (no ikteach exercise number in its "
                             "metadata or name)")
        return result

    token = f"IKTEACH-GRADE-{secrets.token_hex(12)}:"
    student_cells = len(book.cells)
    book.cells.append(nbformat.v4.new_code_cell(_GRADE_CELL.format(number=number, token=token)))
    work = Path(tempfile.mkdtemp(prefix="ikteach-grade-"))
    try:
        shutil.copy(path, work / path.name)
        client = NotebookClient(book, timeout=timeout, kernel_name="python3",
                                allow_errors=True, interrupt_on_timeout=False,
                                shutdown_kernel="immediate", record_timing=False,
                                resources={"metadata": {"path": str(work)}})
        deadline = time.monotonic() + timeout
        with client.setup_kernel():
            for index, cell in enumerate(book.cells):
                if cell.cell_type != "code":
                    continue
                grading = index == student_cells
                if not grading and _only_checks(cell.source):
                    continue  # the grader runs the checks itself, once, in its own cell
                remaining = deadline - time.monotonic()
                if not grading and remaining <= 0:
                    result["notes"].append(f"time limit of {timeout:g} s reached: cells from "
                                           f"cell {index + 1} on were not run")
                    continue
                client.timeout = int(max(1, grade_timeout if grading else remaining))
                try:
                    client.execute_cell(cell, index)
                except CellTimeoutError:
                    if grading:
                        result["notes"].append("the checks did not finish in time")
                        break
                    result["notes"].append(f"cell {index + 1} did not finish within the "
                                           f"notebook's time limit ({timeout:g} s)")
                    _interrupt(client)
                except DeadKernelError:
                    result["notes"].append(f"the kernel died in cell {index + 1}")
                    break
        result["notes"][:0] = _error_lines(book, student_cells)
        grade = _read_grade(book.cells[-1], token)
        if grade is None:
            result["message"] = "no grade: the checks could not run to the end"
        else:
            result.update(score=float(grade["score"]), max=float(grade["max"]),
                          status=grade["status"], message=grade["message"])
    except Exception as exc:  # the grader's own failure on this notebook: report, go on
        result["message"] = f"could not run the notebook: {type(exc).__name__}: {exc}"
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return result


def _only_checks(source):
    """A cell that only calls ik.check.<name>(...) (the template's check cells)."""
    lines = [l for l in source.splitlines() if l.strip() and not l.strip().startswith("#")]
    return bool(lines) and all(re.match(r"\s*ik\.check\.\w+\(.*\)\s*$", l) for l in lines)


def _interrupt(client):
    """Interrupt a busy kernel (the grader's cell still runs after a timed-out cell)."""
    from jupyter_core.utils import ensure_async, run_sync

    try:
        run_sync(ensure_async)(client.km.interrupt_kernel())
    except Exception:
        pass
    time.sleep(1.0)


def _read_grade(cell, token):
    """The grade the grading cell printed after `token` (stdout may arrive in several pieces)."""
    text = "".join(out.get("text", "") for out in cell.get("outputs", [])
                   if out.get("output_type") == "stream" and out.get("name") == "stdout")
    for line in text.splitlines():
        if line.startswith(token):
            try:
                return json.loads(line[len(token):])
            except ValueError:
                return None
    return None


def _students(submissions):
    submissions = Path(submissions)
    if not submissions.is_dir():
        raise ValueError(f"SUBMISSIONS_DIR: expected a folder of student folders, "
                         f"got {str(submissions)!r}")
    return sorted(p for p in submissions.iterdir() if p.is_dir() and not p.name.startswith("."))


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
              grade_timeout=GRADE_TIMEOUT, log=print):
    """Grade every student folder; write the CSV and the feedback files; return the rows."""
    students = _students(submissions)
    out = Path(out)
    feedback = Path(feedback) if feedback else out.parent / "feedback"
    feedback.mkdir(parents=True, exist_ok=True)
    jobs_list = [(s.name, nb) for s in students for nb in sorted(s.glob("*.ipynb"))]
    if jobs > 1:
        with ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("spawn")) as pool:
            futures = [pool.submit(grade_notebook, nb, timeout, grade_timeout) for _, nb in jobs_list]
            outcomes = [f.result() for f in futures]
    else:
        outcomes = [grade_notebook(nb, timeout, grade_timeout) for _, nb in jobs_list]
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
    parser = argparse.ArgumentParser(prog="python -m ikteach.grade",
                                     description="Grade exercise notebooks, one folder per "
                                                 "student.")
    parser.add_argument("submissions", metavar="SUBMISSIONS_DIR")
    parser.add_argument("--out", required=True, help="the CSV to write (one row per student)")
    parser.add_argument("--feedback", default=None,
                        help="folder for <student>.txt (default: feedback/ next to --out)")
    parser.add_argument("--timeout", type=float, default=NOTEBOOK_TIMEOUT,
                        help="seconds allowed for one notebook's cells (default %(default)s)")
    parser.add_argument("--grade-timeout", type=float, default=GRADE_TIMEOUT,
                        help="seconds allowed for the grader's checks (default %(default)s)")
    parser.add_argument("--jobs", type=int, default=1, help="notebooks graded at once")
    args = parser.parse_args(argv)
    try:
        rows = grade_all(args.submissions, args.out, args.feedback, args.timeout, args.jobs,
                         args.grade_timeout)
    except ValueError as exc:
        parser.error(str(exc))
    print(f"wrote {args.out}: {len(rows)} student(s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
