"""scipy's LAPACK tables for jaxlib, without importing all of scipy.linalg.

jaxlib's LAPACK kernels (SVD, LU, Cholesky, ...) call through function pointers it reads from
scipy.linalg.cython_blas and scipy.linalg.cython_lapack, when it first lowers a linear-algebra
call (or, for a program loaded whole from disk, when the program store sets them up).
"""
import importlib.util
import pathlib
import sys


def preload():
    """jaxlib reads its LAPACK pointers from scipy.linalg.cython_blas and .cython_lapack.
    Importing those the usual way imports all of scipy.linalg first (0.25 s); loaded straight
    from their files they take 0.02 s. Where scipy is laid out otherwise, nothing is done and
    jaxlib imports them itself."""
    try:
        spec = importlib.util.find_spec("scipy")
        folder = pathlib.Path(spec.submodule_search_locations[0]) / "linalg"
        for name in ("cython_blas", "cython_lapack"):
            full = f"scipy.linalg.{name}"
            if full in sys.modules:
                continue
            files = sorted(folder.glob(f"{name}.*.so")) + sorted(folder.glob(f"{name}.*.pyd"))
            module_spec = importlib.util.spec_from_file_location(full, files[0])
            module = importlib.util.module_from_spec(module_spec)
            module_spec.loader.exec_module(module)
            sys.modules[full] = module
    except Exception:
        pass
