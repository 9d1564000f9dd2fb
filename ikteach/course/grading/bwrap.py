"""The bubblewrap command line of a sandboxed run, the flags this bwrap accepts, and what the
start-up probe (probe.py) must have seen for the log to say the sandbox holds.

A run sees a whitelist, read-only: the system folders (/usr, /lib...), a few files of /etc,
the grader's Python (prefixes and sys.path folders) and ikteach's package folder; hidden
folders inside those (the checker, the solutions...) get an empty read-only tmpfs. Its own
user namespace maps it to an unprivileged uid without capabilities, and --disable-userns (where
this bwrap has it) stops it from making a new user namespace to regain them. That namespace's
uid is, outside, the uid that starts bwrap: a grader run as root starts it as SANDBOX_ID
(unprivileged()), so that no job owns what root owns, such as the device nodes every sandbox binds.
"""
import os
import subprocess
import sys
import tempfile
from pathlib import Path

SANDBOX_ID = "65534"  # uid and gid inside ("nobody"), and outside when the grader is root
LAUNCH = Path(__file__).with_name("_launch.py")
SYSTEM = ("/usr", "/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32")
ETC = ("ld.so.cache", "ld.so.conf", "ld.so.conf.d", "localtime", "timezone", "passwd", "group",
       "nsswitch.conf", "hosts", "host.conf", "alternatives", "fonts", "mime.types",
       "os-release", "jupyter", "ipython", "matplotlibrc", "python3", "ssl/certs")
NAMESPACES = ["--unshare-user", "--uid", SANDBOX_ID, "--gid", SANDBOX_ID, "--cap-drop", "ALL",
              "--unshare-net", "--unshare-pid", "--unshare-ipc", "--unshare-uts",
              "--unshare-cgroup-try", "--die-with-parent", "--new-session"]
# (extra flags, sized tmpfs), tried in this order: an older bwrap has no --disable-userns or --size
# the parts of /proc that write to the kernel of the whole machine, bound read-only (as Docker
# and Flatpak do): a sandbox of a grader run as root is root's uid outside
PROC_READ_ONLY = ("/proc/sys", "/proc/sysrq-trigger", "/proc/irq", "/proc/bus", "/proc/fs")
VARIANTS = ((["--disable-userns"], True), ([], True), ([], False))
TRIAL_TMPFS = 1 << 20
# syscalls a student's process gets EPERM for: setsid (a new session is a new scheduler
# autogroup: 200 of them would take the CPU from every other job), the kernel keyrings (not
# namespaced: a key would outlive its job), file locks and file-change notification (a lock or
# an inotify watch on a file every sandbox sees, such as the Python binary, is a channel between
# jobs that run at once); any other ABI (x32, 32-bit) is refused whole
SECCOMP = {"x86_64": (0xC000003E, {"setsid": 112, "add_key": 248, "request_key": 249,
                                   "keyctl": 250, "flock": 73, "inotify_init": 253,
                                   "inotify_init1": 294, "fanotify_init": 300}, 72),
           "aarch64": (0xC00000B7, {"setsid": 157, "add_key": 217, "request_key": 218,
                                    "keyctl": 219, "flock": 32, "inotify_init1": 26,
                                    "fanotify_init": 262}, 25)}
# fcntl's commands refused: F_GETLK/F_SETLK/F_SETLKW, their OFD forms, leases and F_NOTIFY
FCNTL_DENIED = (5, 6, 7, 36, 37, 38, 1024, 1025, 1026)


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


def command(bwrap, flags, package, hidden, work, pid1=False, tmpfs_bytes=None, seccomp=None,
            copy=None):
    """bwrap ... -- (argv follows): the whitelist, read-only; `work` the only writable folder;
    `pid1`: argv is the PID namespace's init (the fork server) instead of bwrap's reaper;
    `tmpfs_bytes`: the size of each writable tmpfs; `seccomp`: the fd of seccomp_program();
    `copy`: a copy of ikteach shown in place of `package` (reference.py)."""
    args = [bwrap]
    for d in SYSTEM:
        if os.path.islink(d):
            args += ["--symlink", os.readlink(d), d]
        elif os.path.isdir(d):
            args += ["--ro-bind", d, d]
    for name in ETC:
        args += ["--ro-bind-try", f"/etc/{name}", f"/etc/{name}"]
    args += ["--ro-bind-try", "/sys/devices/system/cpu", "/sys/devices/system/cpu"]
    args += private_mounts(tmpfs_bytes)
    bound = python_paths(package)
    for path in bound:
        args += ["--ro-bind", str(path), str(path)]
    if copy is not None:
        args += ["--ro-bind", str(copy), str(package)]
    for path in hidden:  # only what lies inside a bound folder is visible at all
        if _inside(path, bound) and _is_dir(path):
            args += ["--tmpfs", str(path), "--remount-ro", str(path)]
    # the working folder: a tmpfs of its own (nothing of the grader's disk), HOME and TMPDIR in it
    args += sized_tmpfs(work, tmpfs_bytes) + ["--dir", str(Path(work) / "home" / "tmp")]
    args += ["--remount-ro", "/", "--chdir", str(work)]
    args += ["--seccomp", str(seccomp)] if seccomp is not None else []
    return args + NAMESPACES + (["--as-pid-1"] if pid1 else []) + list(flags) + ["--"]


def unprivileged(args):
    """`args` (a bwrap command line), started as uid SANDBOX_ID where this process is root."""
    if os.geteuid() != 0:
        return list(args)
    sources = [args[i + 1] for i, op in enumerate(args[:-1]) if op in ("--ro-bind", "--ro-bind-try")]
    return started_as(int(SANDBOX_ID), args[0], sources) + list(args)


def started_as(uid, bwrap, sources):
    """The prefix (this process being root) that starts a command as `uid`, with `sources`
    reachable for it (reachable()), then the drop (_launch.py --as)."""
    return reachable(bwrap, sources, uid) + [sys.executable, "-S", str(LAUNCH), "--as", str(uid),
                                             "--"]


def reachable(bwrap, sources, uid):
    """[] where `uid` reaches each of `sources`; else bwrap ... -- (a command follows): as
    root, a mount namespace where a folder it cannot enter on the way (such as /root) is a
    tmpfs holding only the paths to those sources."""
    def closed(folder):
        st = os.stat(folder)
        return st.st_uid != uid and not st.st_mode & 0o001

    outer, made = [bwrap, "--dev-bind", "/", "/", "--chdir", "/", "--die-with-parent"], set()
    for source in map(Path, sources):
        if not source.exists():
            continue
        shut = next((p for p in reversed(source.parents) if closed(p)), None)
        if shut is None:
            continue
        for folder in [shut, *reversed(source.parents[:source.parents.index(shut)])]:
            if folder not in made:
                outer += ["--perms", "0755", "--tmpfs" if folder == shut else "--dir", str(folder)]
                made.add(folder)
        outer += ["--ro-bind", str(source), str(source)]
    return outer + ["--"] if made else []


def private_mounts(tmpfs_bytes):
    """What a run may write besides its working folder, RAM-backed and each at most
    `tmpfs_bytes` (None: no size): /tmp and /dev/shm; /dev itself read-only; POSIX message
    queues visible in /dev/mqueue (so that the fork server removes a job's with its files); of
    its own /proc, what writes to the machine's kernel read-only (PROC_READ_ONLY)."""
    return (["--proc", "/proc"] + [a for p in PROC_READ_ONLY for a in ("--ro-bind-try", p, p)]
            + ["--dev", "/dev", "--mqueue", "/dev/mqueue"]
            + sized_tmpfs("/dev/shm", tmpfs_bytes) + ["--remount-ro", "/dev"]
            + sized_tmpfs("/tmp", tmpfs_bytes))


def sized_tmpfs(path, tmpfs_bytes):
    return (["--size", str(tmpfs_bytes)] if tmpfs_bytes else []) + ["--tmpfs", str(path)]


def seccomp_program():
    """The BPF filter bwrap installs (--seccomp FD), as bytes; None on another machine."""
    import platform
    import struct

    arch, calls, fcntl = SECCOMP.get(platform.machine(), (None, {}, None))
    if arch is None:
        return None
    # (code, jump if true, jump if false, k) with jumps as labels: "deny", "allow" or 0 (next)
    code = [(0x20, 0, 0, 4), (0x15, 0, "deny", arch), (0x20, 0, 0, 0),  # arch; native? nr
            (0x35, "deny", 0, 0x40000000)]                             # x32?
    code += [(0x15, "deny", 0, nr) for nr in calls.values()]
    code += [(0x15, 0, "allow", fcntl), (0x20, 0, 0, 24)]  # fcntl? load its command (low word)
    code += [(0x15, "deny", 0, cmd) for cmd in FCNTL_DENIED]
    code += [(0x06, 0, 0, 0x7FFF0000), (0x06, 0, 0, 0x00050000 | 1)]  # ALLOW, ERRNO(EPERM)
    where = {"allow": len(code) - 2, "deny": len(code) - 1}
    jump = lambda to, at: where[to] - at - 1 if isinstance(to, str) else to  # noqa: E731
    return b"".join(struct.pack("HBBI", op, jump(jt, i), jump(jf, i), k)
                    for i, (op, jt, jf, k) in enumerate(code))


def seccomp_fd():
    """A pipe's read end holding seccomp_program() (the caller passes it on and closes it)."""
    program = seccomp_program()
    if program is None:
        return None
    read, write = os.pipe()
    os.write(write, program)
    os.close(write)
    return read


def working_flags(bwrap):
    """((the extra flags this bwrap runs with, whether its tmpfs take a size), None) or
    (None, why it does not run)."""
    import ikteach

    package = Path(ikteach.__file__).resolve().parent
    why = "it does not run"
    with tempfile.TemporaryDirectory(prefix="ikteach-bwrap-") as work:
        for flags, sized in VARIANTS:
            fd = seccomp_fd()
            argv = unprivileged(command(bwrap, flags, package, [], Path(work),
                                        tmpfs_bytes=TRIAL_TMPFS if sized else None, seccomp=fd))
            try:
                run = subprocess.run(argv + [sys.executable, "-S", "-c", ""], capture_output=True,
                                     timeout=30, cwd=work, pass_fds=[fd] if fd else [])
            except (OSError, subprocess.SubprocessError) as exc:
                return None, f"it does not run ({exc})"
            finally:
                if fd is not None:
                    os.close(fd)
            if run.returncode == 0:
                return (flags, sized), None
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
    if seen.get("devices_owned") is not False:
        failures.append("the student's process owns the machine's device nodes (it is root "
                        "outside its namespace): it could chmod /dev/null for every user")
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
    if seen.get("kernel_settings"):
        failures.append(f"it could open {', '.join(seen['kernel_settings'])} for writing")
    server = seen.get("server")
    if not isinstance(server, dict) or any(server.values()) or not server:
        failures.append(f"it could reach the fork server that starts every notebook ({server})")
    if failures:
        raise SandboxUnavailable("bubblewrap runs, but its sandbox does not hold: "
                                 + "; ".join(failures) + ".")
    lines = [f"runs as uid {seen['uid']} with no capabilities, in its own user namespace, and "
             "as an unprivileged uid outside it (it owns no device node: chmod /dev/null fails)",
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
    if seen.get("oom_lowered") is False:
        lines.append("cannot write /proc or /sys: the kernel's settings (/proc/sys "
                     "read-only, tried core_pattern) nor its own OOM priority (Landlock)")
    if seen.get("userns_blocked"):
        lines.append("cannot create user namespaces (so it cannot regain capabilities)")
    if seen.get("new_session") is False:
        lines.append("cannot start a session of its own (so a job's processes share one "
                     "scheduler group) or use the kernel's keyrings (seccomp)")
    return lines
