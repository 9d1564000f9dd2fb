"""The sandbox one student process runs in, and the cells' text.

Where this machine has a sandbox (bubblewrap) the tests attack it from inside; where it has
none they check that it refuses, and what the override (--no-sandbox) still enforces."""
import os
import socket
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import pytest

from ikteach.course.grading import bwrap, extract
from ikteach.course.grading.sandbox import Limits, Sandbox, SandboxUnavailable
from cells_as_python import python_source
from sandboxes import SANDBOXED

PACKAGE = Path(__file__).resolve().parents[1] / "ikteach"
TMP = Path(tempfile.gettempdir()).resolve()


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


def assert_refused():
    with pytest.raises(SandboxUnavailable) as refusal:
        Sandbox()
    text = str(refusal.value)
    assert "tried: bubblewrap: `bwrap` not found on PATH" in text, text
    assert "apt-get install bubblewrap" in text and "--no-sandbox" in text


@pytest.fixture
def sandbox(tmp_path):
    """(the sandbox, a hidden folder) - or None where there is none (the refusal checked)."""
    secret = tmp_path / "solutions"
    secret.mkdir()
    (secret / "answer.txt").write_text("42")
    if not SANDBOXED:
        assert_refused()
        yield None
        return
    box = Sandbox([secret], Limits(memory_mb=512, cpu_seconds=20))
    box.verify()
    yield box, secret
    box.close()


@pytest.mark.without_bwrap
def test_limits_hold_with_and_without_isolation(sandbox, tmp_path):
    unsandboxed = Sandbox([], Limits(memory_mb=512, cpu_seconds=20), bwrap=False,
                          unsandboxed=True)
    for box in [unsandboxed] + ([sandbox[0]] if sandbox else []):
        code, out = run_in(box, tmp_path, """
            try:
                b = bytearray(2 << 30)   # 2 GiB > 512 MiB
                print("allocated")
            except MemoryError:
                print("MemoryError")
            import os; print(os.environ["HOME"].endswith("/home"), sorted(os.environ)[:3])
            """)
        assert "MemoryError" in out and "True" in out, out
    unsandboxed.close()


ATTACK = """
    import ctypes, os, socket
    libc = ctypes.CDLL(None, use_errno=True)
    for path in {writes!r}:
        try:
            open(path, "w").write("x"); print("wrote", path)
        except OSError as exc:
            print("no write", path, type(exc).__name__)
    for folder in {reads!r}:
        print("listing:", sorted(os.listdir(folder)) if os.path.isdir(folder) else None)
    try:
        socket.create_connection(("127.0.0.1", {port}), timeout=2); print("connected")
    except OSError:
        print("no network")
    status = dict(l.split(":", 1) for l in open("/proc/self/status") if l.startswith("Cap"))
    print("uid", os.getuid(), "caps", sorted({{int(v, 16) for v in status.values()}}))
    print("umount", libc.umount2({check!r}.encode(), 2))
    print("remount", libc.mount(None, b"/", None, 32 | 4096, None),
          libc.mount(None, {package!r}.encode(), None, 32 | 4096, None))
    print("unshare", libc.unshare(0x10000000))
    print("listing after:", os.listdir({check!r}))
    for dev in ("/dev/null", "/dev/zero", "/dev/full", "/dev/random", "/dev/urandom"):
        try:  # to the mode it has: a change of nothing, should it succeed
            os.chmod(dev, os.stat(dev).st_mode & 0o7777); print("chmod", dev)
        except OSError as exc:
            print("no chmod", dev, exc.errno)
    """


@pytest.mark.without_bwrap
def test_a_student_process_cannot_escape_hide_or_regain_power(sandbox, tmp_path):
    """Writes outside (also where the grader imports from), hidden folders, the network,
    capabilities, mounts and new user namespaces - also when the grader runs as root."""
    if sandbox is None:
        return  # the refusal was checked by the fixture
    box, secret = sandbox
    check = str(PACKAGE / "course" / "check")
    private = tmp_path / "escaped.txt"  # the run's /tmp is its own: a write there goes nowhere
    outside = [PACKAGE / "course" / "planted.py", PACKAGE.parent / "planted.py",
               Path.home() / "ESCAPED-sandbox-test.txt", Path(sys.prefix) / "planted.pth"]
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    code, out = run_in(box, tmp_path, ATTACK.format(
        writes=[str(p) for p in outside + [private]], reads=[str(secret), check, str(PACKAGE.parent)],
        port=server.getsockname()[1], check=check, package=str(PACKAGE)))
    server.close()
    # the sandbox's /tmp is a tmpfs of its own: a write under /tmp (the private file; the
    # course itself when it sits under /tmp) lands there and goes nowhere - checked below
    in_tmp = [p for p in outside + [private] if p.resolve().is_relative_to(TMP)]
    for path in outside:
        assert path in in_tmp or f"no write {path} " in out, out
    wrote = [l for l in out.splitlines() if l.startswith("wrote")]
    assert set(wrote) <= {f"wrote {p}" for p in in_tmp}, out
    assert not any(p.exists() for p in outside + [private])
    solutions, checker, checkout = [l for l in out.splitlines() if l.startswith("listing:")]
    assert solutions in ("listing: []", "listing: None") and checker == "listing: []", out
    assert "'ikteach'" in checkout and "'instructor'" not in checkout, out  # only the package
    assert "no network" in out and "uid 65534 caps [0]" in out, out
    assert "umount -1" in out and "remount -1 -1" in out and "unshare -1" in out, out
    assert "listing after: []" in out, out
    # the machine's device nodes are bound in: as their owner (a sandbox of a root grader
    # that is host root) a job could make /dev/null useless for every user (issue 48)
    assert not [l for l in out.splitlines() if l.startswith("chmod")], out
    assert out.count("no chmod /dev/") == 5, out


@pytest.mark.without_bwrap
def test_the_probe_catches_a_sandbox_that_does_not_hold(monkeypatch):
    """Take the network namespace away: verify() must refuse, not log "no network"."""
    if not SANDBOXED:
        return assert_refused()
    monkeypatch.setattr(bwrap, "NAMESPACES", [a for a in bwrap.NAMESPACES if a != "--unshare-net"])
    assert_verify_refuses("reach the grader's machine over the network")


def assert_verify_refuses(why):
    box = Sandbox([])
    try:
        with pytest.raises(SandboxUnavailable, match=why):
            box.verify()
    finally:
        box.close()


def test_a_root_grader_starts_the_sandbox_as_nobody(monkeypatch):
    """As root, bwrap maps the sandbox's uid to root outside unless it starts as another uid:
    started as root, verify() must refuse (the job owns /dev/null); as nobody, it holds."""
    if not SANDBOXED or os.geteuid() != 0:
        return
    argv = bwrap.unprivileged(["bwrap", "--ro-bind", sys.base_prefix, sys.base_prefix, "--"])
    assert argv[argv.index("--as") + 1] == bwrap.SANDBOX_ID and argv[-1] == "--", argv
    monkeypatch.setattr(bwrap, "unprivileged", list)
    assert_verify_refuses("owns the machine's device nodes")


def test_only_a_folder_the_uid_cannot_enter_is_laid_over():
    """reachable(): nothing to do where every folder on the way lets the uid in (a Python in
    /usr, a container's root without the right to make mount namespaces still grades); a
    folder it cannot enter becomes a tmpfs holding the way to each source, and only that."""
    with tempfile.TemporaryDirectory(dir="/tmp") as base:  # /tmp: every uid enters it
        _laid_over(Path(base))


def _laid_over(base):
    base.chmod(0o755)
    shut, source = base / "shut", base / "shut" / "a" / "python"
    source.mkdir(parents=True)
    shut.chmod(0o755)
    assert bwrap.reachable("bwrap", [str(source)], 64999) == []
    shut.chmod(0o700)
    argv = bwrap.reachable("bwrap", [str(source)], 64999)
    assert argv[-1] == "--" and argv[argv.index("--tmpfs") + 1] == str(shut), argv
    assert argv[argv.index("--dir") + 1] == str(shut / "a"), argv
    assert argv[argv.index("--ro-bind") + 1:argv.index("--ro-bind") + 3] == [str(source)] * 2


def test_judge_states_only_what_held():
    good = {"uid": 65534, "capabilities": 0, "devices_owned": False, "read": [], "connected": False, "mounted": False,
            "processes": 2, "userns_blocked": True,
            "server": {"ptrace": False, "memory": False, "stopped": False}}
    lines = bwrap.judge(good, [], [Path("/srv/solutions")])
    assert any("no capabilities" in l for l in lines) and any("PID namespace" in l for l in lines)
    assert not any("user namespaces" in l for l in bwrap.judge(dict(good, userns_blocked=False),
                                                                [], []))
    for bad, why in [({"uid": 0}, "uid 0"), ({"devices_owned": True}, "device nodes"),
                     ({"devices_owned": None}, "device nodes"), ({"capabilities": 1 << 21}, "keeps capabilities"),
                     ({"read": ["/srv/solutions"]}, "read the hidden /srv/solutions"),
                     ({"mounted": True}, "mount"),
                     ({"server": {"ptrace": True, "memory": False, "stopped": False}},
                      "reach the fork server"), ({"server": None}, "reach the fork server")]:
        with pytest.raises(SandboxUnavailable, match=why):
            bwrap.judge(dict(good, **bad), [], [])
    with pytest.raises(SandboxUnavailable, match="write in /work"):
        bwrap.judge(good, ["/work"], [])


def test_without_a_sandbox_it_refuses_unless_told(tmp_path):
    with pytest.raises(SandboxUnavailable) as refusal:
        Sandbox([], bwrap=False)
    assert "bubblewrap: not used" in str(refusal.value) and "--no-sandbox" in str(refusal.value)
    box = Sandbox([], bwrap=False, unsandboxed=True)
    try:
        enforced, not_enforced = box.report()
        assert box.bwrap is None and box.backend == "none (--no-sandbox)"
        assert any("RLIMIT_CPU" in line for line in enforced)
        assert any(line.startswith("ISOLATION: NONE") for line in not_enforced)
        assert run_in(box, tmp_path, "print('ran')")[1].strip() == "ran"
    finally:
        box.close()


def test_blas_kernel_variables_reach_the_student_process(monkeypatch, tmp_path):
    monkeypatch.setenv("OPENBLAS_CORETYPE", "Haswell")
    monkeypatch.setenv("SECRET_TOKEN", "x")
    box = Sandbox([], bwrap=False, unsandboxed=True)
    try:
        env = box.environment(tmp_path)
        assert env["OPENBLAS_CORETYPE"] == "Haswell" and "SECRET_TOKEN" not in env
    finally:
        box.close()


def test_the_whitelist_holds_the_python_and_only_the_package():
    paths = bwrap.python_paths(PACKAGE)
    assert PACKAGE in paths and PACKAGE.parent not in paths  # not the checkout (solutions...)
    assert any(Path(sys.executable).resolve().is_relative_to(p) for p in paths
               + [Path(d).resolve() for d in bwrap.SYSTEM if os.path.isdir(d)])
    assert Path.cwd().resolve() not in paths


def test_the_command_line(tmp_path, monkeypatch):
    """Nothing is run: /tmp private before a Python under /tmp is bound back, a hidden folder
    inside a bound one covered read-only, an unprivileged user without capabilities."""
    monkeypatch.setattr(bwrap, "python_paths", lambda package: [
        Path("/tmp/course/.venv"), Path("/tmp/course/ikteach")])
    hidden = [Path("/tmp/course/ikteach/course/check"), Path("/srv/solutions")]
    (tmp_path / "x").mkdir()
    monkeypatch.setattr(bwrap, "_is_dir", lambda path: True)
    cmd = bwrap.command("bwrap", ["--disable-userns"], Path("/tmp/course/ikteach"), hidden,
                        tmp_path / "x")
    binds = [cmd[i + 1] for i, a in enumerate(cmd) if a == "--ro-bind"]
    tmpfs = [cmd[i + 1] for i, a in enumerate(cmd) if a == "--tmpfs"]
    assert "/tmp/course/.venv" in binds and "/tmp/course/ikteach" in binds
    assert cmd.index("/tmp") < cmd.index("/tmp/course/.venv")  # private /tmp, then bind back
    assert "/tmp/course/ikteach/course/check" in tmpfs and "/srv/solutions" not in cmd
    at = cmd.index("/tmp/course/ikteach/course/check")
    assert cmd[at + 1:at + 3] == ["--remount-ro", "/tmp/course/ikteach/course/check"]
    for flag in (["--uid", "65534"], ["--cap-drop", "ALL"], ["--unshare-net"],
                 ["--disable-userns"], ["--remount-ro", "/"]):
        assert any(cmd[i:i + len(flag)] == flag for i in range(len(cmd))), flag
    assert cmd[-1] == "--"


def test_code_cells_are_the_cells_text_and_magics_become_python():
    book = {"cells": [{"cell_type": "markdown", "source": "x"},
                      {"cell_type": "code", "source": ["a = 1\n", "b = 2"]}]}
    assert extract.code_cells(book) == [(2, "a = 1\nb = 2")]
    assert "get_ipython()" in python_source("%matplotlib inline\nx = 1\n")
    assert python_source("%%time\nx = 1\n") == "x = 1\n"


def test_the_seccomp_filter_refuses_locks_and_watches():
    """The filter's fcntl branch: F_SETLK and friends are refused, F_GETFL is not."""
    import struct
    program = bwrap.seccomp_program()
    if program is None:
        pytest.skip("no filter for this architecture")
    code = [struct.unpack("HBBI", program[i:i + 8]) for i in range(0, len(program), 8)]
    refused = {k for op, jt, jf, k in code if op == 0x15 and jt and code[code.index(
        (op, jt, jf, k)) + jt + 1][3] == 0x00050001}
    assert set(bwrap.FCNTL_DENIED) <= refused and 3 not in refused  # 3: F_GETFL
    assert {73, 253, 294}.issubset(refused) or {32, 26}.issubset(refused)
