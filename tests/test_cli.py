"""The course's one command (`ikteach`, [project.scripts]) and the old `python -m ikteach.grade`."""
import subprocess
import sys
from pathlib import Path

import pytest

from ikteach.course import cli

ROOT = Path(__file__).resolve().parents[1]
IKTEACH = Path(sys.executable).parent / "ikteach"  # the venv's console script


def run(*args):
    return subprocess.run(args, capture_output=True, text=True, cwd=ROOT, timeout=120)


def test_the_console_script_is_installed_and_lists_its_commands():
    out = run(str(IKTEACH), "--help")
    assert out.returncode == 0, out.stderr
    for name in cli.COMMANDS:
        assert name in out.stdout


def test_grade_help_works_from_the_venv():
    out = run(str(IKTEACH), "grade", "--help")
    assert out.returncode == 0, out.stderr
    assert "--out" in out.stdout and "SUBMISSIONS_DIR" in out.stdout


@pytest.mark.parametrize("argv, message", [
    ([], "the following arguments are required: COMMAND"),
    (["grdae"], "invalid choice: 'grdae'"),
    (["grade", "submissions"], "--out is required"),
    (["slides", "no/such.ipynb"], "NOTEBOOK: no such file: no/such.ipynb"),
    (["exercises"], "required: command"),
])
def test_argument_errors_are_clear(argv, message, capsys):
    with pytest.raises(SystemExit) as stop:
        cli.main(argv)
    assert stop.value.code == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("name", cli.COMMANDS)
def test_every_command_has_help(name, capsys):
    # in this process: the console script's own start is tested above, once
    with pytest.raises(SystemExit) as stop:
        cli.main([name, "--help"])
    assert stop.value.code == 0 and "usage:" in capsys.readouterr().out, name


def test_the_old_grade_module_tells_the_new_command_and_forwards():
    out = run(sys.executable, "-m", "ikteach.grade", "--help")
    assert out.returncode == 0
    assert "ikteach grade" in out.stderr
    assert "--out" in out.stdout
    out = run(sys.executable, "-m", "ikteach.grade", "submissions")
    assert out.returncode == 2 and "--out is required" in out.stderr
