"""The Gradescope autograder's entry (run_autograder calls it, see gradescope.py):

    python -m ikteach.course.grading.autograder SUBMISSION_DIR RESULTS_JSON

grades the notebooks of one submission with the course's grader and writes results.json.
Where the grader refuses (no sandbox) or its self-check fails, results.json says why (score 0,
for the instructor to see) and the exit status is non-zero.
"""
import json
import shutil
import sys
import tempfile
from pathlib import Path

from ..grade import grade_all
from .gradescope import results
from .sandbox import SandboxUnavailable
from .selfcheck import SelfCheckFailed


def run(submission, results_path):
    """Grade the notebooks under `submission` as one student; write results.json."""
    work = Path(tempfile.mkdtemp(prefix="ikteach-gradescope-"))
    try:
        student = work / "submissions" / "student"
        student.mkdir(parents=True)
        for path in sorted(Path(submission).rglob("*.ipynb")):
            # regular files only: never a link (to the autograder's source) or a FIFO
            if ".ipynb_checkpoints" not in path.parts and path.is_file() \
                    and not path.is_symlink():
                shutil.copy(path, student / path.name, follow_symlinks=False)
        log, outcomes = [], []
        try:
            rows = grade_all(work / "submissions", work / "out" / "grades.csv",
                             log=log.append, collect=outcomes)
            data = results(rows, outcomes, [l for l in log if l.startswith(("sandbox", "  "))])
        except (SandboxUnavailable, SelfCheckFailed) as exc:
            data = {"score": 0.0, "tests": [], "visibility": "visible",
                    "output": f"The autograder could not grade (not your fault): {exc}"}
    finally:
        shutil.rmtree(work, ignore_errors=True)
    results_path = Path(results_path)
    results_path.parent.mkdir(parents=True, exist_ok=True)
    results_path.write_text(json.dumps(data, indent=2))
    return data


if __name__ == "__main__":
    # no tests in results.json: the grader refused or failed its self-check
    sys.exit(0 if run(sys.argv[1], sys.argv[2])["tests"] else 1)
