"""The Gradescope autograder's entry (run_autograder calls it, see gradescope.py):

    python -m ikteach.course.grading.autograder SUBMISSION_DIR RESULTS_JSON

grades the notebooks of one submission with the course's grader and writes results.json.
"""
import json
import shutil
import sys
import tempfile
from pathlib import Path

from ..grade import grade_all
from .gradescope import results


def run(submission, results_path):
    """Grade the notebooks under `submission` as one student; write results.json."""
    work = Path(tempfile.mkdtemp(prefix="ikteach-gradescope-"))
    try:
        student = work / "submissions" / "student"
        student.mkdir(parents=True)
        for path in sorted(Path(submission).rglob("*.ipynb")):
            if ".ipynb_checkpoints" not in path.parts:
                shutil.copy(path, student / path.name)
        log, outcomes = [], []
        rows = grade_all(work / "submissions", work / "out" / "grades.csv", log=log.append,
                         collect=outcomes)
        data = results(rows, outcomes, [l for l in log if l.startswith(("sandbox", "  "))])
    finally:
        shutil.rmtree(work, ignore_errors=True)
    results_path = Path(results_path)
    results_path.parent.mkdir(parents=True, exist_ok=True)
    results_path.write_text(json.dumps(data, indent=2))
    return data


if __name__ == "__main__":
    run(sys.argv[1], sys.argv[2])
