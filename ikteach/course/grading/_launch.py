"""Start a command under resource limits (run as a script with `python -S`: it imports nothing
from ikteach, so it starts in milliseconds).

    python -S _launch.py CPU_S MEMORY_BYTES FILE_BYTES NPROC CGROUP_DIRS -- COMMAND...
    python -S _launch.py --as UID -- COMMAND...   (root only: COMMAND runs as UID, no groups)

NPROC 0 = leave as is; CGROUP_DIRS: comma-separated, "-" = none. Limits are set here, in the
child, rather than in a preexec_fn (unsafe in a parent with threads, such as one that has
imported JAX).
"""
import os
import resource
import sys


def main(argv):
    if argv[0] == "--as":
        uid = int(argv[1])
        os.setgroups([])
        os.setgid(uid)
        os.setuid(uid)
        os.execvp(argv[3], argv[3:])
    cpu, memory, file_size, nproc, cgroups = argv[:5]
    command = argv[argv.index("--") + 1:]
    os.setsid()  # its own process group: the grader ends all of it at once
    for cgroup in cgroups.split(",") if cgroups != "-" else []:
        with open(os.path.join(cgroup, "cgroup.procs"), "w") as handle:
            handle.write(str(os.getpid()))
    with open("/proc/self/oom_score_adj", "w") as handle:  # out of memory: students go first
        handle.write("1000")
    limits = [(resource.RLIMIT_CPU, int(cpu)), (resource.RLIMIT_AS, int(memory)),
              (resource.RLIMIT_FSIZE, int(file_size)), (resource.RLIMIT_CORE, 0)]
    if int(nproc):
        limits.append((resource.RLIMIT_NPROC, int(nproc)))
    for which, value in limits:
        resource.setrlimit(which, (value, value))
    os.execvp(command[0], command)


if __name__ == "__main__":
    main(sys.argv[1:])
