"""Each student process runs in a sandbox; without one the grader refuses to run student code
(unless told: `unsandboxed=True`, the grader's --no-sandbox).

Backend: bubblewrap (`bwrap`; Debian/Ubuntu/Fedora/Arch package `bubblewrap`): what a run sees
and may do is bwrap.py's command line, seccomp filter and drop of root. Always: own HOME, bare
environment (BLAS kernel variables passed through: the student's numbers come from the grader's
kernels), resource limits (CPU time, address space, file size, no core files), its own process
group (ended as a whole, from outside), the OOM killer's first choice; where this process may
make cgroups (v1 pids/memory/cpu, or v2), one per sandbox: processes, memory of its processes and
files together, an equal CPU share; else RLIMIT_NPROC (not for root).
Student code runs in jobs of a fork server started in the sandbox (servers.py, forkserver.py).
`Sandbox.verify()` runs a probe as such a job and `report()` states only what the probe saw
hold (the lecturers' guide's table says the same, with each row's test).
"""
import dataclasses
import json
import os
import secrets
import select
import shutil
import socket
import subprocess
import sys
import tempfile
from pathlib import Path

from . import bwrap as _bwrap
from .bwrap import SandboxUnavailable
from .process import Process

__all__ = ["Limits", "Process", "Sandbox", "SandboxUnavailable", "refusal"]

CGROUP_FS = Path("/sys/fs/cgroup")
# a sandbox's cgroup (v1: one per controller; v2: one): {limit file: Limits field}
CGROUP_LIMITS = {"pids.max": "processes", "memory.limit_in_bytes": "memory_mb",
                 "memory.max": "memory_mb"}
# BLAS/LAPACK kernel and thread settings: the student's process must compute with the same
# kernels as the grader's (another OpenBLAS kernel changes the last bits of an SVD)
PASSED_THROUGH = ("OPENBLAS_CORETYPE", "OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS",
                  "OMP_NUM_THREADS", "MKL_NUM_THREADS", "MKL_CBWR", "MKL_ENABLE_INSTRUCTIONS",
                  "MKL_DEBUG_CPU_TYPE", "NPY_DISABLE_CPU_FEATURES")
INSTALL_HINT = ("install bubblewrap (Debian/Ubuntu: sudo apt-get install bubblewrap; Fedora: "
                "sudo dnf install bubblewrap; Arch: sudo pacman -S bubblewrap); on macOS or "
                "Windows grade inside a Linux VM or container that has it (README, Grading)")
OVERRIDE = "--no-sandbox"


@dataclasses.dataclass(frozen=True)
class Limits:
    cpu_seconds: int = 600
    memory_mb: int = 4096
    processes: int = 256
    jobs: int = 1  # sandboxes at once (the grader's --jobs): each gets its own process quota
    file_mb: int = 256
    tmpfs_mb: int = 256  # each of a sandbox's /tmp, /dev/shm and working folder

    def cgroup_value(self, field):
        value = getattr(self, field)
        return value << 20 if field.endswith("_mb") else value


def _cgroup_parents():
    """This process's own cgroups (pids, memory, cpu of v1; the v2 tree) where it may make
    one for a sandbox: {folder: the controllers a child there gets}."""
    try:
        lines = Path("/proc/self/cgroup").read_text().splitlines()
    except OSError:
        return {}
    found = {}
    for line in lines:
        _, controllers, path = line.split(":", 2)
        for name in controllers.split(",") if controllers else [""]:
            if name in ("pids", "memory", "cpu") or (
                    not name and (CGROUP_FS / "cgroup.controllers").exists()):
                folder = CGROUP_FS / name / path.lstrip("/")
                probe = folder / f"ikteach-probe-{secrets.token_hex(4)}"
                try:
                    probe.mkdir()
                except OSError:
                    continue
                files = {f.name for f in probe.iterdir()}
                probe.rmdir()
                found[folder] = ({"pids": "pids.max", "memory": "memory.max" if not name else
                                  "memory.limit_in_bytes", "cpu": "cpu.weight" if not name else
                                  "cpu.shares"}, files)
    return {folder: {c for c, f in kinds.items() if f in files}
            for folder, (kinds, files) in found.items()}


def refusal(tried):
    return ("no sandbox for the students' code on this machine, so nothing was graded.\n"
            + "".join(f"  tried: {line}\n" for line in tried)
            + f"  to fix: {INSTALL_HINT}.\n"
            f"  to grade anyway, WITHOUT isolation (every student's code then runs with your "
            f"rights: it can read and change your files and use the network), pass {OVERRIDE}.")


class Sandbox:
    """How student processes are started. `hidden`: folders they must not see; `bwrap`: a path,
    False (do not use it) or None (find it); `unsandboxed`: run without isolation (the override).
    Raises SandboxUnavailable when no backend works and `unsandboxed` is false."""

    def __init__(self, hidden=(), limits=Limits(), bwrap=None, unsandboxed=False):
        self.limits = limits
        self.work_root = Path(tempfile.mkdtemp(prefix="ikteach-grade-")).resolve()
        self.package = Path(__file__).resolve().parents[2]  # ikteach/
        self.hidden = [Path(p).resolve() for p in hidden if p and os.path.lexists(p)]
        self.hidden += [self.package / "course" / "check", self.work_root]  # the checker too
        self.cgroups = _cgroup_parents()
        self.controlled = set().union(*self.cgroups.values())
        self.root = os.geteuid() == 0
        if self.root:  # its copies of ikteach are read by the sandbox's uid, not root (bwrap.py)
            os.chmod(self.work_root, 0o711)
        self.tried, self.verified, self.flags, self.sized_tmpfs = [], [], None, False
        self.bwrap = None
        path = shutil.which("bwrap") if bwrap is None else (bwrap or None)
        if bwrap is False:
            self.tried.append("bubblewrap: not used (told not to)")
        elif not path:
            self.tried.append("bubblewrap: `bwrap` not found on PATH")
        else:
            variant, why = _bwrap.working_flags(path)
            if variant is None:
                self.tried.append(f"bubblewrap ({path}): {why}")
            else:
                self.bwrap, (self.flags, self.sized_tmpfs) = path, variant
        self.unsandboxed = self.bwrap is None and bool(unsandboxed)
        if self.bwrap is None and not unsandboxed:
            self.close()
            raise SandboxUnavailable(refusal(self.tried))

    @property
    def backend(self):
        return "bubblewrap" if self.bwrap else f"none ({OVERRIDE})"

    def close(self):
        """Stop this process's fork servers of this sandbox (their cgroups removed), then
        remove its folder."""
        from .servers import close_all

        close_all(self)
        shutil.rmtree(self.work_root, ignore_errors=True)

    def verify(self):
        """Run the probe as a job of the fork server, as a student's code runs; what it saw
        hold becomes report()'s lines. Raises SandboxUnavailable when bubblewrap runs but does
        not isolate, or when the grader's own Python or ikteach cannot run in the sandbox."""
        from .servers import ServerFailed, server_for

        server = socket.socket()
        server.bind(("127.0.0.1", 0))
        server.listen()
        token = secrets.token_hex(6)
        outside = sorted({str(self.package), sys.prefix, os.getcwd(), str(Path.home()),
                          tempfile.gettempdir()} | {str(p.parent) for p in self.hidden})
        request = {"token": token, "writes": outside, "reads": [str(p) for p in self.hidden],
                   "port": server.getsockname()[1], "imports_only": not self.bwrap}
        out = b""
        try:
            job = server_for(self).job("probe", 120, request)
            try:
                while select.select([job], [], [], 120)[0]:
                    chunk = os.read(job.fileno(), 1 << 16)
                    if not chunk:
                        break
                    out += chunk
            finally:
                job.end(wait_for_exit=5)
        except ServerFailed as exc:
            raise SandboxUnavailable("the grader's Python or packages do not work in the "
                                     f"sandbox: {exc}") from None
        finally:
            server.close()
        marker = f".ikteach-probe-{token}"
        escaped = [d for d in outside if os.path.lexists(os.path.join(d, marker))]
        for d in escaped:
            os.unlink(os.path.join(d, marker))
        try:
            seen = json.loads(out.decode(errors="replace").strip().splitlines()[-1])
        except (ValueError, IndexError):
            raise SandboxUnavailable(f"the sandbox self-check could not run Python "
                                     f"({sys.executable}) in the sandbox: {out[-600:]}") from None
        if seen.get("import_error"):
            raise SandboxUnavailable("the grader's Python or packages do not work in the sandbox: "
                                     f"{seen['import_error']}")
        if self.bwrap:
            self.verified = _bwrap.judge(seen, escaped, self.hidden)
        return self.verified

    def report(self):
        """(enforced, not enforced): lists of short lines for the grader's log."""
        lim, has = self.limits, self.controlled
        yes = ["own temporary working folder and HOME, bare environment",
               f"CPU time {lim.cpu_seconds} s per process (RLIMIT_CPU)",
               f"memory {lim.memory_mb} MiB address space per process (RLIMIT_AS)",
               f"file size {lim.file_mb} MiB (RLIMIT_FSIZE), no core files",
               "wall-clock time limits, applied from outside; the process group is killed "
               "as a whole",
               "when memory runs out, the kernel ends students' processes first "
               "(oom_score_adj 1000), never the grader"]
        no = []
        if "memory" in has:
            yes.append(f"memory: at most {lim.memory_mb} MiB for a sandbox's processes and "
                       "files together (cgroup)")
        else:
            no.append("memory of a job's processes together (no memory cgroup here): bounded "
                      "per process and by the file systems' sizes only")
        if "cpu" in has:
            yes.append("CPU: each sandbox (one notebook at a time) an equal share (cgroup)")
        if "pids" in has:
            yes.append(f"processes: at most {lim.processes} (cgroup pids.max)")
        elif not self.root:
            yes.append(f"processes: at most {lim.processes} per sandbox (RLIMIT_NPROC in its "
                       "user namespace; the user's limit leaves room for every sandbox's)"
                       if self.bwrap else
                       f"processes: at most {lim.processes} for this user (RLIMIT_NPROC)")
        else:
            no.append("process count (root ignores RLIMIT_NPROC and the pids cgroup is not "
                      "writable): a fork storm is bounded only by the CPU and time limits")
        if self.bwrap:
            yes += [f"{line} (checked at start-up)" for line in self.verified]
            if self.sized_tmpfs:
                yes.append(f"its files: /tmp, /dev/shm and its working folder in memory, at "
                           f"most {lim.tmpfs_mb} MiB each; /dev read-only")
            else:
                no.append("the size of /tmp, /dev/shm and the working folder (this bwrap has "
                          "no --size): files there are bounded by memory only")
            yes.append("visible, read-only, by its mount list (probed only as above): the "
                       "system libraries, the grader's Python, ikteach's package without its "
                       "checker; nothing else of this machine")
            if not any(line.startswith("cannot write /proc") for line in self.verified):
                no.append("a job's own OOM priority and /proc files it owns (no Landlock in "
                          "this kernel): it can lower its oom_score_adj")
            no.append("a kernel exploit (bubblewrap shares this machine's kernel)")
        else:
            no += [f"ISOLATION: NONE ({OVERRIDE}): students' code runs with this user's rights",
                   "network access, writes wherever this user may write, reading the solutions "
                   "and other students' files",
                   "processes that leave the process group (setsid) may outlive the run"]
        return yes, no

    def _cgroups(self):
        """New cgroups for one sandbox (with its limits written); [] where there are none."""
        made = []
        for parent, controllers in self.cgroups.items():
            path = parent / f"ikteach-{os.getpid()}-{secrets.token_hex(4)}"
            try:
                path.mkdir()
            except OSError:
                continue
            made.append(path)
            for name, field in CGROUP_LIMITS.items():
                try:
                    (path / name).write_text(str(self.limits.cgroup_value(field)))
                except OSError:  # not this cgroup version's file, or not writable
                    pass
        return made

    def package_for(self, exercise):
        """The copy of ikteach that the jobs of `exercise` see (None: a probe's, nothing
        stubbed): reference.py, the reference rule."""
        from ..check import EXERCISES
        from .reference import sandbox_copy

        folder = self.work_root / f"package-{exercise or 0}"
        folder.mkdir(exist_ok=True)
        if exercise is None:
            return sandbox_copy(self.package, folder / "ikteach")
        return sandbox_copy(self.package, folder / "ikteach", EXERCISES[exercise].REFERENCES,
                            exercise, base=self.package_for(None))

    def quota(self):
        """Processes of one sandbox, where it is bounded by RLIMIT_NPROC (an ordinary user
        without a pids cgroup; 0: not so bounded)."""
        return self.limits.processes if not self.root and "pids" not in self.controlled else 0

    def outer_nproc(self):
        """RLIMIT_NPROC from outside: this user's processes now plus every sandbox's quota.
        Linux (5.14+) counts a user namespace's processes apart and also against the limit its
        creator had: each sandbox's fork server lowers its own to quota(), so one sandbox's fork
        storm stops at its quota, never at the user's, and a classmate's sandbox can still fork."""
        if not self.quota():
            return 0
        uid, mine = os.getuid(), 0
        for name in os.listdir("/proc"):
            try:
                mine += name.isdigit() and os.stat(f"/proc/{name}").st_uid == uid
            except OSError:
                continue
        if not self.bwrap:
            return self.limits.processes
        return mine + self.limits.jobs * (self.quota() + 16) + 64

    def command(self, argv, work, cgroups, pid1=False, seccomp=None, package=None):
        """The full command line: launcher (limits), then bwrap (if any), then argv (`pid1`:
        as the init of its PID namespace; `seccomp`: the fd of bwrap's filter; `package`: the
        copy of ikteach it sees)."""
        lim = self.limits
        nproc = self.outer_nproc()
        launch = [sys.executable, "-S", str(_bwrap.LAUNCH), str(lim.cpu_seconds),
                  str(lim.memory_mb << 20), str(lim.file_mb << 20), str(nproc),
                  ",".join(map(str, cgroups)) or "-", "--"]
        if not self.bwrap:
            return launch + list(argv)
        tmpfs = lim.tmpfs_mb << 20 if self.sized_tmpfs else None
        return launch + _bwrap.unprivileged(_bwrap.command(
            self.bwrap, self.flags, self.package, self.hidden, Path(work), pid1, tmpfs, seccomp,
            package) + list(argv))

    def environment(self, work, package=None):
        """The bare environment of a run; `package`: the copy of ikteach it imports (without
        bubblewrap, which shows the copy in ikteach's own place)."""
        home = Path(work) / "home"
        (home / "tmp").mkdir(parents=True, exist_ok=True)
        env = {"PATH": f"{Path(sys.executable).parent}:/usr/local/bin:/usr/bin:/bin",
               "HOME": str(home), "TMPDIR": str(home / "tmp"), "LANG": "C.UTF-8",
               "MPLBACKEND": "Agg", "JAX_PLATFORMS": "cpu", "PYTHONDONTWRITEBYTECODE": "1",
               "PYTHONNOUSERSITE": "1", "PYTHONPATH": str((package or self.package).parent)}
        env.update({k: os.environ[k] for k in PASSED_THROUGH if k in os.environ})
        return env

    def start(self, argv, work, pid1=False, pass_fds=(), exercise=None, **popen):
        """A running Process for argv in `work` (a folder the caller created), seeing the copy
        of ikteach made for `exercise`."""
        cgroups = self._cgroups()
        package = self.package_for(exercise)
        seccomp = _bwrap.seccomp_fd() if self.bwrap else None
        fds = tuple(pass_fds) + ((seccomp,) if seccomp is not None else ())
        try:  # bubblewrap shows the copy where ikteach lies; without it, PYTHONPATH names it
            proc = subprocess.Popen(self.command(argv, work, cgroups, pid1, seccomp, package),
                                    cwd=work, env=self.environment(work, None if self.bwrap
                                                                   else package),
                                    pass_fds=fds, **popen)
        finally:
            if seccomp is not None:
                os.close(seccomp)
        return Process(proc, cgroups)
