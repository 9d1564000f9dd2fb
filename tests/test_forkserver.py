"""The fork server (ikteach/course/grading/forkserver.py) starts every notebook's run and checks
in a fresh child of one long-lived process per sandbox: what one notebook does must not reach
the next one's state or mark. A notebook that writes files (its HOME, TMPDIR, working folder,
the server's folder around it, /tmp, /dev/shm, /dev), leaves a daemon (setsid + fork), patches
numpy, sets an environment variable, makes a SysV shared memory segment and changes /tmp's mode
or the server folder's ACL is graded; then a plain correct one in the same
sandbox gets 10/10 and a worker of the same server sees none of it.

With bubblewrap all of it holds. Without it (--no-sandbox: no namespaces) the shared places
are the machine's own and are not touched here; the rest holds there too.
"""
import shutil

import pytest

from ikteach.course import grade
from ikteach.course.grading import selfcheck, servers
from ikteach.course.grading.remote import Worker
from ikteach.course.grading.sandbox import Sandbox, SandboxUnavailable


def _sandbox():
    try:
        return Sandbox([])
    except SandboxUnavailable:
        return Sandbox([], unsandboxed=True)


SHARED = ["/tmp", "/dev/shm", "/dev"]
ATTACK = '''\
import ctypes, os, struct, subprocess, sys
import numpy as np
def _attack(shared, change):
    here = [os.environ["HOME"], os.environ["TMPDIR"], os.getcwd(), os.path.dirname(os.getcwd())]
    for folder in here + shared:  # the job's folder's parent: the server's, writable beneath /tmp
        try:
            with open(os.path.join(folder, "left-by-A"), "w") as handle:
                handle.write("A")
        except OSError:  # the sandbox's /dev is read-only
            pass
    daemon = [sys.executable, "-c", "import os, time\\nif os.fork(): os._exit(0)\\n"
              "while True: time.sleep(0.05)", "left-by-A"]
    try:
        subprocess.Popen(daemon, start_new_session=True)
    except OSError:  # the sandbox refuses new sessions: a daemon in this one
        subprocess.Popen(daemon)
    os.environ["LEFT_BY_A"] = "1"
    np.asarray = lambda a, *args, **kwargs: np.zeros_like(np.array(a, dtype=float))
    if shared:
        ctypes.CDLL(None).shmget(0x1EE7, 4096, 0o1666)
    if change == "mode":
        os.chmod("/tmp", 0o700)  # cannot be put back by removing files: a fresh server
    elif change == "acl":  # a default ACL (an xattr) on the server's folder, the job's parent
        acl = struct.pack("<I", 2) + b"".join(struct.pack("<HHI", tag, 7, 0xFFFFFFFF)
                                               for tag in (1, 4, 0x20))
        os.setxattr(os.path.dirname(os.getcwd()), "system.posix_acl_default", acl)
    return True
'''
LOOK = '''\
import os
import numpy as np
def look(shared):
    places = [os.environ["HOME"], os.environ["TMPDIR"], os.getcwd(),
              os.path.dirname(os.getcwd())] + shared
    procs = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as handle:
                procs += [pid] if b"left-by-A" in handle.read() else []
        except OSError:
            pass
    with open("/proc/sysvipc/shm") as table:  # keys in decimal: 0x1EE7 is 7911
        shm = sum(line.split()[0] == "7911" for line in table) if shared else 0
    return {"files": [p for p in places if os.path.exists(os.path.join(p, "left-by-A"))],
            "processes": procs, "env": "LEFT_BY_A" in os.environ, "shm": shm,
            "asarray": float(np.asarray([2.0])[0]), "tmp": oct(os.stat("/tmp").st_mode & 0o777)}
'''


GOOD = """\
def jt_step(J, e):
    J, e = np.asarray(J), np.asarray(e)
    g = J.T @ e
    v = J @ g
    return np.zeros(J.shape[1]) if v @ v == 0 else (e @ v / (v @ v)) * g
"""  # numpy's asarray, which the attack replaces


def attacked_book(shared, change):
    """Exercise 2's known-good answer, preceded by the attack (in the cells and the checks)."""
    book = selfcheck.book(GOOD)
    call = f"_done = _attack({shared!r}, {change!r})\n"
    book["cells"].insert(1, dict(book["cells"][0], source=ATTACK + call))
    return book


# /tmp's mode and the server folder's ACL only inside a sandbox (without one: the machine's own)
@pytest.mark.without_bwrap
@pytest.mark.parametrize("change", [None, "mode", "acl"] if shutil.which("bwrap") else [None])
def test_what_a_notebook_leaves_does_not_reach_the_next(change):
    sandbox = _sandbox()
    shared = SHARED if sandbox.bwrap else []
    if change and not sandbox.bwrap:
        sandbox.close()
        pytest.skip("without a sandbox /tmp is the machine's own")
    try:
        first = servers.server_for(sandbox, 2)  # exercise 2's (its copy of ikteach)
        attacked = grade.grade_book("a.ipynb", attacked_book(shared, change), 30, 60, sandbox)
        assert attacked["notes"] == [] and attacked["score"] < 10, attacked  # its own asarray
        replaced = servers.server_for(sandbox, 2) is not first
        after = grade.grade_book("b.ipynb", selfcheck.book(GOOD), 30, 60, sandbox)
        assert after["score"] == 10 and after["notes"] == [], after
        worker = Worker([(1, LOOK)], sandbox, exercise=2).start()
        try:
            seen = worker.call("look", [shared])
        finally:
            worker.end()
        assert seen == {"files": [], "processes": [], "env": False, "shm": 0, "asarray": 2.0,
                        "tmp": seen["tmp"]}, seen
        if sandbox.bwrap:
            assert seen["tmp"] != oct(0o700), seen
            # /tmp's mode, an xattr (ACL) on the server's folder: not put back by removing
            # files (Landlock governs no metadata): that server was replaced
            assert replaced == bool(change)
    finally:
        servers.close_all()
        sandbox.close()

