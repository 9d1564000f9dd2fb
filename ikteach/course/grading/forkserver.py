"""The fork server: one per sandbox and grading process, it pays Python's, JAX's and ikteach's
start-up once and forks a fresh child for every job (a notebook's cells and then its checks'
calls, cells.py; the start-up probe). Runs inside the sandbox (bubblewrap --as-pid-1: it is
the PID namespace's init), started by servers.py:

    python -m ikteach.course.grading.forkserver CONTROL_FD SANDBOXED(0|1) NPROC

NPROC (0: leave it): the processes its sandbox may have (RLIMIT_NPROC, set by the server on
itself before any job: sandbox.py's quota()).

Each child starts from the server's state, which no student code ever ran in: the server only
imports modules and never starts JAX's backend (so it has one thread, and a fork copies it
whole). A child gets its own session, a new empty folder (cwd, HOME, TMPDIR) and only its two
job pipes; everything else the server holds is closed in it. When the child ends (or the
grader says so, or its time limit passes) the server, as PID 1, kills every other process of
the namespace (kill(-1): daemons, setsid, fork storms), reaps them, removes the job's folder,
whatever appeared in the sandbox's writable /tmp and /dev, and SysV IPC objects; if anything
there that existed before was changed (a /dev node replaced, /tmp's mode, an extended attribute
or ACL there or on the server's folder: Landlock governs no metadata), or its own limits,
priority, CPU set or OOM score are not those it started with (a job may `prlimit` its server:
same uid), it says `dirty` and the grader starts a fresh server: every job starts with the
limits the grader set from outside. In the sandbox a job's child may write only beneath its
folder, /tmp (the server's folder too, where it lies there), /dev/shm and /dev's devices
(Landlock, where the kernel has it: not its own oom_score_adj or /proc/sys). The server is
not dumpable (no ptrace, no /proc/1/mem) and, as init, ignores every signal from inside the
namespace that it has no handler for.

Control messages (JSON over a SOCK_SEQPACKET socket, the job's pipes passed with SCM_RIGHTS):
  -> {"job": id, "kind": "notebook"|"fingerprints"|"probe", "limit": s}  + fds (requests in,
                                                            replies out)
  -> {"end": id}                                            the grader is done with the job
  <- {"done": id, "status": exit status or null, "timed_out": bool, "dirty": bool}
"""
import contextlib
import ctypes
import ctypes.util
import fcntl
import json
import os
import select
import shutil
import signal
import socket
import stat
import sys
import time

from ikteach.course.grading import landlock

PR_SET_DUMPABLE, PR_SET_CHILD_SUBREAPER = 4, 36
IPC_RMID = 0
SHARED = ("/tmp", "/dev")  # what the sandbox user can write besides the job folder (probed)
WRITABLE = ("/tmp", "/dev/shm")  # where a job may write besides its folder (Landlock)


def preload():
    """Everything a job imports, imported once here; JAX's backend is not started."""
    import IPython.core.interactiveshell  # noqa: F401 - the cells' shell
    import matplotlib.pyplot  # noqa: F401
    import numpy  # noqa: F401

    import ikteach  # noqa: F401
    import ikteach.core.solve  # noqa: F401
    from ikteach.course.grading import cells, own_code, probe, remote  # noqa: F401


def _libc():
    return ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)


def _prctl(libc, option, value):
    """Linux's prctl; elsewhere (only ever unsandboxed) there is nothing to set."""
    if hasattr(libc, "prctl"):
        libc.prctl(option, value, 0, 0, 0)


def _xattrs(path):
    """A path's extended attributes, POSIX ACLs included (they are xattrs)."""
    try:
        return tuple(sorted((name, os.getxattr(path, name, follow_symlinks=False))
                            for name in os.listxattr(path, follow_symlinks=False)))
    except (OSError, AttributeError):  # no xattrs here (a file system, or not Linux)
        return ()


def _state(roots, keep):
    """{path: (mode, uid, inode, xattrs)} of everything under `roots` (not following links),
    except what lies inside `keep` (the server's own folder)."""
    seen = {}
    for root in roots:
        for folder, dirs, files in os.walk(root):
            dirs[:] = [d for d in dirs if os.path.join(folder, d) != keep]
            for name in [""] + dirs + files:  # the folder itself, then its entries
                path = os.path.join(folder, name) if name else folder
                try:
                    st = os.lstat(path)
                except OSError:
                    continue
                seen[path] = (st.st_mode, st.st_uid, st.st_ino, _xattrs(path))
    st = os.lstat(keep)
    seen[keep] = (st.st_mode, st.st_uid, st.st_ino, _xattrs(keep))
    return seen


def own_state(libc):
    """What a job could change of this process from outside it (same uid): its limits, nice
    value, CPU set, scheduler and OOM score."""
    import resource

    limits = {name: resource.getrlimit(getattr(resource, name)) for name in dir(resource)
              if name.startswith("RLIMIT_")}
    try:
        with open("/proc/self/oom_score_adj") as handle:
            oom = handle.read().strip()
    except OSError:
        oom = None
    affinity = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None
    scheduler = os.sched_getscheduler(0) if hasattr(os, "sched_getscheduler") else None
    return {"limits": limits, "nice": os.getpriority(os.PRIO_PROCESS, 0), "oom": oom,
            "affinity": affinity, "scheduler": scheduler}


def _remove(path):
    try:
        if stat.S_ISDIR(os.lstat(path).st_mode):
            shutil.rmtree(path, ignore_errors=True)
        else:
            os.unlink(path)
    except OSError:
        pass


def _remove_ipc(libc):
    for kind, call in (("shm", libc.shmctl), ("msg", libc.msgctl), ("sem", libc.semctl)):
        try:
            with open(f"/proc/sysvipc/{kind}") as table:
                ids = [int(line.split()[1]) for line in table.readlines()[1:] if line.strip()]
        except (OSError, ValueError, IndexError):
            continue
        for ident in ids:
            call(ident, IPC_RMID, None) if kind != "sem" else call(ident, 0, IPC_RMID, None)


class Server:
    def __init__(self, control, sandboxed, nproc=0):
        self.control, self.sandboxed, self.nproc = control, sandboxed, nproc
        self.libc = _libc()
        self.home = os.getcwd()  # the server's own folder (bound read-write)
        self.pid1 = os.getpid() == 1
        self.baseline, self.state, self.times = None, None, {}

    def start(self):
        import resource

        if self.nproc:  # this sandbox's user namespace: its own count of processes
            resource.setrlimit(resource.RLIMIT_NPROC, (self.nproc, self.nproc))
        _prctl(self.libc, PR_SET_DUMPABLE, 0)
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        if not self.pid1:  # unsandboxed: orphans of a job come back here, to be ended
            _prctl(self.libc, PR_SET_CHILD_SUBREAPER, 1)
        if self.sandboxed:
            if not self.pid1:
                raise RuntimeError("the fork server must be PID 1 of its sandbox")
            self.baseline = _state(SHARED, self.home)
            self.times = {p: (st.st_atime_ns, st.st_mtime_ns)
                          for p, st in ((p, os.lstat(p)) for p in self.baseline)}
        self.state = own_state(self.libc)

    def send(self, message):
        self.control.send(json.dumps(message).encode())

    def serve(self):
        while True:
            message, fds, _, _ = socket.recv_fds(self.control, 1 << 16, 2)
            if not message:
                return  # the grader is gone
            request = json.loads(message)
            if "job" not in request or len(fds) != 2:
                for fd in fds:
                    os.close(fd)
                continue
            self.send(self.run(request, fds))

    def run(self, request, fds):
        job = os.path.join(self.home, f"job-{int(request['job'])}")
        os.makedirs(os.path.join(job, "home", "tmp"))
        pid = os.fork()
        if pid == 0:
            _child(request["kind"], fds, job, self.control.fileno(), self.sandboxed)
        for fd in fds:
            os.close(fd)
        status, timed_out = self.wait(pid, request)
        self.end_all(pid)
        dirty = self.clean()
        return {"done": request["job"], "status": status, "timed_out": timed_out, "dirty": dirty}

    def wait(self, pid, request):
        """(exit status or None, timed out?): the child's end, the grader's `end`, or the limit."""
        deadline = time.monotonic() + float(request["limit"])
        while True:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                return (os.waitstatus_to_exitcode(status), False)
            left = deadline - time.monotonic()
            if left <= 0:
                return None, True
            if select.select([self.control], [], [], min(left, 0.02))[0]:
                message = self.control.recv(1 << 16)
                if not message or json.loads(message).get("end") == request["job"]:
                    return None, False

    def end_all(self, pid):
        """Kill the job's processes, all of them, and reap them."""
        if self.pid1:  # init of the namespace: every other process in it is the job's
            for _ in range(100):
                try:
                    os.kill(-1, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                try:
                    while os.waitpid(-1, 0):
                        pass
                except ChildProcessError:
                    return
        for _ in range(100):  # unsandboxed: its process group, then its orphans (subreaper)
            try:
                os.killpg(pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
            orphans = _children()
            for child in orphans:
                try:
                    os.kill(child, signal.SIGKILL)
                except ProcessLookupError:
                    pass
            try:
                while os.waitpid(-1, os.WNOHANG)[0]:
                    pass
            except ChildProcessError:
                pass
            if not orphans and not _children():
                return

    def clean(self):
        """Remove what the job left: its folder (all of the server's folder but the folder
        itself) and, in the sandbox, whatever is new in the shared places and SysV IPC objects.
        True when something is left or was changed that cannot be put back, this process's own
        limits and priorities included (the server must then be replaced)."""
        for name in os.listdir(self.home):
            _remove(os.path.join(self.home, name))
        left = bool(os.listdir(self.home)) or own_state(self.libc) != self.state
        if not self.sandboxed:
            return left
        _remove_ipc(self.libc)
        for path in sorted(set(_state(SHARED, self.home)) - set(self.baseline), key=len):
            _remove(path)
        for path, times in self.times.items():  # times a job set are a message to the next
            with contextlib.suppress(OSError):
                os.utime(path, ns=times, follow_symlinks=False)
        return left or _state(SHARED, self.home) != self.baseline


def _children():
    """This process's live children (by /proc; none found where there is no /proc)."""
    me, found = str(os.getpid()), []
    for name in os.listdir("/proc") if os.path.isdir("/proc") else []:
        if name.isdigit():
            try:
                with open(f"/proc/{name}/stat") as handle:
                    fields = handle.read().rsplit(")", 1)[1].split()
            except (OSError, IndexError):
                continue
            if fields[1] == me and fields[0] != "Z":
                found.append(int(name))
    return found


def _child(kind, fds, job, control, sandboxed):
    """The job's process: fresh session and folder, only its pipes; never returns."""
    code = 1
    try:
        try:
            os.setsid()
        except PermissionError:  # in the sandbox: no new sessions (seccomp); its PID namespace
            pass                 # ends it
        for number in (signal.SIGCHLD, signal.SIGTERM, signal.SIGALRM):
            signal.signal(number, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        _prctl(_libc(), PR_SET_DUMPABLE, 1)  # an ordinary process, as a kernel was
        os.close(control)
        high = [fcntl.fcntl(fd, fcntl.F_DUPFD, 100) for fd in fds]  # out of 3 and 4's way
        requests, replies = os.dup2(high[0], 3), os.dup2(high[1], 4)
        os.closerange(5, 1 << 16)
        null = os.open(os.devnull, os.O_RDWR)
        for fd in (0, 1, 2):
            os.dup2(null, fd)
        os.close(null)
        os.chdir(job)
        os.environ.update(HOME=os.path.join(job, "home"), TMPDIR=os.path.join(job, "home", "tmp"),
                          IKTEACH_JAX_CACHE="off")  # no compile cache: it would go with the job
        if sandboxed:
            landlock.restrict([job] + list(WRITABLE))
        if kind == "notebook":
            from ikteach.course.grading import cells
            cells.main(requests, replies)
        elif kind == "fingerprints":  # of the cells' source, where no student code has run
            from ikteach.course.grading import reference
            cells = json.loads(os.fdopen(requests, encoding="utf-8", errors="replace").readline())
            found = reference.source_fingerprints([(int(n), str(s)) for n, s in cells["cells"]])
            os.write(replies, (json.dumps(found) + "\n").encode())
        elif kind == "probe":
            from ikteach.course.grading import probe
            probe.job(requests, replies)
        code = 0
    finally:
        os._exit(code)


def main(argv):
    control = socket.socket(fileno=int(argv[0]))
    null = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1):
        os.dup2(null, fd)
    try:
        preload()
        server = Server(control, argv[1] == "1", int(argv[2]) if len(argv) > 2 else 0)
        server.start()
        hello = {"ready": True, "import_error": None}
    except BaseException as exc:  # noqa: B036 - reported to the grader
        control.send(json.dumps({"ready": False, "import_error":
                                 f"{type(exc).__name__}: {exc}"[:500]}).encode())
        return 1
    server.send(hello)
    os.dup2(null, 2)  # from here on nothing is read from its stderr: never let it fill a pipe
    server.serve()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
