"""Look-at: turn the neck and head so that the eyes face a point.

A point G fixed to the head `distance` ahead of the eyes E (the gaze point) is an end
effector like any other; its target is the point `distance` along the line from E to the
look-at point L:  G* = E + distance (L - E) / |L - E|.  Turning the neck moves E a little,
so the target is re-aimed and solved again for a few rounds (the eyes move less each round).
"""
import numpy as np

from ..core._validate import as_array, as_count, as_number
from .clip_ik import solve_clip
from .skeleton import rig as make_rig, world_points

EYES = (0.0, 8.0, 10.0)   # from the head joint, in the rest pose (z is forward)


def gaze_angle(eyes, gaze, point):
    """Angle (degrees) between where the head looks (gaze - eyes) and where it should (point - eyes)."""
    a, b = np.asarray(gaze) - eyes, np.asarray(point) - eyes
    cos = a @ b / (np.linalg.norm(a) * np.linalg.norm(b))
    return float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))


def look_at(skeleton, root, theta, point, joints=("Neck", "Head"), head="Head", eyes=EYES,
            distance=100.0, rounds=4):
    """Angles theta (n,) turned so that the eyes on `head` face `point` (world, (3,)), moving
    only the named joints. Returns (theta, angle left in degrees)."""
    point = as_array(point, "point", shape=(3,))
    distance = as_number(distance, "distance", minimum=0, strict=True)
    eyes = as_array(eyes, "eyes", shape=(3,))
    root = as_array(root, "root", shape=(3,))
    gaze_rig = make_rig(skeleton, [(head, eyes + [0.0, 0.0, distance])])
    eyes_rig = make_rig(skeleton, [(head, eyes)])
    theta = as_array(theta, "theta", shape=(gaze_rig.n_joints,))
    active = sum((gaze_rig.revolutes(j) for j in joints), [])
    for _ in range(as_count(rounds, "rounds")):
        e = world_points(eyes_rig, root, theta)[0, 0]
        target = e + distance * (point - e) / np.linalg.norm(point - e)
        theta = solve_clip(gaze_rig, root[None], theta[None], target[None, None], active, tol=1e-3).theta[0]
    e, g = world_points(eyes_rig, root, theta)[0, 0], world_points(gaze_rig, root, theta)[0, 0]
    return theta, gaze_angle(e, g, point)
