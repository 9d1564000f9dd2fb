"""A 3-D reachability map of a spatial arm: which points of a grid its hand reaches while it
holds one tool orientation R_t. Each point p is the pose target T = [[R_t, p], [0, 1]], solved
from several starts; all starts of all points go to ik.solve_batch as one batch (one compiled
program, vectorised), and a point counts as reached when any of its starts converges.
Drawing the map with the arm: ikteach/pictures/workspace_maps.py (reach_scene)."""
import dataclasses

import numpy as np

from ._validate import as_array, as_number
from .batch import solve_batch
from .pose import check_pose
from .solve import status_counts


@dataclasses.dataclass(frozen=True)
class ReachMap:
    """One row per grid point: reached (some start converged), how many starts converged, the
    point's status ("converged" when reached, else the status of the start that came closest)
    and that start's final theta."""
    points: np.ndarray       # (G, 3)
    reached: np.ndarray      # (G,) bool
    converged: np.ndarray    # (G,) starts that converged, 0..S
    status: np.ndarray       # (G,) names, see ik.STATUSES
    theta: np.ndarray        # (G, joints)

    def counts(self):
        return status_counts(self.status)


def box_grid(lower, upper, step):
    """The points of a box [lower, upper] (two 3-vectors) spaced `step` apart along x, y and z,
    as (G, 3), x changing fastest."""
    lower, upper = as_array(lower, "lower", shape=(3,)), as_array(upper, "upper", shape=(3,))
    step = as_number(step, "step", minimum=0, strict=True)
    if np.any(upper < lower):
        raise ValueError(f"upper: expected upper >= lower on every axis, got {upper} and {lower}")
    axes = [np.arange(lo, hi + step / 2, step) for lo, hi in zip(lower, upper)]
    Z, Y, X = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    return np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)


def tool_poses(rotation, points):
    """The pose targets [[R_t, p], [0, 1]] for every point p (G, 3): (G, 4, 4)."""
    poses = np.tile(np.eye(4), (len(points), 1, 1))
    poses[:, :3, :3], poses[:, :3, 3] = rotation, points
    return poses


def reach_map(arm, rotation, points, starts, method="dls", **settings):
    """Which points (G, 3) the hand of a spatial arm reaches holding the tool rotation R_t (3, 3):
    every point from every start (S, n) in one ik.solve_batch call of G * S pose targets
    (method and settings as in ik.solve_batch); a point is reached when any start converges."""
    if getattr(arm, "dim", None) != 3:
        raise ValueError(f"arm: expected a spatial chain (ik.serial_chain), got {arm!r:.60}")
    rotation = as_array(rotation, "rotation", shape=(3, 3))
    check_pose(tool_poses(rotation, np.zeros((1, 3))), "rotation")
    points = as_array(points, "points", shape=(None, 3))
    starts = as_array(starts, "starts", shape=(None, arm.n_joints))
    if len(points) == 0 or len(starts) == 0:
        raise ValueError(f"points, starts: expected at least one of each, got {len(points)} "
                         f"points and {len(starts)} starts")
    G, S = len(points), len(starts)
    res = solve_batch(arm, np.repeat(tool_poses(rotation, points), S, axis=0),
                      np.tile(starts, (G, 1)), method=method, **settings)
    ok = (res.status == "converged").reshape(G, S)
    best = np.where(ok, -1.0, res.error.reshape(G, S)).argmin(axis=1)  # a converged start first
    pick = np.arange(G) * S + best
    return ReachMap(points=points, reached=ok.any(axis=1), converged=ok.sum(axis=1),
                    status=res.status[pick], theta=res.theta[pick])
