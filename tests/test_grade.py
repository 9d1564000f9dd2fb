"""python -m ikteach.course.grade on the solutions, the untouched templates, the wrong and the hostile
submissions (tests/submissions/, written by make_hostile.py).

One grading run (two notebooks at a time) serves every test here.
"""
import csv
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from ikteach.course import grade

ROOT = Path(__file__).resolve().parents[1]
WRONG = ROOT / "tests" / "submissions"
STUDENTS = sorted(p.name for p in WRONG.iterdir() if p.is_dir())
UNTOUCHED = ["01_jacobian.ipynb", "06_singularity_study.ipynb", "07_priority_step.ipynb"]
ESCAPES = [Path("/tmp/ikteach-escaped.txt"), Path("/var/tmp/ikteach-escaped.txt"),
           ROOT / "ESCAPED.txt"]


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
    before = {p: p.read_bytes() for p in subs.rglob("*") if p.is_file()}
    for path in ESCAPES:
        path.unlink(missing_ok=True)
    out = base / "out" / "grades.csv"
    run = subprocess.run([sys.executable, "-m", "ikteach.course.grade", str(subs), "--out", str(out),
                          "--timeout", "10", "--jobs", "2"],
                         capture_output=True, text=True, timeout=1500, cwd=base)
    assert run.returncode == 0, run.stderr[-3000:]
    rows = {r["student"]: r for r in csv.DictReader(out.open())}
    feedback = {p.stem: p.read_text() for p in (base / "out" / "feedback").glob("*.txt")}
    return rows, feedback, before, run.stdout


def scores(row):
    return [float(row[f"ex{n}"]) for n in range(1, 8)], float(row["total"])


def test_one_row_and_one_feedback_file_per_student(graded):
    rows, feedback, *_ = graded
    students = {"solutions", "untouched"} | set(STUDENTS)
    assert set(rows) == students and set(feedback) == students


def test_solutions_get_full_marks(graded):
    rows, feedback, *_ = graded
    assert scores(rows["solutions"]) == ([10.0] * 7, 70.0)
    assert feedback["solutions"].count("passed, 10/10") == 7
    # exercise 6's written answer is copied for the instructor, not marked
    assert "your written answer (not marked by the checker" in feedback["solutions"]
    assert "| Stretched towards a target it cannot reach" in feedback["solutions"]


def test_untouched_templates_get_zero(graded):
    rows, feedback, *_ = graded
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
    rows, feedback, *_ = graded
    marks, total = scores(rows[student])
    assert marks[exercise - 1] == score and total == score
    assert f"Exercise {exercise} (" in feedback[student] and line in feedback[student]


# hostile submissions: (student, exercise, marks, a line of its feedback)
HOSTILE = [
    # replaces ik.check.grade, ik.check.pinv_step and sys.modules["ikteach.course.check"]: template
    ("forge_check", 3, 0, "not yet implemented"),
    # prints fake grade lines, replaces print, sys.stdout and the display hook: template
    ("forge_output", 2, 0, "not yet implemented"),
    # patches the checks from inside its own function (which runs in another process)
    ("patch_in_function", 2, 7, "alpha looks fixed: it is 0.1 in every case"),
    # writes outside its folder (the files are checked below); its function is right
    ("write_outside", 1, 10, "passed, 10/10"),
    ("fork_storm", 2, 10, "passed, 10/10"),
    ("memory_hog", 4, 10, "raised MemoryError"),
    ("sigint_loop", 5, 10, "did not finish within the notebook's time limit (10 s)"),
    ("huge_output", 1, 10, "passed, 10/10"),
    ("hostile", 3, 10, "did not finish within the notebook's time limit (10 s)"),
    ("not_json", 1, 0, "it is not JSON"),
    ("no_functions", 3, 0, "`pinv_step` not found in the notebook"),
]


@pytest.mark.parametrize("student, exercise, score, line", HOSTILE)
def test_a_hostile_submission_loses_only_its_own_marks(graded, student, exercise, score, line):
    rows, feedback, *_ = graded
    marks, total = scores(rows[student])
    assert marks[exercise - 1] == score and total == score, feedback[student]
    assert line in feedback[student], feedback[student]


def test_nothing_escapes(graded):
    """No file written outside the working folder, submissions untouched, no process left."""
    _, _, before, _ = graded
    for path in ESCAPES:
        assert not path.exists(), path
    for path, content in before.items():
        assert path.read_bytes() == content
    time.sleep(1)
    left = subprocess.run(["pgrep", "-f", "sleep 77.125"], capture_output=True, text=True)
    assert left.stdout.strip() == "", "the fork storm's children outlived the grading"


def test_the_solutions_and_other_students_are_out_of_reach(graded):
    """The stealing submission copies a solution when it can read one: with bubblewrap it
    cannot (0 marks); without, the log must say this is not enforced."""
    rows, feedback, _, log = graded
    stolen = scores(rows["steal_solution"])[1]
    if "no writes outside the working folder (bubblewrap" in log:
        assert stolen == 0 and "`dls_step` raised FileNotFoundError" in feedback["steal_solution"]
    else:
        assert "reading the solutions and other students' folders" in log


def test_the_log_says_what_the_sandbox_enforces(graded):
    log = graded[3]
    assert "sandbox: enforced:" in log and "sandbox: NOT enforced:" in log
    assert "RLIMIT_CPU" in log and "RLIMIT_AS" in log and "RLIMIT_FSIZE" in log


def test_exercise_number_from_metadata_or_name():
    assert grade.exercise_number("x/03_anything.ipynb", {"metadata": {}}) == 3
    assert grade.exercise_number("x/renamed.ipynb", {"metadata": {"ikteach": {"exercise": 5}}}) == 5
    assert grade.exercise_number("x/renamed.ipynb", {"metadata": {}}) is None


def test_missing_submissions_dir_is_a_clear_error(tmp_path):
    with pytest.raises(ValueError, match="SUBMISSIONS_DIR"):
        grade.grade_all(tmp_path / "nope", tmp_path / "g.csv")
