"""A character in 3-D with pyvista: bones as tubes, joints as balls, on a floor; shown through
ik.pictures.scene.show (a static PNG off screen, pyvista's live view in a live Jupyter)."""
import numpy as np

from .scene import WINDOW, _pv, add_meshes

BONE_COLORS = {"Left": "#4c72b0", "Right": "#dd8452"}
OTHER = "#777777"
UP = np.array([0.0, 1.0, 0.0])   # BVH: y up


def character_scene(rig, points, targets=None, window_size=WINDOW, plotter=None):
    """A pyvista Plotter with the pose (world points (m, 3) of rig.points) and targets (k, 3)
    as purple balls; the camera looks at the character from the front-left, fixed."""
    pv = _pv()
    points = np.asarray(points, dtype=float)
    p = plotter if plotter is not None else pv.Plotter(window_size=list(window_size),
                                                       off_screen=pv.OFF_SCREEN or None)
    p.set_background("white")
    centre = points.mean(axis=0)
    height = np.ptp(points[:, 1])
    p.add_mesh(pv.Plane(center=(centre[0], 0.0, centre[2]), direction=UP, i_size=1.6 * height,
                        j_size=1.6 * height), color="#eeeeee", render=False)
    bones = []
    for a, b in rig.bones():
        name = rig.points[b] if isinstance(rig.points[b], str) else rig.points[b][0]
        colour = next((c for side, c in BONE_COLORS.items() if name.startswith(side)), OTHER)
        if np.linalg.norm(points[b] - points[a]) > 1e-9:
            bones.append((pv.Tube(pointa=points[a], pointb=points[b], radius=0.018 * height,
                                  n_sides=16), colour))
    balls = [(pv.Sphere(center=q, radius=0.025 * height), "#333333") for q in points]
    add_meshes(p, bones + balls, smooth_shading=True)  # one actor per colour
    if targets is not None:
        add_meshes(p, [(pv.Sphere(center=t, radius=0.03 * height), "#8172b3")
                       for t in np.asarray(targets, dtype=float).reshape(-1, 3)], opacity=0.6)
    eye = centre + height * np.array([1.3, 0.35, 1.9])
    p.camera_position = [tuple(eye), tuple(centre), tuple(UP)]
    p.camera.view_angle = 30.0
    p._ikteach_alt = describe(rig, points, targets)  # ik.pictures.scene.show's alt text
    return p


def _point_name(rig, k):
    name = rig.points[k]
    return name if isinstance(name, str) else name[0]


def describe(rig, points, targets=None):
    """Alt text for a character scene: what is drawn, how tall, and where each target is
    (next to which named point of the skeleton, and how far from it)."""
    points = np.asarray(points, dtype=float)
    height = np.ptp(points[:, 1])
    words = [f"3-D view, from the front left, of a skeleton of {len(points)} points on a grey floor, "
             f"{height:.0f} units tall (the clip's units): bones as tubes (left limbs blue, right limbs "
             "orange, the spine and head grey), joints as dark balls"]
    for t in [] if targets is None else np.asarray(targets, dtype=float).reshape(-1, 3):
        k = int(np.argmin(np.linalg.norm(points - t, axis=1)))
        gap = float(np.linalg.norm(points[k] - t))
        where = (f"on the {_point_name(rig, k)} (reached)" if gap < 0.03 * height  # inside the ball
                 else f"{gap:.1f} units from the nearest point, the {_point_name(rig, k)}")
        words.append(f"a translucent purple target ball at ({t[0]:.0f}, {t[1]:.0f}, {t[2]:.0f}), {where}")
    return "; ".join(words) + "."
