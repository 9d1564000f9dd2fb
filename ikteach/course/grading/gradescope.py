"""A Gradescope autograder bundle that grades with the same checks and sandbox.

    python -m ikteach.course.grade --gradescope OUT.zip

The zip holds setup.sh (Gradescope runs it once when building the image: Python, bubblewrap,
ikteach from the bundled source), run_autograder (run per submission) and ikteach's source -
never the instructor's solutions. run_autograder grades every exercise notebook in
/autograder/submission as one student and writes /autograder/results/results.json: one test
per exercise handed in (score, max_score, the feedback text) and the total as "score".
For a local run, IKTEACH_GS_SUBMISSION, IKTEACH_GS_RESULTS and IKTEACH_GS_PYTHON override the
submission folder, the results file and the Python it runs on.
"""
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]

SETUP = """\
#!/usr/bin/env bash
# Gradescope image setup: Python, bubblewrap (the sandbox), ikteach from this bundle.
set -euo pipefail
apt-get update
apt-get install -y python3 python3-venv python3-pip bubblewrap
python3 -m venv /autograder/venv
/autograder/venv/bin/pip install --upgrade pip
/autograder/venv/bin/pip install "/autograder/source[grade]"
"""

RUN = """\
#!/usr/bin/env bash
# Gradescope runs this for each submission; results.json in Gradescope's format.
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
SUBMISSION="${IKTEACH_GS_SUBMISSION:-/autograder/submission}"
RESULTS="${IKTEACH_GS_RESULTS:-/autograder/results/results.json}"
PYTHON="${IKTEACH_GS_PYTHON:-/autograder/venv/bin/python}"
export PYTHONPATH="$HERE${PYTHONPATH:+:$PYTHONPATH}"   # the bundled ikteach first
exec "$PYTHON" -m ikteach.course.grading.autograder "$SUBMISSION" "$RESULTS"
"""


def bundle(out):
    """Write the autograder zip; returns its path."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        for name, text in (("setup.sh", SETUP), ("run_autograder", RUN)):
            info = zipfile.ZipInfo(name)
            info.external_attr = 0o100755 << 16  # executable
            z.writestr(info, text)
        for path in sorted((ROOT / "ikteach").rglob("*.py")):
            z.write(path, path.relative_to(ROOT).as_posix())
        for name in ("pyproject.toml", "README.md", "LICENSE"):
            if (ROOT / name).exists():
                z.write(ROOT / name, name)
    return out


def results(student_rows, outcomes, log_lines):
    """results.json's dict from one student's graded notebooks."""
    tests = []
    for r in sorted(outcomes, key=lambda r: (r["exercise"] or 99, r["file"])):
        text = "\n".join([r["message"]] + [f"note: {n}" for n in r["notes"]])
        name = f"Exercise {r['exercise']} ({r['file']})" if r["exercise"] else r["file"]
        tests.append({"name": name, "score": r["score"], "max_score": r["max"],
                      "output": text, "visibility": "visible"})
    if not tests:
        tests.append({"name": "exercise notebooks", "score": 0.0, "max_score": 0.0,
                      "output": "no exercise notebook (NN_name.ipynb) found in the submission",
                      "visibility": "visible"})
    total = float(student_rows[0]["total"]) if student_rows else 0.0
    return {"score": total, "tests": tests, "output": "\n".join(log_lines),
            "visibility": "visible", "stdout_visibility": "hidden"}
