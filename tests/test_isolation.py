"""One student's CPU and time stay in that student's jobs (issue 35): a class of three graded
two notebooks at a time - a CPU storm (200 busy children, each trying a session of its own,
kept alive through the notebook's run and its checks), forty cells of shell escapes, and an
honest classmate (the instructor's solutions) graded beside them, who keeps 70/70.

Where this machine has no sandbox the grader refuses the class (exit status 2, no CSV): the
storm would run on the machine itself.
"""
import csv
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ikteach.course import grade
from sandboxes import SANDBOXED

ROOT = Path(__file__).resolve().parents[1]
CLASS = ROOT / "tests" / "submissions" / "storm_class"
TIMEOUT, GRADE_TIMEOUT = 10, 40


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    base = tmp_path_factory.mktemp("storm")
    subs = base / "submissions"
    shutil.copytree(CLASS, subs)
    shutil.copytree(ROOT / "instructor" / "solutions", subs / "honest")
    out = base / "out" / "grades.csv"
    run = subprocess.run([sys.executable, "-m", "ikteach.course.grade", str(subs), "--out",
                          str(out), "--timeout", str(TIMEOUT), "--grade-timeout",
                          str(GRADE_TIMEOUT), "--jobs", "2"],
                         capture_output=True, text=True, timeout=900, cwd=base)
    if not SANDBOXED:
        assert run.returncode == 2 and not out.exists(), run.stderr[-2000:]
        assert "no sandbox for the students' code" in run.stderr
        return None
    assert run.returncode == 0, run.stderr[-3000:]
    rows = {r["student"]: r for r in csv.DictReader(out.open(encoding="utf-8"))}
    feedback = {p.stem: p.read_text(encoding="utf-8")
                for p in (base / "out" / "feedback").glob("*.txt")}
    return rows, feedback, run.stdout


def test_the_honest_classmate_keeps_full_marks_beside_a_cpu_storm(graded):
    if graded is None:
        return
    rows, feedback, _ = graded
    assert set(rows) == {"cpu_storm", "honest", "shell_escapes"}
    assert [float(rows["honest"][f"ex{n}"]) for n in range(1, 8)] == [10.0] * 7, \
        feedback["honest"]
    assert "did not finish within the notebook's time limit" in feedback["cpu_storm"]


def test_shell_escapes_hold_to_the_time_limits(graded):
    """40 cells of 300 `!x` lines: the cells are stopped at --timeout, the checks (whose worker
    reads the cells' IPython syntax) at --grade-timeout, and the grader's own process never
    works on them: the notebook costs at most the two limits and the grace."""
    if graded is None:
        return
    rows, feedback, log = graded
    text = feedback["shell_escapes"]
    assert f"did not finish within the notebook's time limit ({TIMEOUT} s)" in text, text
    took = re.search(r"shell_escapes/02_jt_step.ipynb: .* \((\d+) s\)", log)
    assert int(took.group(1)) <= TIMEOUT + GRADE_TIMEOUT + grade.GRACE, log

