"""Grade the students' exercise notebooks.

    python -m ikteach.course.grade SUBMISSIONS_DIR --out grades.csv [--jobs N] [...: --help]
    python -m ikteach.course.grade --gradescope OUT.zip      (a Gradescope autograder bundle)

SUBMISSIONS_DIR holds one folder per student (the folder name is the student) with that
student's exercise notebooks, read as untrusted (grading/submissions.py: a bad entry costs only
its student's marks, with a reason in the CSV's `notes`), each taken for an exercise by what it
does (grading/recognise.py). Each notebook is one job in a sandbox (grading/sandbox.py; where
none works the grader refuses unless --no-sandbox), a fresh child of a fork server no student
code ran in (grading/forkserver.py), whose copy of ikteach has that exercise's answers as stubs
that raise (grading/reference.py):

1. its code cells run in IPython's shell (grading/cells.py) within --timeout CPU s; their errors
   are notes, nothing they print counts;
2. ik.check runs in the grader's own process on hidden cases (the check cell's, and as many
   drawn from a seed logged at the start: --seed repeats a run), calling the functions the
   cells left through a pipe (grading/remote.py), each call limited in CPU seconds of the job
   (a machine's load changes no mark), all of them within --grade-timeout. A graded name that
   is not a function written in the notebook gets 0 (grading/own_code.py); a notebook that a
   check's time limit stopped is graded once more from a clean start before that counts.

Before anyone is graded the sandbox is probed and a known-good answer must get full marks
(grading/selfcheck.py), or the grader stops with a non-zero exit status. Writes one CSV row per
student (ex1..ex7, total, sandbox, notes, copied) and a feedback file per student
(grading/report.py; by default in a `feedback` folder next to the CSV)."""
import argparse
import collections
import dataclasses
import functools
import os
import secrets
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

from .exercises import ANSWER_PLACEHOLDER
from .grading.recognise import exercise_number, identify  # noqa: F401 (grade.identify)
from .grading.report import POINTS, RERUN, labels, write_results
from .grading.submissions import notebooks, read_notebook, students, text

NOTEBOOK_TIMEOUT = 120.0  # CPU seconds for all of a student's cells
GRADE_TIMEOUT = 180.0     # seconds for a notebook's checks: every call
GRACE = 15.0              # the fork server's kill comes first; then the grader ends it all
MAX_NOTEBOOKS = 3 * 7      # notebooks graded per student (the rest: a note)
INSTRUCTOR = Path(__file__).resolve().parents[2] / "instructor"  # the solutions: hidden

__all__ = ["grade_all", "grade_notebook", "grade_book", "exercise_number", "main"]


def _answer_text(book):
    """The student's written answer (Markdown cells tagged `answer`), for the instructor."""
    texts = []
    for cell in (c for c in book["cells"] if isinstance(c, dict)):
        meta = cell.get("metadata")
        tags = meta.get("tags") if isinstance(meta, dict) else None
        if cell.get("cell_type") == "markdown" and isinstance(tags, list) and "answer" in tags:
            source = cell.get("source", "")
            text_ = "".join(map(str, source)) if isinstance(source, list) else str(source)
            if text_.strip() != ANSWER_PLACEHOLDER:  # the template's, untouched
                texts.append(text_)
    return "\n".join(texts)[:4000]


def _run(number, book, sandbox, timeout, grade_timeout, seed=None):
    """(verdict or None, notes, copied, stopped): the notebook's cells and then ik.check's
    calls in one job, the verdict computed here on the hidden cases drawn from `seed`; notes:
    the cells' errors and what went wrong; stopped: a time limit of the checks ended a call."""
    from . import check
    from .check.verdicts import CPU_CLOCK
    from .grading import reference
    from .grading.extract import code_cells
    from .grading.remote import ProcessEnded, Worker

    module = check.EXERCISES[number]
    worker = Worker(code_cells(book), sandbox, exercise=number, graded=module.FUNCTIONS,
                    limit=grade_timeout, timeout=timeout)
    clock = CPU_CLOCK.set(worker.cpu_seconds)
    try:
        held = worker.held()  # before the notebook's job: a server runs one at a time
        try:
            worker.start()
        except (ProcessEnded, ValueError) as exc:  # died, hung, or answered garbage
            return (None, worker.errors + (worker.notes or [f"nothing could be graded: {exc}"]),
                    [], False)
        notes = worker.errors + worker.notes
        # reported, never scored: the cells' source, fingerprinted where no student code ran
        copied = reference.copied(held, reference.reference_fingerprints(module.REFERENCES))
        if worker.foreign:  # a graded name bound to ikteach's (or anyone's) code: no marks
            return (check.registry.refuse(number, " ".join(worker.foreign.values())), notes,
                    copied, False)
        namespace = {name: worker.function(name) for name in worker.names}
        return check.grade(number, namespace, seed=seed), notes, copied, worker.stopped
    finally:
        CPU_CLOCK.reset(clock)
        worker.end()


def _result(name, number=None, message=""):
    return {"file": text(name), "exercise": number, "how": None, "score": 0.0, "max": float(POINTS),
            "status": "not graded", "message": message, "notes": [], "answer": "", "copied": []}


def grade_book(name, book, timeout=NOTEBOOK_TIMEOUT, grade_timeout=GRADE_TIMEOUT,
               sandbox=None, seed=None):
    """Grade one notebook (a dict) on the hidden cases drawn from `seed` (None: a fresh secret
    one); returns a dict: file, exercise, how (how the exercise was recognised), score, max,
    status, message, notes (what went wrong on the way), answer (the written answer, if any),
    copied (functions whose code is ikteach's answer: for the instructor), seed, seconds."""
    from .grading import servers
    from .grading.sandbox import Sandbox
    from .notebook import compilation_cache

    sandbox = sandbox or Sandbox()  # raises SandboxUnavailable where there is none
    compilation_cache()  # the checks' compiled programs: loaded, not compiled, from a 2nd run
    number, how = identify(name, book)
    result = dict(_result(name, number), how=how)
    result["seed"] = seed = secrets.randbits(63) if seed is None else int(seed)
    if number is None:
        result["message"] = ("not an exercise notebook (no ikteach exercise in its metadata, "
                             "its functions or its name)")
        return result
    started = time.monotonic()
    try:
        result["answer"] = _answer_text(book)
        verdict, notes, result["copied"], stopped = _run(number, book, sandbox, timeout,
                                                         grade_timeout, seed)
        if stopped:  # the grader's own time limit: confirmed, from a clean start, before it counts
            servers.close_all()
            again, notes_again, _, _ = _run(number, book, sandbox, timeout, grade_timeout, seed)
            if again is not None:
                verdict, notes = again, notes_again + [RERUN]
        result["notes"] = notes[:40]
        if verdict is None:
            result["message"] = "no grade: your code could not be loaded for the checks"
        else:
            result.update(score=float(verdict.score), max=float(verdict.max_score),
                          status=verdict.status, message=verdict.message)
    except Exception as exc:  # the grader's own failure on this notebook: report, go on
        result["message"] = f"could not grade the notebook: {type(exc).__name__}: {exc}"
    finally:
        result["seconds"] = time.monotonic() - started
    return result


def grade_notebook(path, timeout, grade_timeout, sandbox, problem=None, seed=None):
    """Grade one notebook file (read as untrusted: see grading/submissions.py) in `sandbox`
    (`problem`: why it is not read, found when it was listed)."""
    path = Path(path)
    number = exercise_number(path, None)
    if problem is None:
        book, problem = read_notebook(path)
    if problem is not None:
        return _result(path.name, number, problem)
    try:
        return grade_book(path.name, book, timeout, grade_timeout, sandbox, seed=seed)
    except Exception as exc:  # noqa: BLE001 - one notebook's failure is its own
        return _result(path.name, number, f"could not grade the notebook: {type(exc).__name__}")


def by_student(jobs_list, jobs):
    """jobs_list in `jobs` shares, each student's notebooks in one share (graded one after
    another: a student's notebooks never run at once, so none reaches another exercise's
    reference through what they share, e.g. the page cache)."""
    counts = collections.Counter(student for student, _, _ in jobs_list)
    sizes, share = [0] * jobs, {}
    for student, count in sorted(counts.items(), key=lambda c: (-c[1], repr(c[0]))):
        share[student] = sizes.index(min(sizes))  # the most notebooks first, to the emptiest
        sizes[share[student]] += count
    return [[job for job in jobs_list if share[job[0]] == n] for n in range(jobs)]


def jobs_for(sandbox, jobs):
    """(notebooks graded at once, the log's line or None): one where this user may give no
    sandbox its own CPU share (no cpu cgroup: an ordinary user without a delegated one), so a
    student's busy processes never take a classmate's CPU."""
    if jobs > 1 and "cpu" not in sandbox.controlled:
        return 1, (f"--jobs {jobs}: graded one notebook at a time instead (no CPU share per "
                   "sandbox here: a cpu cgroup this user may make, e.g. a delegated user scope)")
    return jobs, None


def _grade_share(share, timeout, grade_timeout, sandbox, seed):
    return [grade_notebook(nb, timeout, grade_timeout, sandbox, problem, seed)
            for _, nb, problem in share]


def _grade_jobs(jobs_list, jobs, timeout, grade_timeout, sandbox, seed):
    """Every notebook's result, in order; a grading process that dies costs its share."""
    if jobs <= 1:
        return _grade_share(jobs_list, timeout, grade_timeout, sandbox, seed)
    shares = [s for s in by_student(jobs_list, jobs) if s]
    with ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("spawn")) as pool:
        futures = [pool.submit(_grade_share, share, timeout, grade_timeout, sandbox, seed)
                   for share in shares]
        outcomes = {}
        for share, future in zip(shares, futures):
            try:
                results = future.result()
            except Exception as exc:  # noqa: BLE001 - a crashed grading process
                results = [_result(os.path.basename(nb), None, "could not grade the notebook: "
                                   f"the grading process failed ({exc!r:.200})")
                           for _, nb, _ in share]
            outcomes.update({id(job): r for job, r in zip(share, results)})
    return [outcomes[id(job)] for job in jobs_list]


def grade_all(submissions, out, feedback=None, timeout=NOTEBOOK_TIMEOUT, jobs=1,
              grade_timeout=GRADE_TIMEOUT, log=print, limits=None, bwrap=None, collect=None,
              unsandboxed=False, warn=None, seed=None):
    """Grade every student folder; write the CSV and the feedback files; return the rows
    (`collect`: a list that receives every notebook's result dict). The checks run on hidden
    cases drawn from `seed` (None: a fresh secret one, logged so a run can be repeated).
    Raises SandboxUnavailable (no sandbox, and not `unsandboxed`) or SelfCheckFailed before
    grading anyone."""
    from .grading import selfcheck
    from .grading.sandbox import Limits, Sandbox

    if submissions is None or not Path(submissions).is_dir():
        raise ValueError(f"SUBMISSIONS_DIR: expected a folder of student folders, "
                         f"got {str(submissions)!r}")
    found, ignored = students(submissions)
    out = Path(out)
    feedback = Path(feedback) if feedback else out.parent / "feedback"
    hidden = [submissions, out.parent, feedback, INSTRUCTOR, Path.cwd() / "instructor"]
    limits = dataclasses.replace(limits or Limits(), jobs=max(1, int(jobs)))
    sandbox = Sandbox(hidden, limits, bwrap=bwrap, unsandboxed=unsandboxed)
    try:
        if sandbox.unsandboxed:
            (warn or (lambda m: print(m, file=sys.stderr)))(
                "WARNING: --no-sandbox: every student's code runs WITHOUT isolation, with "
                "your user's rights (files, network). The CSV records it.")
        sandbox.verify()
        enforced, not_enforced = sandbox.report()
        log(f"sandbox: {sandbox.backend}; enforced:")
        for line in enforced:
            log(f"  + {line}")
        log("sandbox: NOT enforced:")
        for line in not_enforced:
            log(f"  - {line}")
        seed = secrets.randbits(63) if seed is None else int(seed)
        log(f"hidden cases: seed {seed} (--seed {seed} grades on the same cases again)")
        jobs, why = jobs_for(sandbox, limits.jobs)
        if why:
            log(why)
        selfcheck.run(functools.partial(grade_book, seed=seed), sandbox, timeout, grade_timeout)
        log("self-check: a known-good answer got 10/10 and a wrapper of ikteach's own got 0")
        for name in ignored:
            log(f"ignored (not a student folder): {text(name)}")
        jobs_list, per_student, notes = [], {}, {}
        for name, folder, problem in found:
            per_student[name], notes[name] = [], [problem] if problem else []
            if problem:
                continue
            try:
                books = notebooks(folder)
            except OSError as exc:
                notes[name].append(f"the folder could not be read: {exc.strerror or exc}")
                continue
            for _, path, _why in books[MAX_NOTEBOOKS:]:
                notes[name].append(f"{text(os.path.basename(path))}: not graded: more than "
                                   f"{MAX_NOTEBOOKS} notebooks handed in")
            jobs_list += [(name, path, why) for _, path, why in books[:MAX_NOTEBOOKS]]
        # by exercise: each exercise's fork server (its own copy of ikteach) starts once
        jobs_list.sort(key=lambda job: exercise_number(job[1], None) or 0)
        outcomes = _grade_jobs(jobs_list, jobs, timeout, grade_timeout, sandbox, seed)
    finally:
        sandbox.close()
    if collect is not None:
        collect.extend(outcomes)
    shown = labels(per_student)  # as the CSV shows them: printable, one per folder
    for (student, path, problem), result in zip(jobs_list, outcomes):
        per_student[student].append(result)
        if problem or result["status"] == "not graded":
            notes[student].append(f"{result['file']}: {result['message']}")
        log(f"{shown[student]}/{result['file']}: {result['score']:g}/{result['max']:g} "
            f"{result['status']} ({result.get('seconds', 0.0):.0f} s)")
    return write_results(per_student, notes, out, feedback, sandbox.backend)


def main(argv=None):
    from .grading.sandbox import OVERRIDE, Limits, SandboxUnavailable
    from .grading.selfcheck import SelfCheckFailed

    parser = argparse.ArgumentParser(prog="python -m ikteach.course.grade",
                                     description="Grade exercise notebooks, one folder per "
                                                 "student.")
    parser.add_argument("submissions", metavar="SUBMISSIONS_DIR", nargs="?")
    parser.add_argument("--out", help="the CSV to write (one row per student)")
    parser.add_argument("--feedback", default=None,
                        help="folder for <student>.txt (default: feedback/ next to --out)")
    parser.add_argument("--timeout", type=float, default=NOTEBOOK_TIMEOUT,
                        help="CPU seconds allowed for one notebook's cells, and 5 times as "
                             "many in wall time (default %(default)s)")
    parser.add_argument("--grade-timeout", type=float, default=GRADE_TIMEOUT,
                        help="seconds allowed for one notebook's checks (default %(default)s)")
    parser.add_argument("--jobs", type=int, default=1, help="notebooks graded at once")
    parser.add_argument("--seed", type=int, default=None,
                        help="the hidden cases' seed (default: a fresh secret one, logged)")
    parser.add_argument("--memory-mb", type=int, default=Limits.memory_mb,
                        help="address space of one student process, and the memory of one "
                             "sandbox where a memory cgroup can be made (default %(default)s)")
    parser.add_argument("--cpu-s", type=int, default=Limits.cpu_seconds,
                        help="CPU seconds of one student process (default %(default)s)")
    parser.add_argument("--tmpfs-mb", type=int, default=Limits.tmpfs_mb,
                        help="size of each of a student's /tmp, /dev/shm and working folder, "
                             "all in memory (default %(default)s)")
    parser.add_argument("--no-bwrap", action="store_true",
                        help="do not use bubblewrap even where it works (then only "
                             f"{OVERRIDE} grades)")
    parser.add_argument(OVERRIDE, dest="no_sandbox", action="store_true",
                        help="where no sandbox works, run students' code WITHOUT isolation "
                             "(warned on stderr, recorded in the CSV)")
    parser.add_argument("--gradescope", metavar="OUT.zip",
                        help="write a Gradescope autograder bundle instead of grading")
    args = parser.parse_args(argv)
    if args.gradescope:
        from .grading.gradescope import bundle
        print(f"wrote {bundle(args.gradescope)}")
        return 0
    if not args.out:
        parser.error("--out is required (the CSV to write)")
    limits = Limits(cpu_seconds=args.cpu_s, memory_mb=args.memory_mb, tmpfs_mb=args.tmpfs_mb)
    try:
        rows = grade_all(args.submissions, args.out, args.feedback, args.timeout, args.jobs,
                         args.grade_timeout, limits=limits,
                         bwrap=False if args.no_bwrap else None, unsandboxed=args.no_sandbox,
                         seed=args.seed)
    except ValueError as exc:
        parser.error(str(exc))
    except SandboxUnavailable as exc:
        print(f"grade: refused: {exc}", file=sys.stderr)
        return 2
    except SelfCheckFailed as exc:
        print(f"grade: stopped: {exc}", file=sys.stderr)
        return 3
    print(f"wrote {args.out}: {len(rows)} student(s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
