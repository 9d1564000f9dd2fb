"""The bubblewrap command line of a sandboxed run, the flags this bwrap accepts, and what the
start-up probe (probe.py) must have seen for the log to say the sandbox holds.

A run sees a whitelist, read-only: the system folders (/usr, /lib...), a few files of /etc,
the grader's Python (prefixes and sys.path folders) and ikteach's package folder; hidden
folders inside those (the checker, the solutions...) get an empty read-only tmpfs. Its own
user namespace maps it to an unprivileged uid without capabilities (so a grader running as
root gives it no power to remount or to read what is laid over), and --disable-userns (where
this bwrap has it) stops it from making a new user namespace to regain them.
"""
import os
import subprocess
import sys
import tempfile
from pathlib import Path

SANDBOX_ID = "65534"  # uid and gid inside ("nobody")
SYSTEM = ("/usr", "/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32")
ETC = ("ld.so.cache", "ld.so.conf", "ld.so.conf.d", "localtime", "timezone", "passwd", "group",
       "nsswitch.conf", "hosts", "host.conf", "alternatives", "fonts", "mime.types",
       "os-release", "jupyter", "ipython", "matplotlibrc", "python3", "ssl/certs")
NAMESPACES = ["--unshare-user", "--uid", SANDBOX_ID, "--gid", SANDBOX_ID, "--cap-drop", "ALL",
              "--unshare-net", "--unshare-pid", "--unshare-ipc", "--unshare-uts",
              "--unshare-cgroup-try", "--die-with-parent", "--new-session"]
VARIANTS = (["--disable-userns"], [])  # tried in this order


class SandboxUnavailable(RuntimeError):
    """No backend isolates student code here; the message says what was tried and what to do."""


_is_dir = os.path.isdir


def _inside(path, folders):
    return any(path == f or f in path.parents for f in folders)


def python_paths(package):
    """What the grader's Python needs, outermost first: prefixes, the real executable's
    prefix, sys.path folders (not the working folder), and of the folder holding ikteach
    (a checkout: its solutions, tests...) only the package and what lies in the prefixes."""
    found = {Path(p).resolve() for p in (sys.prefix, sys.base_prefix, sys.exec_prefix,
                                         sys.base_exec_prefix)}
    found.add(Path(sys.executable).resolve().parents[1])
    skip = {Path.cwd().resolve(), Path(sys.argv[0] or ".").resolve().parent}
    prefixes = list(found)
    for entry in sys.path:
        if entry and os.path.isabs(entry) and os.path.isdir(entry):
            path = Path(entry).resolve()
            # not the folder ikteach lies in, nor others of it (a checkout's tests/...)
            if path not in skip and (not _inside(path, [package.parent])
                                     or _inside(path, prefixes)):
                found.add(path)
    found.add(package)
    system = [Path(d).resolve() for d in SYSTEM if os.path.isdir(d)]
    kept = sorted((p for p in found if not _inside(p, system) and p != Path("/")),
                  key=lambda p: len(p.parts))
    return [p for i, p in enumerate(kept) if not _inside(p, kept[:i])]


def command(bwrap, flags, package, hidden, work, pid1=False, copy=None):
    """bwrap ... -- (argv follows): the whitelist, read-only; `work` the only writable folder;
    `pid1`: argv is the PID namespace's init (the fork server) instead of bwrap's reaper;
    `copy`: a copy of ikteach shown in place of `package` (reference.py)."""
    args = [bwrap]
    for d in SYSTEM:
        if os.path.islink(d):
            args += ["--symlink", os.readlink(d), d]
        elif os.path.isdir(d):
            args += ["--ro-bind", d, d]
    for name in ETC:
        args += ["--ro-bind-try", f"/etc/{name}", f"/etc/{name}"]
    args += ["--ro-bind-try", "/sys/devices/system/cpu", "/sys/devices/system/cpu",
             "--proc", "/proc", "--dev", "/dev", "--tmpfs", "/tmp", "--tmpfs", "/dev/shm"]
    bound = python_paths(package)
    for path in bound:
        args += ["--ro-bind", str(path), str(path)]
    if copy is not None:
        args += ["--ro-bind", str(copy), str(package)]
    for path in hidden:  # only what lies inside a bound folder is visible at all
        if _inside(path, bound) and _is_dir(path):
            args += ["--tmpfs", str(path), "--remount-ro", str(path)]
    args += ["--remount-ro", "/", "--bind", str(work), str(work), "--chdir", str(work)]
    return args + NAMESPACES + (["--as-pid-1"] if pid1 else []) + list(flags) + ["--"]


def working_flags(bwrap):
    """(the extra flags this bwrap runs with, None) or (None, why it does not run)."""
    import ikteach

    package = Path(ikteach.__file__).resolve().parent
    why = "it does not run"
    with tempfile.TemporaryDirectory(prefix="ikteach-bwrap-") as work:
        for flags in VARIANTS:
            argv = command(bwrap, flags, package, [], Path(work)) + [sys.executable, "-S", "-c", ""]
            try:
                run = subprocess.run(argv, capture_output=True, timeout=30, cwd=work)
            except (OSError, subprocess.SubprocessError) as exc:
                return None, f"it does not run ({exc})"
            if run.returncode == 0:
                return flags, None
            text = run.stderr.decode(errors="replace").strip().splitlines()
            why = f"it fails here: {text[-1][:300] if text else f'exit status {run.returncode}'}"
    if "namespace" in why or "Operation not permitted" in why:
        why += (" (user namespaces are off: e.g. sysctl kernel.unprivileged_userns_clone=1, "
                "or inside Docker run with --security-opt seccomp=unconfined)")
    return None, why


def judge(seen, escaped, hidden):
    """The lines the log may state, from what the probe saw; raises SandboxUnavailable (with
    every property that does not hold) when the sandbox does not isolate."""
    failures = []
    if seen.get("uid") in (0, None):
        failures.append(f"the student's process runs as uid {seen.get('uid')}")
    if seen.get("capabilities") != 0:
        failures.append(f"the student's process keeps capabilities ({seen.get('capabilities')})")
    if escaped:  # seen from here: a write into the run's private /tmp goes nowhere
        failures.append(f"it could write in {', '.join(escaped)}")
    if seen.get("read"):
        failures.append(f"it could read the hidden {', '.join(seen['read'])}")
    if seen.get("connected"):
        failures.append("it could reach the grader's machine over the network")
    if seen.get("mounted"):
        failures.append("it could mount a file system")
    server = seen.get("server")
    if not isinstance(server, dict) or any(server.values()) or not server:
        failures.append(f"it could reach the fork server that starts every notebook ({server})")
    if failures:
        raise SandboxUnavailable("bubblewrap runs, but its sandbox does not hold: "
                                 + "; ".join(failures) + ".")
    lines = [f"runs as uid {seen['uid']} with no capabilities, in its own user namespace",
             "cannot mount or remount file systems",
             "no network (own network namespace; the grader's port was unreachable)",
             "no writes outside its working folder (tried the ikteach package, the Python "
             "prefix, the grader's folder, HOME, /tmp and the folders holding hidden ones)",
             "solutions, submissions, the checker and the grader's output hidden: "
             + ", ".join(str(p) for p in hidden)]
    if seen.get("processes", 99) <= 4:
        lines.append("own PID namespace per grading process, whose init is the fork server: "
                     "after each notebook's run and checks every other process in it is killed "
                     "and what they wrote removed")
    lines.append("cannot ptrace, read the memory of, or stop the fork server that starts every "
                 "notebook in a fresh child")
    if seen.get("userns_blocked"):
        lines.append("cannot create user namespaces (so it cannot regain capabilities)")
    return lines
