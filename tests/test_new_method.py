"""A new Jacobian method with a parameter of its own is one class (its own file in the package)
and one line in the registry (ikteach/core/methods.py: METHODS): ik.solve, ik.solve_batch,
ik.track and joint limits then take it, and its parameter is traced (a new value reuses the
compiled loop)."""
import jax.numpy as jnp
import numpy as np

import ikteach as ik
from ikteach.core.method import JacobianMethod, method

ARM = ik.planar_chain([1.0, 1.0, 1.0])
START = np.array([0.3, 0.3, 0.3])


@method(data=("gain",))
class ScaledTranspose(JacobianMethod):
    """delta_theta = gain J^T e: the Jacobian transpose with a fixed step size."""
    gain: float = 0.1

    def step(self, J, e):
        return self.gain * (J.T @ e)


def test_a_new_method_runs_everywhere_with_its_own_parameter(monkeypatch):
    monkeypatch.setitem(ik.core.methods.METHODS, "scaled_jt", ScaledTranspose)
    target = np.array([1.5, 1.5])
    by_name = ik.solve(ARM, target, START, method="scaled_jt", max_iter=2000)
    assert by_name.status == "converged", by_name
    faster = ik.solve(ARM, target, START, method=ScaledTranspose(gain=0.2), max_iter=2000)
    assert faster.converged and faster.iterations != by_name.iterations  # its parameter counts
    batch = ik.solve_batch(ARM, np.stack([target] * 10), START, method=ScaledTranspose(0.2),
                           max_iter=2000)
    assert list(batch.status) == ["converged"] * 10
    assert np.abs(batch.theta[0] - faster.theta).max() < 1e-12
    limited = ik.solve(ARM, target, START, method=ScaledTranspose(0.2),
                       joint_limits=(-0.5, 1.2), max_iter=2000)
    assert np.all(limited.theta <= 1.2) and np.all(limited.theta >= -0.5)
    path = np.stack([np.linspace(1.5, 2.0, 20), np.full(20, 1.0)], axis=1)
    assert np.all(np.isfinite(ik.track(ARM, path, START, method=ScaledTranspose(0.2)).error))
    # the registry is the one list: the step is a plain function of J and e
    assert jnp.allclose(ScaledTranspose(2.0).step(jnp.eye(2), jnp.ones(2)), 2.0)
