"""Workspace maps of a planar arm (ik.pictures.workspace_maps): the sweep and tracking of
ikteach/core/sweeps.py, drawn; the reachable set's boundary extracted with
skimage.measure.find_contours; a closed path taken from a scikit-image sample image.
"""
import numpy as np

from ..core.sweeps import (Grid, SweepMap, Tracking, end_path, reach_radii, sigma_min,  # noqa: F401
                              sweep, target_grid, track)

# one colour per status of ik.STATUSES (a status without one would be drawn white, like no target)
STATUS_COLORS = {"converged": "#55a868", "stalled": "#dd8452", "max_iter": "#c44e52",
                 "diverged": "#222222", "slow": "#8172b3", "singular": "#4c72b0", "damped": "#937860",
                 "fixed_point": "#da8bc3"}
STATUS_COLOR_NAMES = {"converged": "green", "stalled": "orange", "max_iter": "red",
                      "diverged": "black", "slow": "purple", "singular": "blue", "damped": "brown",
                      "fixed_point": "pink"}


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


def reach_scene(arm, theta, reach_map, step, hide=None):
    """A 3-D reachability map (ikteach/core/reach_map.py) drawn with pyvista around the arm at
    theta (ik.pictures.scene): each grid point a sphere in its status colour (STATUS_COLORS),
    reached points large, the others small; `hide` (G,) bool leaves points out (a cut-away)."""
    from . import scene

    pv = scene._pv()
    p = scene.scene(arm, theta, window_size=(640, 480))
    keep = np.ones(len(reach_map.points), bool) if hide is None else ~np.asarray(hide)
    shown = []
    for name, colour in STATUS_COLORS.items():
        chosen = keep & (reach_map.status == name)
        if chosen.any():
            size = 0.18 * step if name == "converged" else 0.07 * step
            dots = pv.PolyData(reach_map.points[chosen]).glyph(
                geom=pv.Sphere(radius=size, theta_resolution=10, phi_resolution=10),
                scale=False, orient=False)
            p.add_mesh(dots, color=colour, render=False)
            shown.append(f"{int(chosen.sum())} {name} ({STATUS_COLOR_NAMES[name]})")
    eye, focus, up = p.camera_position  # scene's view, moved onto the grid's centre, wider
    centre = reach_map.points[keep].mean(axis=0)
    p.camera_position = [tuple(np.add(eye, centre - focus)), tuple(centre), up]
    p.camera.zoom(0.8)
    p._ikteach_alt = (f"{scene.describe(arm, theta)[:-1]}; around it {int(keep.sum())} of the "
                      f"{len(keep)} grid points {step:g} apart as spheres by status: {', '.join(shown)}; "
                      "reached points large, the others small.")
    return p
