"""Workspace maps of a planar arm: solve a grid of targets at once (ik.solve_batch) and
draw, per method, the iterations to converge, the final status and sigma_min; extract the
reachable set's boundary with skimage.measure.find_contours; track a closed path taken
from a scikit-image sample image with one update per frame (Buss's moving target).
"""
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
from . import xla

STATUS_COLORS = {"converged": "#55a868", "stalled": "#dd8452", "max_iter": "#c44e52",
                 "diverged": "#222222", "slow": "#8172b3"}


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
    return method if isinstance(method, str) else getattr(method, "__name__", "custom")


def sweep(arm, grid, theta0, method="dls", **kwargs):
    """ik.solve_batch over every grid target from the same theta0; results as images."""
    res = solve_batch(arm, grid.points, theta0, method=method, **kwargs)
    return SweepMap(_method_name(method), grid.image(res.iterations), grid.image(res.status),
                    grid.image(res.theta), grid.image(res.error))


@xla.jit
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


def boundary(mask, grid):
    """The boundary of a boolean image (True = reached), by skimage.measure.find_contours at
    level 0.5, as a list of (k, 2) arrays of workspace (x, y) points."""
    from skimage.measure import find_contours

    padded = np.pad(np.asarray(mask, dtype=float), 1)  # close contours at the image edge
    dx, dy = grid.xs[1] - grid.xs[0], grid.ys[1] - grid.ys[0]
    out = []
    for c in find_contours(padded, 0.5):
        rows, cols = c[:, 0] - 1, c[:, 1] - 1
        out.append(np.stack([grid.xs[0] + cols * dx, grid.ys[0] + rows * dy], axis=1))
    return out


def contour_radii(contours, centre=(0.0, 0.0), min_points=20):
    """(min, mean, max) distance from centre of each contour with at least min_points points,
    sorted by mean radius."""
    rows = []
    for c in contours:
        if len(c) >= min_points:
            r = np.linalg.norm(c - np.asarray(centre)[:2], axis=1)
            rows.append((r.min(), r.mean(), r.max()))
    return sorted(rows, key=lambda t: t[1])


def plot_map(ax, image, grid, title, contours=(), radii=None, cmap="viridis", label=None,
             vmin=None, vmax=None):
    """imshow of a map over the workspace, with the extracted boundary (white) and the
    analytic reach circles (dashed) drawn on top. Returns the image artist."""
    import matplotlib.pyplot as plt

    im = ax.imshow(image, origin="lower", extent=grid.extent, cmap=cmap, vmin=vmin, vmax=vmax,
                   interpolation="nearest")
    for c in contours:
        ax.plot(c[:, 0], c[:, 1], color="white", lw=1.2)
    if radii is not None:
        t = np.linspace(0, 2 * np.pi, 200)
        for r in radii:
            if r > 0:
                ax.plot(r * np.cos(t), r * np.sin(t), "k--", lw=0.8)
    ax.set_title(title)
    ax.set_xlabel("target x")
    ax.set_ylabel("target y")
    ax.set_aspect("equal")
    ax.grid(False)
    if label is not None:
        plt.colorbar(im, ax=ax, shrink=0.8, label=label)
    return im


def status_image(status):
    """Status names (n, n) as an RGB image, colours from STATUS_COLORS."""
    from matplotlib.colors import to_rgb

    out = np.ones(status.shape + (3,))
    for name, colour in STATUS_COLORS.items():
        out[status == name] = to_rgb(colour)
    return out


# ---- trajectory tracking -------------------------------------------------------------

def image_path(image, n_points=400):
    """The longest contour of a (binary) image, resampled to n_points evenly spaced by arc
    length, in image coordinates (x = column, y = up), closed (last point != first)."""
    from skimage.measure import find_contours

    c = max(find_contours(np.pad(np.asarray(image, dtype=float), 1), 0.5), key=len)
    xy = np.stack([c[:, 1], -c[:, 0]], axis=1)
    if not np.allclose(xy[0], xy[-1]):
        xy = np.vstack([xy, xy[:1]])
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(xy, axis=0), axis=1))]
    t = np.linspace(0.0, s[-1], n_points, endpoint=False)
    return np.stack([np.interp(t, s, xy[:, 0]), np.interp(t, s, xy[:, 1])], axis=1)


def fit_path(path, centre, width):
    """Scale and move a path (k, 2) so its bounding box is `width` wide, centred at centre."""
    path = np.asarray(path, dtype=float)
    lo, hi = path.min(axis=0), path.max(axis=0)
    return (path - (lo + hi) / 2) * (width / (hi - lo)[0]) + np.asarray(centre, dtype=float)


def horse_path(n_points=400, centre=(1.0, 0.0), width=1.0):
    """The outline of skimage.data.horse() (ships with scikit-image; no download) as a
    closed path of n_points targets, width wide, centred at centre."""
    from skimage import data

    return fit_path(image_path(~data.horse(), n_points), centre, width)


@dataclasses.dataclass(frozen=True)
class Tracking:
    """One update per frame: theta[k] after frame k, error[k] = |path[k] - F(theta[k])|."""
    method: str
    theta: np.ndarray
    error: np.ndarray

    @property
    def jitter(self):
        """ik.jitter_per_step: sum_i |theta_i[k+1] - 2 theta_i[k] + theta_i[k-1]| per frame."""
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
