"""Workspace sweeps of a planar arm: solve a grid of targets at once (ik.solve_batch) and
keep, per method, the iterations to converge, the final status and sigma_min; track a closed
path with one update per frame (Buss's moving target). Drawing the maps, their boundaries and
the image-derived paths: ikteach/pictures/workspace_maps.py."""
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from .batch import solve_batch
from .jacobian import jacobian
from ._validate import as_array
from .kinematics import end_path  # noqa: F401  (ws.end_path, used by the notebook)
from .jitter import jitter_per_step
from .solve import status_counts
from .track import track as follow
from .._runtime.jit import quick_jit

@dataclasses.dataclass(frozen=True)
class Grid:
    """An n x n grid of targets: points (n*n, 2) row by row (y up the rows), axis values xs, ys."""
    points: np.ndarray
    xs: np.ndarray
    ys: np.ndarray

    @property
    def shape(self):
        return (len(self.ys), len(self.xs))

    @property
    def extent(self):
        """imshow extent (left, right, bottom, top) with pixels centred on the grid points."""
        dx, dy = self.xs[1] - self.xs[0], self.ys[1] - self.ys[0]
        return (self.xs[0] - dx / 2, self.xs[-1] + dx / 2, self.ys[0] - dy / 2, self.ys[-1] + dy / 2)

    def image(self, values):
        """Per-target values (n*n, ...) as an image (n, n, ...)."""
        values = np.asarray(values)
        return values.reshape(self.shape + values.shape[1:])


def target_grid(arm, n=256, margin=1.1):
    """n x n targets covering the square of half-width margin * reach around the base."""
    from .chain import reach

    if arm.dim != 2:
        raise ValueError(f"arm: expected a planar arm (ik.planar_chain), got a {arm.dim}-D chain")
    if not isinstance(n, (int, np.integer)) or n < 2:
        raise ValueError(f"n: expected an integer >= 2, got {n!r}")
    half = margin * float(reach(arm))
    bx, by = np.asarray(arm.base)[:2]
    xs, ys = np.linspace(bx - half, bx + half, n), np.linspace(by - half, by + half, n)
    X, Y = np.meshgrid(xs, ys)
    return Grid(np.stack([X.ravel(), Y.ravel()], axis=1), xs, ys)


@dataclasses.dataclass(frozen=True)
class SweepMap:
    """One method over a grid: iterations and status codes as images, final theta per target."""
    method: str
    iterations: np.ndarray   # (n, n)
    status: np.ndarray       # (n, n) names, see ik.STATUSES
    theta: np.ndarray        # (n, n, joints)
    error: np.ndarray        # (n, n)

    def counts(self):
        return status_counts(self.status)


def _method_name(method):
    """A label: the method's name, its class's (DLS), or a step function's."""
    if isinstance(method, str):
        return method
    return getattr(method, "__name__", type(method).__name__.lower())


def sweep(arm, grid, theta0, method="dls", **kwargs):
    """ik.solve_batch over every grid target from the same theta0; results as images."""
    res = solve_batch(arm, grid.points, theta0, method=method, **kwargs)
    return SweepMap(_method_name(method), grid.image(res.iterations), grid.image(res.status),
                    grid.image(res.theta), grid.image(res.error))


@quick_jit
def _sigma_min(arm, thetas):
    return jax.vmap(lambda q: jnp.linalg.svd(jacobian(arm, q), compute_uv=False)[-1])(thetas)


def sigma_min(arm, thetas):
    """sigma_min(J(theta)) for each row of thetas (..., n): the distance to a singularity."""
    thetas = np.asarray(thetas, dtype=float)
    flat = thetas.reshape(-1, thetas.shape[-1])
    return np.asarray(_sigma_min(arm, flat)).reshape(thetas.shape[:-1])


def reach_radii(lengths):
    """Analytic reach of a planar arm about its base: outer R = sum l_i,
    inner r = max(0, 2 max l_i - sum l_i) (the longest link folded back on the others)."""
    lengths = np.asarray(lengths, dtype=float)
    outer = lengths.sum()
    return max(0.0, 2 * lengths.max() - outer), outer


@dataclasses.dataclass(frozen=True)
class Tracking:
    """One update per frame: theta[k] after frame k, error[k] = |path[k] - F(theta[k])|."""
    method: str
    theta: np.ndarray
    error: np.ndarray

    @property
    def jitter(self):
        """ik.core.jitter.jitter_per_step: sum_i |theta_i[k+1] - 2 theta_i[k] + theta_i[k-1]| per frame."""
        return jitter_per_step(self.theta)

    def summary(self):
        return {"mean error": float(self.error.mean()), "max error": float(self.error.max()),
                "mean jitter": float(self.jitter.mean()), "max jitter": float(self.jitter.max())}


def track(arm, path, theta0, method="dls", damping=0.5, rcond=1e-6, clamp=None, max_step=None):
    """Buss's moving-target protocol along a path (k, d): one step of `method` per frame,
    from the previous theta (ik.track), kept with per-frame jitter for the maps notebook."""
    theta0 = as_array(theta0, "theta0", shape=(arm.n_joints,))
    res = follow(arm, path, theta0, method=method, damping=damping, rcond=rcond, clamp=clamp,
                 max_step=max_step)
    return Tracking(_method_name(method), res.theta[1:], res.error)
