"""ikteach.lapack_tables: jaxlib's LAPACK kernels get their pointers without scipy.linalg."""
import subprocess
import sys

SCRIPT = """
import sys, numpy as np, jax, jax.numpy as jnp, ikteach
A = np.array([[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]])
s = jax.jit(lambda a: jnp.linalg.svd(a, compute_uv=False))(A)   # lowered and run here
x = jax.jit(jnp.linalg.solve)(A, np.ones(3))
assert np.allclose(s, np.linalg.svd(A, compute_uv=False)) and np.allclose(A @ x, 1.0)
print("scipy.linalg" in sys.modules)
import scipy.linalg                    # the whole package still imports as usual afterwards
from scipy.linalg import cython_lapack
assert np.allclose(scipy.linalg.solve(A, np.ones(3)), x) and hasattr(cython_lapack, "__pyx_capi__")
"""


def test_linear_algebra_lowers_and_runs_without_importing_scipy_linalg():
    out = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == ["False"]
