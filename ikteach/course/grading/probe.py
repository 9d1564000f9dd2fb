"""The sandbox's start-up probe: run inside it as a job of the fork server (as a student's
code is), it tries what a student's code must not be able to do and answers what it saw.
Request: {"token": ..., "writes": [folders], "reads": [hidden folders], "port": N,
"imports_only": false}.

The grader checks the writes on its own side too (a write into a private /tmp succeeds in
here and escapes nowhere) and decides from this what its log may state (bwrap.judge).
"""
import ctypes
import ctypes.util
import json
import os
import signal
import socket

MS_REMOUNT, MS_BIND, CLONE_NEWUSER = 32, 4096, 0x10000000


def capabilities():
    bits = 0
    with open("/proc/self/status") as status:
        for line in status:
            if line.split(":")[0] in ("CapInh", "CapPrm", "CapEff", "CapBnd", "CapAmb"):
                bits |= int(line.split()[1], 16)
    return bits


def devices_owned():
    """Does the job own the machine's /dev/null? (a chmod to the mode it has)"""
    try:
        os.chmod("/dev/null", os.stat("/dev/null").st_mode & 0o7777)
        return True
    except OSError:
        return False


def wrote(folders, token):
    done = []
    for folder in folders:
        try:
            os.close(os.open(os.path.join(folder, f".ikteach-probe-{token}"),
                             os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
            done.append(folder)
        except OSError:
            pass
    return done


def readable(folders):
    """Hidden folders whose content shows (beyond the way down to this run's own folder)."""
    here, seen = os.getcwd(), []
    for folder in folders:
        try:
            names = set(os.listdir(folder))
        except OSError:
            continue
        if here.startswith(folder.rstrip("/") + "/"):
            names.discard(here[len(folder.rstrip("/")) + 1:].split("/")[0])
        if names:
            seen.append(folder)
    return seen


def connected(port):
    try:
        socket.create_connection(("127.0.0.1", port), timeout=2).close()
        return True
    except OSError:
        return False


def mounted(libc, package):
    os.makedirs("mnt", exist_ok=True)
    tmpfs = libc.mount(b"none", b"mnt", b"tmpfs", 0, None) == 0
    remount = libc.mount(None, package.encode(), None, MS_REMOUNT | MS_BIND, None) == 0
    return tmpfs or remount


def userns_blocked(libc):
    pid = os.fork()
    if pid == 0:  # in a child: a new user namespace would change this process for good
        os._exit(0 if libc.unshare(CLONE_NEWUSER) == 0 else 1)
    return os.waitpid(pid, 0)[1] != 0


def new_session():
    pid = os.fork()
    if pid == 0:  # in a child: setsid would take this process out of the job's session
        try:
            os.setsid()
            os._exit(0)
        except OSError:
            os._exit(1)
    return os.waitpid(pid, 0)[1] == 0


def kernel_writable():
    """What of the machine's kernel settings and its own OOM priority the job could change:
    /proc/sys files that open for writing (opened, never written) and whether its
    oom_score_adj goes down (then put back)."""
    opened = []
    for path in ("/proc/sys/kernel/core_pattern", "/proc/sys/vm/panic_on_oom",
                 "/proc/sysrq-trigger"):
        try:
            os.close(os.open(path, os.O_WRONLY))
            opened.append(path)
        except OSError:
            pass
    try:
        with open("/proc/self/oom_score_adj") as handle:
            before = handle.read().strip()
        with open("/proc/self/oom_score_adj", "w") as handle:
            handle.write("0")
        lowered = True
        with open("/proc/self/oom_score_adj", "w") as handle:
            handle.write(before)
    except OSError:
        lowered = False
    return {"kernel_settings": opened, "oom_lowered": lowered}


def job(requests_fd, replies_fd):
    """The probe as a job of the fork server (forkserver.py): the request on one pipe, what it
    saw on the other."""
    with os.fdopen(requests_fd, "r") as requests:
        request = json.loads(requests.readline())
    with os.fdopen(replies_fd, "w") as replies:
        replies.write(json.dumps(main(request)) + "\n")


def server_held(libc):
    """What the job could do to its fork server (PID 1 of the sandbox): each must be False."""
    PTRACE_ATTACH, PTRACE_DETACH = 16, 17
    held = {"ptrace": libc.ptrace(PTRACE_ATTACH, 1, None, None) == 0}
    if held["ptrace"]:
        libc.ptrace(PTRACE_DETACH, 1, None, None)
    try:
        with open("/proc/1/mem", "rb"):
            held["memory"] = True
    except OSError:
        held["memory"] = False
    try:
        os.kill(1, signal.SIGSTOP)  # init ignores it from inside its namespace
        with open("/proc/1/stat") as stat:
            held["stopped"] = stat.read().rsplit(")", 1)[1].split()[0] in "Tt"
        os.kill(1, signal.SIGCONT)
    except OSError:
        held["stopped"] = False
    return held


def main(request):
    libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
    package = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    seen = {}
    if not request.get("imports_only"):  # unsandboxed (the override): try nothing harmful
        seen = {"uid": os.getuid(), "capabilities": capabilities(), "devices_owned": devices_owned(),
                "wrote": wrote(request["writes"], request["token"]),
                "read": readable(request["reads"]), "connected": connected(request["port"]),
                "mounted": mounted(libc, package), "userns_blocked": userns_blocked(libc), "new_session": new_session(),
                "processes": sum(name.isdigit() for name in os.listdir("/proc")),
                "server": server_held(libc), **kernel_writable()}
    try:
        import IPython  # noqa: F401 - what a notebook's job needs
        import ikteach  # noqa: F401
        seen["import_error"] = None
    except BaseException as exc:  # noqa: B036 - reported to the grader
        seen["import_error"] = f"{type(exc).__name__}: {exc}"[:500]
    return seen
