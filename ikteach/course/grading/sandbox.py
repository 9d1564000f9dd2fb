"""Each student process runs in a sandbox, as far as this machine allows.

Always: its own temporary working folder and HOME, a bare environment, resource limits
(CPU time, address space, file size, no core files), its own process group (ended as a whole).
Where bubblewrap (`bwrap`, Debian package `bubblewrap`) runs: no network, the whole file
system read-only except its working folder, /tmp private, the instructor's solutions, the
submissions and the grader's output hidden, its own PID namespace (every process it started
dies with it). Where the cgroup v1 `pids` controller is writable: a cap on its processes
(RLIMIT_NPROC caps them for a non-root grader; it does not apply to root).
`Sandbox().report()` says what was and was not enforced; the grader logs it.
"""
import dataclasses
import os
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

LAUNCH = Path(__file__).with_name("_launch.py")
CGROUP_PIDS = Path("/sys/fs/cgroup/pids")


@dataclasses.dataclass(frozen=True)
class Limits:
    cpu_seconds: int = 600
    memory_mb: int = 4096
    processes: int = 256
    file_mb: int = 256


def _bwrap_works(bwrap):
    try:
        return subprocess.run([bwrap, "--ro-bind", "/", "/", "--dev", "/dev", "--proc", "/proc",
                               "--unshare-net", "--unshare-pid", "--die-with-parent", "true"],
                              capture_output=True, timeout=20).returncode == 0
    except (OSError, subprocess.SubprocessError):
        return False


def _cgroup_works():
    probe = CGROUP_PIDS / f"ikteach-probe-{secrets.token_hex(4)}"
    try:
        probe.mkdir()
        ok = (probe / "pids.max").exists()
        probe.rmdir()
        return ok
    except OSError:
        return False


class Sandbox:
    """How student processes are started; `hidden`: folders they must not see."""

    def __init__(self, hidden=(), limits=Limits(), bwrap=None):
        self.limits = limits
        self.work_root = Path(tempfile.mkdtemp(prefix="ikteach-grade-")).resolve()
        needed = [Path(__file__).resolve().parents[2], Path(sys.prefix).resolve(),
                  Path(sys.base_prefix).resolve(),
                  Path(sys.executable).resolve()]  # ikteach and the Python it runs on
        self.needed = needed
        wanted = [Path(p).resolve() for p in hidden if p and Path(p).exists()]
        self.hidden = [p for p in wanted if not any(p == n or p in n.parents for n in needed)]
        self.unhidden = [p for p in wanted if p not in self.hidden]
        self.hidden.append(self.work_root)  # every run's folder; each run sees only its own
        path = shutil.which("bwrap") if bwrap is None else (bwrap or None)
        self.bwrap = path if path and _bwrap_works(path) else None
        self.cgroup = _cgroup_works()
        self.root = os.geteuid() == 0

    def close(self):
        shutil.rmtree(self.work_root, ignore_errors=True)

    def report(self):
        """(enforced, not enforced): lists of short lines for the grader's log."""
        lim = self.limits
        yes = ["own temporary working folder and HOME, bare environment",
               f"CPU time {lim.cpu_seconds} s per process (RLIMIT_CPU)",
               f"memory {lim.memory_mb} MiB address space per process (RLIMIT_AS)",
               f"file size {lim.file_mb} MiB (RLIMIT_FSIZE), no core files",
               "wall-clock time limit; the process group is ended as a whole"]
        no = []
        if self.cgroup:
            yes.append(f"processes: at most {lim.processes} (cgroup pids.max)")
        elif not self.root:
            yes.append(f"processes: at most {lim.processes} for this user (RLIMIT_NPROC)")
        else:
            no.append("process count (root ignores RLIMIT_NPROC and the pids cgroup is not "
                      "writable): a fork storm is bounded only by the CPU and time limits")
        if self.bwrap:
            yes += ["no network (bubblewrap: own network namespace)",
                    "no writes outside the working folder (bubblewrap: read-only root, "
                    "private /tmp)",
                    "solutions, submissions and grader output hidden (bubblewrap: empty "
                    "tmpfs over " + ", ".join(str(p) for p in self.hidden) + ")"
                    if self.hidden else "nothing to hide was given",
                    "own PID namespace: every process it starts ends with it"]
        else:
            no += ["network (install bubblewrap: apt-get install bubblewrap)",
                   "writes outside the working folder: only file permissions stop them",
                   "reading the solutions and other students' folders: only file "
                   "permissions stop it",
                   "processes that leave the process group (setsid) may outlive the run"]
        for path in self.unhidden:
            no.append(f"hiding {path}: it holds the Python or ikteach the checks run on "
                      "(put submissions and output elsewhere)")
        no.append("reading files the grader's user may read outside the hidden folders "
                  "(e.g. the installed packages) - run the grader in a container for more")
        return yes, no

    def _cgroup_dir(self):
        if not self.cgroup:
            return None
        path = CGROUP_PIDS / f"ikteach-{os.getpid()}-{secrets.token_hex(4)}"
        path.mkdir()
        (path / "pids.max").write_text(str(self.limits.processes))
        return path

    def command(self, argv, work, cgroup):
        """The full command line: launcher (limits), then bwrap (if any), then argv."""
        lim = self.limits
        nproc = lim.processes if (not self.root and not self.cgroup) else 0
        launch = [sys.executable, "-S", str(LAUNCH), str(lim.cpu_seconds),
                  str(lim.memory_mb << 20), str(lim.file_mb << 20), str(nproc),
                  str(cgroup) if cgroup else "-", "--"]
        if not self.bwrap:
            return launch + list(argv)
        wrap = [self.bwrap, "--ro-bind", "/", "/", "--dev", "/dev", "--proc", "/proc",
                "--tmpfs", "/tmp", "--tmpfs", "/dev/shm"]
        tmp = Path("/tmp")
        kept = [p for p in self.needed if tmp in p.parents]  # a checkout or venv under /tmp
        kept = [p for p in kept if not any(q in p.parents for q in kept)]
        for path in kept:
            wrap += ["--ro-bind", str(path), str(path)]
        for path in self.hidden:  # under /tmp only what was bound back needs hiding again
            if tmp not in path.parents or any(k in path.parents for k in kept):
                wrap += ["--tmpfs", str(path)]
        wrap += ["--bind", str(work), str(work), "--chdir", str(work),
                 "--unshare-net", "--unshare-pid", "--unshare-ipc", "--unshare-uts",
                 "--die-with-parent", "--new-session", "--"]
        return launch + wrap + list(argv)

    def environment(self, work):
        home = Path(work) / "home"
        (home / "tmp").mkdir(parents=True, exist_ok=True)
        return {"PATH": f"{Path(sys.executable).parent}:/usr/local/bin:/usr/bin:/bin",
                "HOME": str(home), "TMPDIR": str(home / "tmp"), "LANG": "C.UTF-8",
                "MPLBACKEND": "Agg", "JAX_PLATFORMS": "cpu", "PYTHONDONTWRITEBYTECODE": "1",
                "PYTHONNOUSERSITE": "1"}

    def start(self, argv, work, **popen):
        """A running Process for argv in `work` (a folder the caller created)."""
        cgroup = self._cgroup_dir()
        proc = subprocess.Popen(self.command(argv, work, cgroup), cwd=work,
                                env=self.environment(work), **popen)
        return Process(proc, cgroup)


class Process:
    """A sandboxed process; end() kills it and everything it started."""

    def __init__(self, proc, cgroup):
        self.proc, self.cgroup = proc, cgroup

    def wait(self, timeout):
        """Its exit status, or None when it ran past `timeout` seconds (it is then ended)."""
        try:
            return self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.end()
            return None

    def end(self):
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        if self.cgroup:
            for _ in range(50):
                pids = (self.cgroup / "cgroup.procs").read_text().split()
                if not pids:
                    break
                for pid in pids:
                    try:
                        os.kill(int(pid), signal.SIGKILL)
                    except (ProcessLookupError, PermissionError):
                        pass
                time.sleep(0.02)
            try:
                self.cgroup.rmdir()
            except OSError:
                pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            pass
