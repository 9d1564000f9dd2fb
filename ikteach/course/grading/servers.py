"""The grader's side of the fork server (forkserver.py): one server per sandbox in each grading
process, started on first use and replaced when it dies, hangs or reports that a job left
something it could not put back.

    job = server_for(sandbox).job("notebook", limit=60, setup={...})
    ... os.read(job.fileno(), ...) / job.write(...) ...
    done = job.end()          # every process of the job killed, its files gone

A job's two pipes are made here for that job alone and passed to the server with the request,
so nothing a finished job wrote can be read as the next job's answer.
"""
import atexit
import json
import os
import select
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

STARTUP_LIMIT = 120.0  # seconds for a server to import what the jobs need
END_LIMIT = 30.0       # seconds for a server to end a job and clean up after it

_servers = {}  # sandbox work_root -> Server, in this process


class ServerFailed(RuntimeError):
    """The fork server could not start (the message says why: e.g. an import error)."""


def server_for(sandbox, exercise=None):
    """This process's running server for `sandbox` and `exercise` (whose copy of ikteach it
    sees: reference.py), a new one if it has none or it broke."""
    key = (str(sandbox.work_root), exercise)
    for other in [k for k in _servers if k[0] == key[0] and k != key]:
        _servers.pop(other).stop()  # one server per sandbox at a time: each holds JAX
    server = _servers.get(key)
    if server is None or not server.alive():
        _servers[key] = server = Server(sandbox, exercise)
    return server


def close_all(sandbox=None):
    """Stop this process's servers (of `sandbox`; None: all)."""
    for key in [k for k in _servers if sandbox is None or k[0] == str(sandbox.work_root)]:
        _servers.pop(key).stop()


atexit.register(close_all)


class Server:
    def __init__(self, sandbox, exercise=None):
        self.sandbox, self.jobs, self.broken = sandbox, 0, False
        self.dir = Path(tempfile.mkdtemp(prefix="server-", dir=sandbox.work_root))
        try:
            ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        except (OSError, AttributeError) as exc:  # e.g. macOS: no SEQPACKET Unix sockets
            raise ServerFailed(f"this system cannot run the fork server ({exc}): grade on "
                               "Linux (README, Grading)") from None
        try:
            self.process = sandbox.start(
                [sys.executable, "-m", "ikteach.course.grading.forkserver", str(theirs.fileno()),
                 "1" if sandbox.bwrap else "0", str(sandbox.quota() if sandbox.bwrap else 0)],
                self.dir, pid1=True, exercise=exercise,
                pass_fds=(theirs.fileno(),),
                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        finally:
            theirs.close()
        self.control = ours
        hello = self.receive(STARTUP_LIMIT)
        if not hello or not hello.get("ready"):
            why = (hello or {}).get("import_error") or self._stderr()
            self.stop()
            raise ServerFailed(why or "it ended without a word")

    def _stderr(self):
        try:
            self.process.end()
            lines = self.process.proc.stderr.read(1 << 16).decode(errors="replace").splitlines()
            return lines[-1].strip() if lines else ""  # e.g. an import error at start-up
        except (OSError, ValueError):
            return ""

    def alive(self):
        return not self.broken and self.process.proc.poll() is None

    def receive(self, timeout):
        """The server's next message (a dict), or None when it is gone or silent that long."""
        if not select.select([self.control], [], [], max(0.0, timeout))[0]:
            return None
        try:
            data = self.control.recv(1 << 16)
            return json.loads(data) if data else None
        except (OSError, ValueError):
            return None

    def job(self, kind, limit, setup):
        """Start a job (its child runs `kind` with `setup` as its first request line)."""
        self.jobs += 1
        requests_r, requests_w = os.pipe()
        replies_r, replies_w = os.pipe()
        try:
            message = {"job": self.jobs, "kind": kind, "limit": float(limit)}
            socket.send_fds(self.control, [json.dumps(message).encode()],
                            [requests_r, replies_w])
        except OSError:
            self.broken = True
            for fd in (requests_w, replies_r):
                os.close(fd)
            raise
        finally:
            os.close(requests_r)
            os.close(replies_w)
        job = Job(self, self.jobs, requests_w, replies_r)
        try:
            job.write((json.dumps(setup) + "\n").encode())
        except OSError:  # the child ended before reading it; its end says why
            pass
        return job

    def stop(self):
        self.broken = True
        try:
            self.control.close()
        finally:
            self.process.end()  # the whole sandbox, its process group and namespace


class Job:
    """One job's pipes; end() (always called) ends it and returns the server's report:
    {"status": exit status or None, "timed_out": bool} (status None also when it was stopped)."""

    def __init__(self, server, number, requests, replies):
        self.server, self.number = server, number
        self.requests, self.replies = requests, replies
        self.report = None

    def fileno(self):
        return self.replies

    def write(self, data):
        view = memoryview(data)
        while view:
            view = view[os.write(self.requests, view):]

    def end(self, wait_for_exit=0.0):
        """End the job (after waiting up to `wait_for_exit` s for its child to end by itself)."""
        if self.report is not None:
            return self.report
        for fd in (self.requests, self.replies):
            os.close(fd)
        server = self.server
        report = server.receive(wait_for_exit) if wait_for_exit > 0 else None
        if report is None and server.alive():
            try:
                server.control.send(json.dumps({"end": self.number}).encode())
            except OSError:
                server.broken = True
        deadline = time.monotonic() + END_LIMIT
        while report is None or report.get("done") != self.number:
            report = server.receive(deadline - time.monotonic())
            if report is None:  # gone or hung: ended from outside, as a whole
                server.stop()
                report = {"done": self.number, "status": None, "timed_out": False}
                break
        if report.get("dirty"):
            server.stop()  # the next job gets a fresh server
        self.report = report
        return report
