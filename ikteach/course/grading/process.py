"""A process the sandbox started: its CPU clock (the student's own work) and its end (it and
everything it started killed, its cgroups removed)."""
import contextlib
import os
import signal
import subprocess
import time


class Process:
    """A sandboxed process; end() kills it and everything it started."""

    def __init__(self, proc, cgroups):
        self.proc, self.cgroups = proc, cgroups

    def cpu_seconds(self):
        """CPU seconds its process tree has used (the live processes, with the children they
        reaped), read from /proc: the student's own work, whatever else the machine runs."""
        parents, used = {}, {}
        for name in filter(str.isdigit, os.listdir("/proc")):
            try:
                with open(f"/proc/{name}/stat", "rb") as handle:
                    fields = handle.read().rsplit(b")", 1)[1].split()
                parents.setdefault(int(fields[1]), []).append(int(name))
                used[int(name)] = sum(map(int, fields[11:15]))  # utime stime cutime cstime
            except (OSError, ValueError, IndexError):
                continue
        tree, total = [self.proc.pid], 0
        while tree:
            pid = tree.pop()
            total += used.get(pid, 0)
            tree += parents.get(pid, [])
        return total / os.sysconf("SC_CLK_TCK")

    def end(self):
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            pass
        deadline = time.monotonic() + 10
        for cgroup in self.cgroups:  # removed once empty (unsandboxed: what left by setsid)
            while cgroup.exists() and time.monotonic() < deadline:
                try:
                    cgroup.rmdir()
                except OSError:  # busy: processes still dying, or ones that left the group
                    with contextlib.suppress(OSError):
                        for pid in (cgroup / "cgroup.procs").read_text().split():
                            with contextlib.suppress(OSError):
                                os.kill(int(pid), signal.SIGKILL)
                    time.sleep(0.02)
