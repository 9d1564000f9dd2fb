"""One student's CPU and time stay in that student's jobs (issue 35): a class of three graded
two notebooks at a time - a CPU storm (200 busy children, each trying a session of its own,
kept alive through the notebook's run and its checks), forty cells of shell escapes (skipped),
and an honest classmate graded beside them (the instructor's solutions to exercise 2, the
storm's, and 5, a solve under a time limit), who keeps full marks.

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

from ikteach.course.grading import bwrap
from ikteach.course.grading.remote import MAX_NOTES
from sandboxes import SANDBOXED

ROOT = Path(__file__).resolve().parents[1]
CLASS = ROOT / "tests" / "submissions" / "storm_class"
HONEST = ("02_jt_step.ipynb", "05_stop_rule.ipynb")  # the attacks' exercise, and a solve


def honest(folder):
    folder.mkdir(parents=True)
    for name in HONEST:
        shutil.copy(ROOT / "instructor" / "solutions" / name, folder / name)
TIMEOUT, GRADE_TIMEOUT = 10, 40


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    base = tmp_path_factory.mktemp("storm")
    subs = base / "submissions"
    shutil.copytree(CLASS, subs)
    honest(subs / "honest")
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


@pytest.mark.without_bwrap  # without a sandbox: the class is refused (the fixture checks)
def test_the_honest_classmate_keeps_full_marks_beside_a_cpu_storm(graded):
    if graded is None:
        return
    rows, feedback, _ = graded
    assert set(rows) == {"cpu_storm", "honest", "shell_escapes"}
    assert float(rows["honest"]["total"]) == 10.0 * len(HONEST), feedback["honest"]
    assert "did not finish within the notebook's time limit" in feedback["cpu_storm"]


def test_shell_escapes_are_skipped_with_bounded_notes(graded):
    """40 cells of 300 `!x` lines: the grader's shell runs no shell line (issue 50: skipped, a
    note each, at most MAX_NOTES kept), and the answer is graded. IPython's own transform of
    those cells takes about 100 CPU s: --timeout stops them (that note is past the MAX_NOTES
    kept), and since it counts CPU seconds, a busy machine does not get the job killed."""
    if graded is None:
        return
    rows, feedback, log = graded
    text = feedback["shell_escapes"]
    assert "Exercise 2 (02_jt_step.ipynb): 10/10" in text and "`!x` was skipped" in text, text
    assert text.count("was skipped") <= MAX_NOTES, text


def test_the_log_records_the_hidden_cases_seed(graded):
    """Graded without --seed: a fresh secret seed, logged so that the run can be repeated."""
    if graded is None:
        return
    seed = re.search(r"hidden cases: seed (\d+) \(--seed (\d+) grades on the same cases", graded[2])
    assert seed and seed.group(1) == seed.group(2), graded[2]


# --- graded as an ordinary user (issue 41): no cgroups, the process limit counted per user ------
FORK_TO_LIMIT = '''\
import os, time
_children = 0
while _children < 5000:  # until the process limit refuses; the children stay through the checks
    try:
        pid = os.fork()
    except OSError:
        break
    if pid == 0:
        time.sleep(600)
        os._exit(0)
    _children += 1
time.sleep(8)  # the classmate's jobs start meanwhile (they must still fork)
'''
PRLIMIT_SERVER = '''\
import os, resource
_server = os.getppid()  # the fork server that starts the next notebooks of this exercise
resource.prlimit(_server, resource.RLIMIT_NOFILE, (24, 24))
os.setpriority(os.PRIO_PROCESS, _server, 19)
'''
FORGED = '''\
import json, os
_forged = {"ready": ["x%d" % i for i in range(100000)],
           "foreign": {"x%d" % i: "y" * 400 for i in range(20000)},
           "held": {"%024d" % i: "z" * 80 for i in range(20000)}}
os.write(4, (json.dumps(_forged) + "\\n").encode())  # the job's replies pipe
'''
USER = 64999  # an ordinary user: not nobody, whose processes the sandboxes of root's graders are


def _with_cell(source):
    import json
    book = json.loads((ROOT / "instructor" / "solutions" / "02_jt_step.ipynb").read_text())
    book["cells"].insert(1, {"cell_type": "code", "metadata": {}, "outputs": [],
                             "execution_count": None, "source": source})
    return json.dumps(book)


@pytest.fixture(scope="module")
def graded_as_user():
    """A class graded by an ordinary user (no cgroups, RLIMIT_NPROC per user), two
    notebooks at a time: a fork to the process limit, a prlimit on the fork server, a forged
    first message, and an honest classmate."""
    import os
    import tempfile
    if not SANDBOXED or os.geteuid() != 0:
        pytest.skip("needs root (to become an ordinary user) and bubblewrap")
    # where the Python lies under a folder the user cannot enter (/root), it is shown to it
    as_user = bwrap.started_as(USER, shutil.which("bwrap"), [sys.base_prefix])
    seen = subprocess.run(as_user + [sys.executable, "-S", "-c",
                                     "import os, sys; print(os.getuid(), sys.base_prefix)"],
                          capture_output=True, text=True, timeout=60)
    assert seen.stdout.split() == [str(USER), sys.base_prefix], seen
    base = Path(tempfile.mkdtemp(prefix="ikteach-as-user-"))  # pytest's folders are root's only
    subs = base / "submissions"
    honest(subs / "zz_honest")  # graded last
    for name, source in (("fork_to_limit", FORK_TO_LIMIT), ("prlimit_server", PRLIMIT_SERVER),
                         ("forged", FORGED)):
        (subs / name).mkdir(parents=True)
        (subs / name / "02_jt_step.ipynb").write_text(_with_cell(source))
    (base / "out").mkdir()
    for path in [base, *base.rglob("*")]:
        os.chown(path, USER, USER)
    try:
        run = subprocess.run(
            as_user + [sys.executable, "-m", "ikteach.course.grade", str(subs), "--out",
                       str(base / "out" / "grades.csv"), "--timeout", str(TIMEOUT),
                       "--grade-timeout", str(GRADE_TIMEOUT), "--jobs", "2", "--seed", "1"],
            capture_output=True, text=True, timeout=900, cwd=base,
            env={"PATH": os.environ["PATH"], "HOME": str(base), "LANG": "C.UTF-8"})
        assert run.returncode == 0, run.stderr[-3000:]
        rows = {r["student"]: r for r in csv.DictReader((base / "out" / "grades.csv").open())}
        feedback = {p.stem: p.read_text() for p in (base / "out" / "feedback").glob("*.txt")}
    finally:
        shutil.rmtree(base, ignore_errors=True)
    return rows, feedback, run.stdout


def test_as_an_ordinary_user_the_classmate_keeps_full_marks(graded_as_user):
    rows, feedback, log = graded_as_user
    assert "at most 256 per sandbox (RLIMIT_NPROC in its user namespace" in log, log
    assert "as an unprivileged uid outside it" in log and "(checked at start-up)" in log, log
    assert float(rows["zz_honest"]["total"]) == 10.0 * len(HONEST), feedback["zz_honest"]
    assert float(rows["forged"]["total"]) == 0 and len(rows["forged"]["notes"]) < 2000
