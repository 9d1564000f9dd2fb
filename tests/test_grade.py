"""python -m ikteach.grade on the solutions, the untouched templates and the wrong submissions.

One grading run (a kernel per notebook, two at a time) serves every test here.
"""
import csv
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ikteach import grade

ROOT = Path(__file__).resolve().parents[1]
WRONG = ROOT / "tests" / "submissions"


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    base = tmp_path_factory.mktemp("grading")
    subs = base / "submissions"
    shutil.copytree(ROOT / "instructor" / "solutions", subs / "solutions")
    shutil.copytree(ROOT / "notebooks" / "exercises", subs / "untouched")
    for student in WRONG.iterdir():
        shutil.copytree(student, subs / student.name)
    (subs / "untouched" / "notes.txt").write_text("not a notebook: ignored")
    before = {p: p.read_bytes() for p in subs.rglob("*") if p.is_file()}
    out = base / "out" / "grades.csv"
    run = subprocess.run([sys.executable, "-m", "ikteach.grade", str(subs), "--out", str(out),
                          "--timeout", "40", "--jobs", "2"],
                         capture_output=True, text=True, timeout=900, cwd=base)
    assert run.returncode == 0, run.stderr[-3000:]
    rows = {r["student"]: r for r in csv.DictReader(out.open())}
    feedback = {p.stem: p.read_text() for p in (base / "out" / "feedback").glob("*.txt")}
    return rows, feedback, before


def scores(row):
    return [float(row[f"ex{n}"]) for n in range(1, 8)], float(row["total"])


def test_one_row_and_one_feedback_file_per_student(graded):
    rows, feedback, _ = graded
    students = {"solutions", "untouched"} | {p.name for p in WRONG.iterdir()}
    assert set(rows) == students and set(feedback) == students


def test_solutions_get_full_marks(graded):
    rows, feedback, _ = graded
    assert scores(rows["solutions"]) == ([10.0] * 7, 70.0)
    assert feedback["solutions"].count("passed, 10/10") == 7


def test_untouched_templates_get_zero(graded):
    rows, feedback, _ = graded
    assert scores(rows["untouched"]) == ([0.0] * 7, 0.0)
    assert feedback["untouched"].count("not yet implemented") == 7


@pytest.mark.parametrize("student, exercise, score, line", [
    ("sign_error", 1, 2, "wrong sign: your Jacobian is -1 x the expected one"),
    ("fixed_alpha", 2, 6, "alpha looks fixed: it is 0.1 in every case"),
    ("no_cutoff", 3, 5, "no cut-off: 1/sigma_i must be dropped"),
    ("lambda_not_squared", 4, 2, "missing square on lambda"),
    ("infinite_loop", 1, 0, "did not return within 5 s"),
    ("exception", 2, 0, "`jt_step` raised ValueError"),
])
def test_wrong_submissions_get_partial_marks_and_the_right_feedback(graded, student, exercise,
                                                                     score, line):
    rows, feedback, _ = graded
    marks, total = scores(rows[student])
    assert marks[exercise - 1] == score and total == score
    assert f"Exercise {exercise} (" in feedback[student] and line in feedback[student]


def test_a_hostile_submission_costs_only_its_own_marks(graded):
    """It deletes every file in its working directory, then never returns."""
    rows, feedback, before = graded
    # its function is right; the loop is cut off
    assert scores(rows["hostile"])[1] == 10.0, feedback["hostile"]
    assert "did not finish within the notebook's time limit (40 s)" in feedback["hostile"]
    for path, content in before.items():  # the submissions themselves are untouched
        assert path.read_bytes() == content


def test_exercise_number_from_metadata_or_name():
    assert grade.exercise_number("x/03_anything.ipynb", {"metadata": {}}) == 3
    assert grade.exercise_number("x/renamed.ipynb", {"metadata": {"ikteach": {"exercise": 5}}}) == 5
    assert grade.exercise_number("x/renamed.ipynb", {"metadata": {}}) is None


def test_missing_submissions_dir_is_a_clear_error(tmp_path):
    with pytest.raises(ValueError, match="SUBMISSIONS_DIR"):
        grade.grade_all(tmp_path / "nope", tmp_path / "g.csv")


def test_the_grade_line_is_read_even_when_stdout_arrives_in_pieces():
    token = "IKTEACH-GRADE-abc:"
    cell = {"outputs": [{"output_type": "stream", "name": "stdout", "text": "checks...\n" + token + '{"sco'},
                        {"output_type": "stream", "name": "stdout", "text": 're": 7}\n'}]}
    assert grade._read_grade(cell, token) == {"score": 7}
