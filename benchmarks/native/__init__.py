"""Build benchmarks/native/dls_loop.c with gcc at bench time and call it through ctypes.

    lib = build()                     # compiles into a temporary folder
    status, iterations, error, total = run(lib, lengths, targets, theta0, tol, damping,
                                           stall_tol, max_iter)
"""
import ctypes
import pathlib
import shutil
import subprocess
import tempfile

import numpy as np

SOURCE = pathlib.Path(__file__).with_name("dls_loop.c")
FLAGS = ["-O3", "-ffp-contract=off", "-shared", "-fPIC"]  # no FMA: IEEE steps like numpy's


def build():
    """Compile the scalar DLS loop; None when no C compiler is found."""
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        return None
    out = pathlib.Path(tempfile.mkdtemp(prefix="ikteach-bench-")) / "dls_loop.so"
    subprocess.run([cc, *FLAGS, str(SOURCE), "-o", str(out), "-lm"], check=True)
    lib = ctypes.CDLL(str(out))
    dp, ip = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_int)
    lib.dls_sweep.restype = ctypes.c_long
    lib.dls_sweep.argtypes = [dp, ctypes.c_int, dp, dp, ctypes.c_double, ctypes.c_double,
                              ctypes.c_double, ctypes.c_int, ctypes.c_long, ctypes.c_long,
                              ip, ip, dp]
    return lib


def run(lib, lengths, targets, theta0, tol, damping, stall_tol, max_iter):
    """Solve every target (B, 2); returns status codes, iterations, errors and their total."""
    lengths = np.ascontiguousarray(lengths, dtype=np.float64)
    targets = np.ascontiguousarray(targets, dtype=np.float64)
    theta0 = np.ascontiguousarray(theta0, dtype=np.float64)
    count = len(targets)
    status = np.zeros(count, dtype=np.intc)
    iterations = np.zeros(count, dtype=np.intc)
    error = np.zeros(count)
    dp = lambda a: a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))  # noqa: E731
    ip = lambda a: a.ctypes.data_as(ctypes.POINTER(ctypes.c_int))  # noqa: E731
    total = lib.dls_sweep(dp(lengths), len(lengths), dp(targets), dp(theta0), tol, damping,
                          stall_tol, max_iter, 0, count, ip(status), ip(iterations), dp(error))
    return status, iterations, error, int(total)
