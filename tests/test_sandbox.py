"""The sandbox one student process runs in, and the AST extraction of student code."""
import socket
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from ikteach.course.grading import extract
from ikteach.course.grading.sandbox import Limits, Sandbox


def run_in(sandbox, tmp_path, code):
    work = tmp_path / "work"
    work.mkdir(exist_ok=True)
    process = sandbox.start([sys.executable, "-S", "-c", textwrap.dedent(code)], work,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    try:
        out = process.proc.communicate(timeout=60)[0].decode()
    finally:
        process.end()
    return process.proc.returncode, out


@pytest.fixture
def sandbox(tmp_path):
    secret = tmp_path / "solutions"
    secret.mkdir()
    (secret / "answer.txt").write_text("42")
    box = Sandbox([secret], Limits(memory_mb=512, cpu_seconds=20))
    yield box, secret
    box.close()


def test_limits_hold_in_every_mode(sandbox, tmp_path):
    box, _ = sandbox
    code, out = run_in(box, tmp_path, """
        try:
            b = bytearray(2 << 30)   # 2 GiB > 512 MiB
            print("allocated")
        except MemoryError:
            print("MemoryError")
        import os; print(os.environ["HOME"].endswith("/home"), sorted(os.environ)[:3])
        """)
    assert "MemoryError" in out and "True" in out, out


def test_bubblewrap_hides_blocks_writes_and_network_or_the_report_says_not(sandbox, tmp_path):
    box, secret = sandbox
    enforced, not_enforced = box.report()
    outside = tmp_path / "escaped.txt"  # under /tmp: bubblewrap gives the run a private /tmp
    repo = Path(__file__).resolve().parents[1] / "ESCAPED-sandbox-test.txt"  # read-only there
    home = Path.home() / "ESCAPED-sandbox-test.txt"  # on the read-only root wherever the repo is
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    port = server.getsockname()[1]
    code, out = run_in(box, tmp_path, f"""
        import os, socket
        for path in [{str(outside)!r}, {str(repo)!r}, {str(home)!r}]:
            try:
                open(path, "w").write("x"); print("wrote")
            except OSError as exc:
                print("no write", type(exc).__name__)
        print("secret files:", os.listdir({str(secret)!r}) if os.path.isdir({str(secret)!r}) else None)
        try:
            socket.create_connection(("127.0.0.1", {port}), timeout=2); print("connected")
        except OSError:
            print("no network")
        """)
    server.close()
    if box.bwrap:
        assert "no write" in out and "no network" in out, out
        assert "secret files: None" in out or "secret files: []" in out, out
        assert not outside.exists() and not repo.exists() and not home.exists()  # nothing escaped
        assert any("no network" in line for line in enforced)
    else:
        repo.unlink(missing_ok=True)
        home.unlink(missing_ok=True)
        assert any(line.startswith("network") for line in not_enforced)
        assert any("writes outside the working folder" in line for line in not_enforced)


def test_without_bubblewrap_the_report_lists_what_is_not_enforced(tmp_path):
    box = Sandbox([], bwrap=False)
    try:
        enforced, not_enforced = box.report()
        assert box.bwrap is None and any("RLIMIT_CPU" in line for line in enforced)
        assert any(line.startswith("network") for line in not_enforced)
        assert run_in(box, tmp_path, "print('ran')")[1].strip() == "ran"
    finally:
        box.close()


def test_the_grader_never_hides_its_own_python_or_ikteach(tmp_path):
    import ikteach
    box = Sandbox([Path(ikteach.__file__).parents[1], tmp_path])
    try:
        assert Path(ikteach.__file__).parents[1] not in box.hidden and tmp_path in box.hidden
        assert any("hiding" in line for line in box.report()[1])
    finally:
        box.close()


def test_extraction_keeps_definitions_and_drops_the_rest():
    cell = textwrap.dedent("""\
        %matplotlib inline
        import numpy as np
        ARM = [1.0, 1.0]
        print("hello")
        ik.check.grade = None
        def f(x):
            return x
        for i in range(3):
            pass
        """)
    kept = extract.kept_statements(extract.python_source(cell))
    assert [type(n).__name__ for n in kept] == ["Import", "Assign", "Assign", "FunctionDef"]
    book = {"cells": [{"cell_type": "markdown", "source": "x"},
                      {"cell_type": "code", "source": ["a = 1\n", "b = 2"]}]}
    assert extract.code_cells(book) == [(2, "a = 1\nb = 2\n")]
    with pytest.raises(SyntaxError):
        extract.kept_statements("def (:")


def test_a_python_under_tmp_is_bound_back_read_only(tmp_path):
    # bubblewrap gives the run a private /tmp: a checkout or venv there must be bound back
    box = Sandbox([tmp_path / "class"], bwrap="/usr/bin/bwrap")
    try:
        box.bwrap = "/usr/bin/bwrap"  # the command line only; nothing is run
        box.needed = [Path("/tmp/course/.venv"), Path("/tmp/course/ikteach"), Path("/usr")]
        box.hidden = [Path("/tmp/course/.venv/secret"), Path("/tmp/other"), Path("/srv/solutions")]
        cmd = box.command(["python", "-c", "1"], tmp_path, None)
        binds = [cmd[i + 1] for i, a in enumerate(cmd) if a == "--ro-bind"]
        tmpfs = [cmd[i + 1] for i, a in enumerate(cmd) if a == "--tmpfs"]
        assert "/tmp/course/.venv" in binds and "/tmp/course/ikteach" in binds
        assert "/usr" not in binds[1:]  # outside /tmp: already there via the read-only root
        assert "/tmp/course/.venv/secret" in tmpfs and "/srv/solutions" in tmpfs
        assert "/tmp/other" not in tmpfs  # gone with the private /tmp anyway
        assert cmd.index("/tmp/course/.venv") < cmd.index("/tmp/course/.venv/secret")  # bind, then hide
    finally:
        box.close()
