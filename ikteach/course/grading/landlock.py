"""Landlock (Linux 5.13+): a process restricts itself, for good, to writing beneath a few folders.

The fork server's child calls restrict() before any student code runs (forkserver.py): from then
on no file outside those folders opens for writing, is made, removed or renamed, in that process
and all it starts - /proc and /sys included (its own oom_score_adj, /proc/sys's kernel settings,
whatever the uid it runs as). Reading is not restricted here (bubblewrap's mount list decides
what is there to read). On a kernel without Landlock restrict() returns False and the start-up
probe says so in the grader's log."""
import ctypes
import os

CREATE_RULESET, ADD_RULE, RESTRICT_SELF = 444, 445, 446  # the same on every architecture
VERSION, RULE_PATH_BENEATH, NO_NEW_PRIVS = 1, 1, 38
# the write rights of each ABI version: write, remove dir/file, make char/dir/reg/sock/fifo/
# block/symlink (1), + refer, i.e. rename/link across folders (2), + truncate (3)
WRITES = {1: 0b1_1111_1111_0010, 2: 0b11_1111_1111_0010, 3: 0b111_1111_1111_0010}
DEVICE_WRITES = 1 << 1 | 1 << 14  # write (and truncate) an existing file: /dev/null


class _PathBeneath(ctypes.Structure):
    _pack_ = 1
    _fields_ = [("allowed_access", ctypes.c_uint64), ("parent_fd", ctypes.c_int32)]


def _libc():
    return ctypes.CDLL(None, use_errno=True)


def abi():
    """The kernel's Landlock ABI version (0: none)."""
    try:
        version = _libc().syscall(CREATE_RULESET, None, 0, VERSION)
    except (OSError, AttributeError):
        return 0
    return max(int(version), 0)


def restrict(writable, devices=("/dev",)):
    """Restrict this process (and its children) to writing beneath `writable` folders and to
    existing files beneath `devices`; True when it holds."""
    version = min(abi(), 3)
    if version < 1:
        return False
    libc = _libc()
    handled = WRITES[version]
    fd = libc.syscall(CREATE_RULESET, ctypes.byref(ctypes.c_uint64(handled)), 8, 0)
    if fd < 0:
        return False
    try:
        for folder, rights in [(f, handled) for f in writable] + [
                (d, handled & DEVICE_WRITES) for d in devices]:
            try:
                parent = os.open(folder, os.O_PATH | os.O_CLOEXEC)
            except OSError:
                continue
            try:
                rule = _PathBeneath(rights, parent)
                if libc.syscall(ADD_RULE, fd, RULE_PATH_BENEATH, ctypes.byref(rule), 0) != 0:
                    return False
            finally:
                os.close(parent)
        libc.prctl(NO_NEW_PRIVS, 1, 0, 0, 0)
        return libc.syscall(RESTRICT_SELF, fd, 0) == 0
    finally:
        os.close(fd)
