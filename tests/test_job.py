"""A notebook's job (issue 41): its cells run in IPython's shell and the checks call what they
built, in one fresh process; what a job can reach of the machine, its fork server and the next
job; how a notebook is taken for its exercise; names a lecturer can tell apart.

With bubblewrap (as root here and in CI) the job is in the sandbox; without it the grader's
--no-sandbox path runs the same job, and the tests of what only a sandbox stops are skipped
(tests/test_grade.py checks the refusal there).
"""
import contextlib
import copy
import json
import os
import signal
import threading
from pathlib import Path

import pytest

from ikteach.course import check, grade
from ikteach.course.grading import report, servers
from ikteach.course.grading.remote import MAX_NOTES, ProcessEnded, Worker
from ikteach.course.grading.sandbox import Sandbox
from sandboxes import SANDBOXED

ROOT = Path(__file__).resolve().parents[1]
SOLUTION = json.loads((ROOT / "instructor" / "solutions" / "02_jt_step.ipynb").read_text())
JT = """\
    J, e = np.asarray(J), np.asarray(e)
    g = J.T @ e
    v = J @ g
    return np.zeros(J.shape[1]) if v @ v == 0 else (e @ v / (v @ v)) * g
"""


@pytest.fixture(scope="module")
def sandbox():
    box = Sandbox([]) if SANDBOXED else Sandbox([], unsandboxed=True)
    yield box
    servers.close_all()
    box.close()


def without_metadata(book):
    book = copy.deepcopy(book)
    book["metadata"] = {"kernelspec": {"name": "python3"}, "colab": {"provenance": []}}
    return book


def with_answer(source):
    """Exercise 2's solution notebook with its answer cell replaced by `source`."""
    book = copy.deepcopy(SOLUTION)
    cell = next(c for c in book["cells"] if c["cell_type"] == "code"
                and "def jt_step(" in "".join(c["source"]))
    cell["source"] = source
    return book


def with_cell(source):
    """Exercise 2's solution notebook with a code cell `source` inserted as its second cell."""
    book = copy.deepcopy(SOLUTION)
    book["cells"].insert(1, {"cell_type": "code", "metadata": {}, "outputs": [],
                             "execution_count": None, "source": source})
    return book


HONEST = {
    # Colab's copy: "Copy of ...", the course metadata gone
    "Copy of 02_jt_step.ipynb": without_metadata(SOLUTION),
    # renamed, no metadata: taken by its content
    "my homework.ipynb": without_metadata(SOLUTION),
    # a top-level class used by the answer, under postponed annotations
    "02_future_class.ipynb": with_answer(
        "from __future__ import annotations\nimport dataclasses\n\n\n@dataclasses.dataclass\n"
        "class Step:\n    alpha: float\n    g: np.ndarray\n\n    def delta(self) -> np.ndarray:\n"
        "        return self.alpha * self.g\n\n\ndef jt_step(J, e) -> np.ndarray:\n"
        "    J, e = np.asarray(J), np.asarray(e)\n    g = J.T @ e\n    v = J @ g\n"
        "    alpha = 0.0 if v @ v == 0 else e @ v / (v @ v)\n"
        "    return Step(alpha, g).delta()\n"),
    # a constant table built in a loop inside a try, and a module alias set the same way
    "02_loop_constants.ipynb": with_answer(
        "SIGNS = {}\ntry:\n    import numpy as xp\n    for i, s in enumerate([1.0, -1.0]):\n"
        "        SIGNS[i] = s\nexcept ImportError:\n    xp = None\n\n\ndef jt_step(J, e):\n"
        "    J, e = xp.asarray(J), xp.asarray(e)\n    g = SIGNS[0] * (J.T @ e)\n    v = J @ g\n"
        "    return xp.zeros(J.shape[1]) if v @ v == 0 else (e @ v / (v @ v)) * g\n"),
    # jax.jit over jax.numpy, no Python branch
    "02_jit.ipynb": with_answer(
        "import jax\nimport jax.numpy as jnp\n\n\n@jax.jit\ndef jt_step(J, e):\n"
        "    J, e = jnp.asarray(J), jnp.asarray(e)\n    g = J.T @ e\n    v = J @ g\n"
        "    vv = v @ v\n"
        "    return jnp.where(vv == 0, 0.0, (e @ v) / jnp.where(vv == 0, 1.0, vv)) * g\n"),
    # a process pool made at the top level, used by the answer
    "02_process_pool.ipynb": with_answer(
        "from concurrent.futures import ProcessPoolExecutor\nimport multiprocessing\n"
        "POOL = ProcessPoolExecutor(2, mp_context=multiprocessing.get_context('fork'))\n\n\n"
        "def jt_step(J, e):\n    J, e = np.asarray(J), np.asarray(e)\n"
        "    g = POOL.submit(np.dot, J.T, e).result()\n    v = J @ g\n"
        "    return np.zeros(J.shape[1]) if v @ v == 0 else (e @ v / (v @ v)) * g\n"),
}


@pytest.mark.parametrize("name", sorted(HONEST))
def test_every_honest_way_of_writing_the_answer_gets_its_marks(sandbox, name):
    result = grade.grade_book(name, HONEST[name], 60, 120, sandbox, seed=1)
    assert result["exercise"] == 2 and result["score"] == 10, result
    assert not [n for n in result["notes"] if "raised" in n], result["notes"]
    if name.startswith("my"):
        assert result["how"] == "by its content (it defines `jt_step`)", result["how"]


def test_a_notebook_is_taken_for_its_exercise_by_metadata_content_or_name():
    assert grade.identify("Copy of 05_stop_rule.ipynb", {"cells": []}) == (5, "by its file name")
    assert grade.identify("2024_hw_03_pinv_step (1).ipynb", {"cells": []})[0] == 3
    assert grade.identify("x.ipynb", without_metadata(SOLUTION))[0] == 2
    assert grade.identify("01_jacobian.ipynb", SOLUTION) == (2, "by its metadata")
    # exercise 3 answered in a copy of the exercise 2 file: its content decides (round 5)
    started_from_2 = json.loads((ROOT / "instructor" / "solutions" / "03_pinv_step.ipynb").read_text())
    started_from_2["metadata"] = SOLUTION["metadata"]
    assert grade.identify("02_jt_step.ipynb", started_from_2) == (
        3, "by its content (it defines `pinv_step`); its metadata says exercise 2")
    assert grade.identify("notes.ipynb", {"cells": [{"cell_type": "code",
                                                     "source": "print(1)"}]}) == (None, None)


SEEN = """\
import fcntl, os, sys
def seen():
    out = {}
    for path in ["/proc/sys/kernel/core_pattern", "/proc/sys/vm/panic_on_oom",
                 "/proc/sysrq-trigger", "/proc/self/oom_score_adj", "/proc/1/oom_score_adj"]:
        try:
            os.close(os.open(path, os.O_WRONLY))  # opened, never written
            out[path] = "opened for writing"
        except OSError as exc:
            out[path] = exc.strerror
    with open(sys.executable, "rb") as shared:  # a file every sandbox sees
        for name, lock in [("lockf", lambda: fcntl.lockf(shared, fcntl.LOCK_SH | fcntl.LOCK_NB)),
                           ("flock", lambda: fcntl.flock(shared, fcntl.LOCK_SH | fcntl.LOCK_NB))]:
            try:
                lock()
                out[name] = "locked"
            except OSError as exc:
                out[name] = exc.strerror
    st = os.stat(sys.prefix)  # metadata, which Landlock does not govern: left as it was
    for name, change in [("chmod", lambda: os.chmod(sys.prefix, st.st_mode & 0o7777)),
                         ("utime", lambda: os.utime(sys.prefix, ns=(st.st_atime_ns,
                                                                    st.st_mtime_ns))),
                         ("xattr", lambda: os.setxattr(sys.prefix, "user.ikteach", b"1"))]:
        try:
            change()
            out[name] = "changed"
        except OSError as exc:
            out[name] = exc.strerror
    return out
"""


@pytest.mark.skipif(not SANDBOXED, reason="only the sandbox stops it (the refusal is tested)")
def test_nothing_of_the_kernel_is_writable_and_no_lock_is_shared(sandbox):
    """As root with bubblewrap (this machine, CI): /proc/sys and the job's own oom_score_adj do
    not open for writing, a lock on a file all sandboxes see is refused, and the mode, times
    and extended attributes of the grader's Python (the sandbox's uid may own it) stay."""
    worker = Worker([(1, SEEN)], sandbox, exercise=2).start()
    try:
        seen = worker.call("seen", [])
    finally:
        worker.end()
    assert all(v != "opened for writing" for v in seen.values()), seen
    assert seen["lockf"] != "locked" and seen["flock"] != "locked", seen
    assert {seen[n] for n in ("chmod", "utime", "xattr")} == {"Read-only file system"}, seen
    assert os.geteuid() != 0 or seen["/proc/sys/kernel/core_pattern"] in (
        "Read-only file system", "Permission denied"), seen


ATTACK_SERVER = """\
import os, resource
_server = os.getppid()  # the fork server that starts every notebook of this exercise
resource.prlimit(_server, resource.RLIMIT_NOFILE, (24, 24))
os.setpriority(os.PRIO_PROCESS, _server, 19)
"""


def test_a_job_that_changes_its_fork_server_does_not_reach_the_next(sandbox):
    """prlimit and setpriority on the server (same uid): the next notebook gets a fresh one."""
    first = servers.server_for(sandbox, 2)
    grade.grade_book("attack.ipynb", with_cell(ATTACK_SERVER), 60, 120, sandbox, seed=1)
    assert servers.server_for(sandbox, 2) is not first
    after = grade.grade_book("b.ipynb", SOLUTION, 60, 120, sandbox, seed=1)
    assert after["score"] == 10 and after["notes"] == [], after


LEAVE_METADATA = """\
import os, struct
_none = struct.pack("<I", 2) + b"".join(struct.pack("<HHI", tag, 0, 0xFFFFFFFF) for tag in (1, 4, 32))
for _path, _name, _value in [("/tmp", "user.left", b"1"), ("/dev/shm", "user.left", b"1"),
                             ("..", "system.posix_acl_default", _none), ("..", "user.left", b"1")]:
    os.setxattr(_path, _name, _value)  # the server's folder (the job folder's parent) too
"""
SEES_METADATA = "import os\nassert not os.listxattr('/tmp') and not os.listxattr('/dev/shm')\n"


@pytest.mark.skipif(not SANDBOXED, reason="only the sandbox stops it (the refusal is tested)")
def test_extended_attributes_and_acls_a_job_leaves_do_not_reach_the_next(sandbox):
    """Round 5: a default ACL without rights on the fork server's folder and xattrs on /tmp and
    /dev/shm: the server is replaced, and the next notebook sees none of it."""
    first = servers.server_for(sandbox, 2)
    left = grade.grade_book("attack.ipynb", with_cell(LEAVE_METADATA), 60, 120, sandbox, seed=1)
    assert left["notes"] == [], left  # it did set them all
    assert servers.server_for(sandbox, 2) is not first
    after = grade.grade_book("b.ipynb", with_cell(SEES_METADATA), 60, 120, sandbox, seed=1)
    assert after["score"] == 10 and after["notes"] == [], after


LEAVE_TIMES = "import os\nfor _p in ('/tmp', '/dev/shm', '..'):\n    os.utime(_p, ns=(123456789, 987654321))\n"
SEES_TIMES = ("import os\nassert not {123456789, 987654321} & {t for p in ('/tmp', '/dev/shm', '..') "
              "for t in (os.stat(p).st_atime_ns, os.stat(p).st_mtime_ns)}\n")


@pytest.mark.skipif(not SANDBOXED, reason="only the sandbox stops it (the refusal is tested)")
def test_times_a_job_sets_do_not_reach_the_next(sandbox):
    """Round 5: times set on /tmp, /dev/shm and the server's folder (a message of 128 bits
    each) are put back after the job; the server is kept (times change in every job)."""
    first = servers.server_for(sandbox, 2)
    left = grade.grade_book("attack.ipynb", with_cell(LEAVE_TIMES), 60, 120, sandbox, seed=1)
    assert left["notes"] == [], left
    after = grade.grade_book("b.ipynb", with_cell(SEES_TIMES), 60, 120, sandbox, seed=1)
    assert servers.server_for(sandbox, 2) is first
    assert after["score"] == 10 and after["notes"] == [], after


FORGED = """\
import json, os
_forged = {"ready": ["x%d" % i for i in range(100000)],
           "foreign": {"x%d" % i: "y" * 400 for i in range(20000)},
           "held": {"%024d" % i: "z" * 80 for i in range(20000)}}
os.write(4, (json.dumps(_forged) + "\\n").encode())  # the job's replies pipe
"""


def test_what_a_job_says_is_bounded(sandbox):
    """A notebook that forges the job's first message: what the grader keeps of it is
    bounded (not the 20000 entries), and the forged list of names gives it nothing."""
    book = with_answer(FORGED)
    result = grade.grade_book("forged.ipynb", book, 60, 120, sandbox, seed=1)
    assert result["score"] == 0 and len(json.dumps(result)) < 40_000, len(json.dumps(result))


FORGED_FOREIGN = """\
from ikteach.course.grading import own_code
own_code.foreign = lambda namespace, names: {}  # the job's report of foreign names: forged
jt_step = ik.jt_step
"""


def test_a_forged_report_of_foreign_names_gains_nothing(sandbox):
    """own_code.foreign runs in the student's process, so a cell can replace it; that only
    takes away the early 0 that a one-line `def` wrapper avoids anyway: the name is still
    called in the job, where ikteach's answer is a stub that raises."""
    result = grade.grade_book("forged.ipynb", with_answer(FORGED_FOREIGN), 60, 120, sandbox,
                              seed=1)
    assert result["score"] == 0, result
    assert "`jt_step` raised ReferenceBlocked: ikteach's jt_step is the reference" in \
        result["message"], result["message"]


FLOOD = """\
import json, os, signal
signal.signal(signal.SIGALRM, signal.SIG_IGN)  # the notebook's own alarm: ignored
_lines = (json.dumps({"stopped": "x" * 20, "error": "y" * 400}) + "\\n").encode() * 200
while True:
    os.write(4, _lines)  # the job's replies pipe
"""
LOUD = "def jt_step(J, e):\n    raise RuntimeError('x' * 8_000_000)\n"


def test_what_a_job_writes_during_its_cells_is_bounded_and_ends_at_the_deadline(sandbox):
    """Issue 50 item 2: notes on arrival at most MAX_NOTES, the grader's deadline holds while
    lines keep coming (the job is ended by the grader, not by its server's later limit), and a
    student's 8 MB error message is cut."""
    worker = Worker([(1, FLOOD)], sandbox, exercise=2, limit=120, timeout=1)
    with pytest.raises(ProcessEnded, match="ignored the alarm"):
        worker.start()
    assert len(worker.errors) + len(worker.notes) <= MAX_NOTES + 1, len(worker.notes)
    loud = grade.grade_book("loud.ipynb", with_answer(LOUD), 60, 120, sandbox, seed=1)
    assert loud["score"] == 0 and len(json.dumps(loud)) < 10_000, len(json.dumps(loud))


def _jobs():
    """The students' jobs of this process's sandboxes: children of a fork server (the same
    command line: a fork) that descend from this test."""
    table = {}
    for name in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{name}/stat", "rb") as stat, open(f"/proc/{name}/cmdline", "rb") as cmd:
                table[int(name)] = (int(stat.read().rsplit(b")", 1)[1].split()[1]),
                                    b"grading.forkserver" in cmd.read())
        except (OSError, ValueError, IndexError):
            continue

    def ours(pid):
        while pid > 1 and pid != os.getpid():
            pid = table.get(pid, (0, False))[0]
        return pid == os.getpid()

    return [pid for pid, (parent, server) in table.items()
            if server and table.get(parent, (0, False))[1] and ours(pid)]


def _busy(done):
    """A machine busier than any load: the students' jobs get 0.25 s to run in every 1.25 s."""
    def send(pids, number):
        for pid in pids:
            with contextlib.suppress(ProcessLookupError):  # a job that has just ended
                os.kill(pid, number)

    while not done.wait(0.25):
        frozen = _jobs()
        send(frozen, signal.SIGSTOP)
        done.wait(1.0)
        send(frozen, signal.SIGCONT)


def test_honest_answers_keep_their_marks_on_a_machine_too_busy_for_their_time_limits(
        sandbox, monkeypatch):
    """Exercise 2's solution (the self-check's exercise) and exercise 5's (a solve under a
    limit, which the grader compiles) graded while their jobs wait 1 s in every 1.25 s, longer
    than every call's limit (cut to 0.5 s, and 3 s for a solve): the limits count the job's
    CPU seconds, so the marks are full, on the first run."""
    monkeypatch.setattr(check.verdicts, "TIME_LIMIT", 0.5)
    monkeypatch.setattr(check.ex05_stop_rule, "SOLVE_LIMIT", 3.0)
    books = {n: json.loads((ROOT / "instructor" / "solutions" / n).read_text())
             for n in ("02_jt_step.ipynb", "05_stop_rule.ipynb")}
    done = threading.Event()
    busy = threading.Thread(target=_busy, args=(done,))
    busy.start()
    try:
        results = [grade.grade_book(n, b, 60, 180, sandbox, seed=3) for n, b in books.items()]
    finally:
        done.set()
        busy.join()
    assert [(r["score"], r["notes"]) for r in results] == [(10.0, [])] * 2, results


def test_a_call_held_up_without_using_its_cpu_time_says_the_machine_is_busy(monkeypatch):
    """A call that waits BUSY times its limit without using the CPU time the limit allows is
    stopped with the words for what happened (here: the student's own wait)."""
    monkeypatch.setattr(check.verdicts, "TIME_LIMIT", 0.1)
    monkeypatch.setattr(check.verdicts, "BUSY", 3)
    verdict = check.jt_step_verdict(lambda J, e: threading.Event().wait(60))
    assert verdict.score == 0 and "this machine is busy (or your code waits)" in verdict.message


FIRST_RUN = """\
import os
try:  # what a first run of this notebook left: an extended attribute on /tmp, a file in it
    _again = os.getxattr("/tmp", "user.ikteach-run") == b"1"
except OSError:
    _again = False
_again = _again or os.path.exists("/tmp/ikteach-run")
if not _again:
    open("/tmp/ikteach-run", "w").close()
    try:
        os.setxattr("/tmp", "user.ikteach-run", b"1")
    except OSError:
        pass


def jt_step(J, e):
    if not _again:
        while True:  # past the time limit, so that the grader runs the notebook again
            pass
""" + JT
ASKS_AGAIN = "def jt_step(J, e):\n    raise RuntimeError('did not return within 5 s')\n"


@pytest.mark.skipif(not SANDBOXED, reason="a fresh sandbox is what the re-run starts in")
def test_a_run_again_comes_only_from_the_grader_s_time_limit_and_starts_clean(sandbox,
                                                                                 monkeypatch):
    """Re-runs (issue 50 item 4): a student's error in the time limit's words starts none; a
    re-run finds nothing the first run left (files, extended attributes)."""
    monkeypatch.setattr(check.verdicts, "TIME_LIMIT", 0.3)
    asks = grade.grade_book("asks.ipynb", with_answer(ASKS_AGAIN), 60, 120, sandbox, seed=1)
    assert asks["score"] == 0 and grade.RERUN not in asks["notes"], asks
    again = grade.grade_book("again.ipynb", with_answer(FIRST_RUN), 60, 120, sandbox, seed=1)
    assert again["score"] == 0 and grade.RERUN in again["notes"], again
    assert "did not return within 0.3 s of CPU time" in again["message"], again


def test_any_two_folders_get_two_rows_and_two_feedback_files():
    latin1 = os.fsdecode(b"M\xfcller")
    names = [latin1, "M\\xfcller", "Müller", "Mu\u0308ller", "Anna", "anna", "x" * 255]
    shown = report.labels(names)
    assert len(set(shown.values())) == len(names), shown
    forged = names + [shown["Anna"], shown["Anna"] + " [0]"]  # folders named as hashed labels
    assert len(set(report.labels(forged).values())) == len(forged), report.labels(forged)
    files = {report.file_name(label).casefold() for label in shown.values()}
    assert len(files) == len(names), files
    assert shown["x" * 255] == "x" * 255 and shown[latin1].startswith("M\\xfcller [")


def test_the_feedback_counts_the_notebook_the_csv_counts_and_names_the_others(tmp_path):
    """Issue 50 item 3: the unfilled template and the answer as a browser's second download,
    in either order: the CSV and the feedback both count the answer and name the template."""
    def result(name, score, message):
        return {"file": name, "exercise": 2, "how": "by its metadata", "score": score,
                "max": 10.0, "status": "", "message": message, "notes": [], "answer": ""}

    template = result("02_jt_step.ipynb", 0.0, "Exercise 2: not yet implemented")
    answer = result("02_jt_step (1).ipynb", 10.0, "Exercise 2: passed, 10/10")
    for order in ([answer, template], [template, answer]):
        rows = report.write_results({"kim": order}, {"kim": []}, tmp_path / "g.csv",
                                    tmp_path / "fb", "none")
        page = (tmp_path / "fb" / "kim.txt").read_text()
        assert rows[0]["ex2"] == 10.0 and "Total: 10/70" in page, page
        assert "Exercise 2 (02_jt_step (1).ipynb): 10/10" in page, page
        assert "not counted (the best notebook counts): 02_jt_step.ipynb: 0/10" in page, page


def test_a_student_s_notebooks_are_never_graded_at_once():
    """Round 5 (a relay through the page cache between two of one student's notebooks under
    --jobs 2): each student's notebooks are in one grading process's share, in order."""
    jobs_list = [(s, f"{s}/{n:02d}.ipynb", None) for n in (1, 2, 5) for s in ("ann", "bo", "cy")]
    shares = grade.by_student(jobs_list, 2)
    assert sorted(job for share in shares for job in share) == sorted(jobs_list)
    for student in ("ann", "bo", "cy"):
        assert sum(any(job[0] == student for job in share) for share in shares) == 1
    assert all(share == [job for job in jobs_list if job in share] for share in shares)


def test_an_ordinary_user_without_a_cpu_share_grades_one_notebook_at_a_time():
    """Issue 50 item 1: without a cpu cgroup per sandbox, a fork storm would take a concurrent
    classmate's CPU: one notebook at a time, said in the log."""
    from types import SimpleNamespace
    assert grade.jobs_for(SimpleNamespace(controlled={"pids", "cpu"}), 2) == (2, None)
    jobs, why = grade.jobs_for(SimpleNamespace(controlled={"pids"}), 2)
    assert jobs == 1 and "no CPU share per sandbox" in why
    assert grade.jobs_for(SimpleNamespace(controlled=set()), 1) == (1, None)


def test_the_grader_s_cgroups_are_removed_when_it_ends():
    """Issue 50 item 6: closing a sandbox (grade_all does when it ends) stops this process's
    fork servers of it and removes the cgroups made for them (as root: pids, memory, cpu)."""
    box = Sandbox([]) if SANDBOXED else Sandbox([], unsandboxed=True)
    try:
        server = servers.server_for(box, 2)
        made = list(server.process.cgroups)
        assert len(made) == len(box.cgroups) and all(c.is_dir() for c in made), made
    finally:
        box.close()
    assert server.process.proc.poll() is not None
    assert not [c for c in made if c.exists()], made


HOSTILE = "x\x1b]0;x\x07\x1b[2J\nz_control\u2215 0\u2215 10\u202eevil"  # title, clear, a fake line


def test_no_name_reaches_the_log_csv_or_feedback_with_a_control_or_bidi_character(
        tmp_path, monkeypatch):
    """Issue 50 item 5: a folder and a notebook named with ESC sequences, BEL, a newline and
    U+202E, beside a folder named as their escaped text: every log line, CSV cell, feedback
    file name and feedback line is printable, and each folder keeps a row and file of its own.
    The notebook is no JSON, so nothing reaches a sandbox (none is started here)."""
    import csv
    import re

    from ikteach.course.grading import sandbox, selfcheck
    from ikteach.course.grading.submissions import UNSAFE, text

    class Unused:  # the grader's sandbox and self-check: no notebook here gets that far
        unsandboxed, backend, controlled = False, "none", set()
        verify = close = lambda self: None

        def __init__(self, *args, **kwargs):
            pass

        def report(self):
            return [], []

    monkeypatch.setattr(sandbox, "Sandbox", Unused)
    monkeypatch.setattr(selfcheck, "run", lambda *args: None)
    subs, log = tmp_path / "subs", []
    for folder in (HOSTILE, text(HOSTILE), "anna"):
        (subs / folder).mkdir(parents=True)
        (subs / folder / f"02_jt_step{HOSTILE}.ipynb").write_text("{not json")
    rows = grade.grade_all(subs, tmp_path / "out" / "grades.csv", log=log.append)
    unsafe = re.compile(f"[{UNSAFE}\n]")
    feedback = list((tmp_path / "out" / "feedback").iterdir())
    with open(tmp_path / "out" / "grades.csv", newline="", encoding="utf-8") as handle:
        cells = [value for row in csv.reader(handle) for value in row]
    pages = [line for page in feedback for line in page.read_text().splitlines()]
    names = [page.name for page in feedback]
    assert len(log) > 3 and not [s for s in log + cells + pages + names if unsafe.search(s)]
    assert len({row["student"] for row in rows}) == len(feedback) == 3
    graded = {line.rsplit(" (", 1)[0] for line in log}
    assert {f"{row['student']}/02_jt_step{text(HOSTILE)}.ipynb: 0/10 not graded"
            for row in rows} <= graded, log
