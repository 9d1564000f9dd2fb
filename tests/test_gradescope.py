"""The Gradescope bundle: its run_autograder, run locally with Gradescope's paths overridden,
writes a correct results.json for a solution and for a wrong submission."""
import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from ikteach.course.grading import gradescope
from sandboxes import SANDBOXED

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def bundle(tmp_path_factory):
    base = tmp_path_factory.mktemp("gradescope")
    path = gradescope.bundle(base / "autograder.zip")
    source = base / "source"
    with zipfile.ZipFile(path) as z:
        z.extractall(source)
        modes = {i.filename: i.external_attr >> 16 for i in z.infolist()}
    for name in ("setup.sh", "run_autograder"):
        (source / name).chmod(modes[name] & 0o777)
    return source, set(modes)


def run_autograder(source, tmp_path, notebook):
    submission = tmp_path / "submission"
    submission.mkdir()
    shutil.copy(notebook, submission / notebook.name)
    results = tmp_path / "results" / "results.json"
    env = dict(os.environ, IKTEACH_GS_SUBMISSION=str(submission), IKTEACH_GS_RESULTS=str(results),
               IKTEACH_GS_PYTHON=sys.executable)
    run = subprocess.run([str(source / "run_autograder")], env=env, capture_output=True,
                         text=True, timeout=600)
    data = json.loads(results.read_text())
    if not SANDBOXED:  # the autograder refuses, and results.json says why
        assert run.returncode == 1 and data["score"] == 0.0 and data["tests"] == []
        assert "could not grade (not your fault)" in data["output"]
        assert "apt-get install bubblewrap" in data["output"]
        return None
    assert run.returncode == 0, run.stderr[-3000:]
    return data


def test_the_bundle_holds_the_scripts_and_no_solutions(bundle):
    source, names = bundle
    assert {"setup.sh", "run_autograder", "ikteach/course/grade.py",
            "ikteach/course/check/ex01_jacobian.py"} <= names
    assert not [n for n in names if n.startswith("instructor") or "solution" in n.lower()]
    assert "bubblewrap" in (source / "setup.sh").read_text()


@pytest.mark.without_bwrap
def test_a_solution_scores_full_marks(bundle, tmp_path):
    data = run_autograder(bundle[0], tmp_path, ROOT / "instructor" / "solutions" / "02_jt_step.ipynb")
    if data is None:
        return  # refused: checked in run_autograder
    assert data["score"] == 10.0
    [test] = data["tests"]
    assert (test["name"], test["score"], test["max_score"]) == (
        "Exercise 2 (02_jt_step.ipynb)", 10.0, 10.0)
    assert "passed, 10/10" in test["output"] and "sandbox: bubblewrap; enforced:" in data["output"]


@pytest.mark.without_bwrap
def test_a_wrong_submission_gets_its_marks_and_feedback(bundle, tmp_path):
    data = run_autograder(bundle[0], tmp_path, ROOT / "tests" / "submissions" / "fixed_alpha"
                          / "02_jt_step.ipynb")
    if data is None:
        return  # refused: checked in run_autograder
    assert data["score"] == 7.0
    [test] = data["tests"]
    assert test["score"] == 7.0 and test["max_score"] == 10.0
    assert "alpha looks fixed: it is 0.1 in every case" in test["output"]
