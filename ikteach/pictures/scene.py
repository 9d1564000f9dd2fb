"""3-D scenes of an arm with pyvista: links as tubes, joints as short cylinders along their
axes, frames as axes triads (x red, y green, z blue), the end effector's path as a trail.

show() honours the backend chosen with ik.notebook.setup(pyvista="static" | "interactive"):
static renders off screen to a PNG with alt text; interactive hands the plotter to
pyvista's trame view (the `3d` extra) in a live kernel.
"""
import io

import numpy as np

from ..core.kinematics import end_path, joint_frames
from ..core.chain import reach

COLORS = {"link": "#4c72b0", "joint": "#dd8452", "base": "#555555", "trail": "#c44e52",
          "target": "#8172b3"}
TRIAD_COLORS = ("#d62728", "#2ca02c", "#1f77b4")  # x, y, z
WINDOW = (480, 360)
STATIC_BACKENDS = (None, "static", "none")  # pv.global_theme.jupyter_backend values shown as PNG


def _pv():
    try:
        import pyvista as pv
    except ModuleNotFoundError as exc:  # the `scenes` extra: only the 3-D lectures install it
        raise ModuleNotFoundError("3-D scenes need pyvista: pip install 'ikteach[scenes]'") from exc

    from .backend_3d import apply_pyvista_choice

    apply_pyvista_choice()
    try:  # vtk's X11 warnings go straight to stderr; keep errors only
        from vtkmodules.vtkCommonCore import vtkLogger  # not `import vtk`: every module, 0.5 s

        vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)
    except (ImportError, AttributeError):
        pass
    return pv


def frames(arm, theta):
    """World joint positions (n+1, 3), world joint axes (n, 3) and the 4x4 end pose, as numpy."""
    positions, axes, R = (np.asarray(x) for x in joint_frames(arm, theta))
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, positions[-1]
    return positions, axes, T


def triad(T, size):
    """Three arrows along the columns of T's rotation, from T's origin: [(mesh, colour), ...]."""
    pv = _pv()
    T = np.asarray(T, dtype=float)
    return [(pv.Arrow(start=T[:3, 3], direction=T[:3, k], scale=size, tip_length=0.3,
                      tip_radius=0.1, shaft_radius=0.035), TRIAD_COLORS[k]) for k in range(3)]


def triad_anchors(T):
    """(origin, unit direction) of each arrow of triad(T)."""
    T = np.asarray(T, dtype=float)
    return [(T[:3, 3], T[:3, k]) for k in range(3)]


UP_Z = np.array([0.0, 0.0, 1.0])


def arm_anchors(positions, axes):
    """(origin, unit direction) of each part of arm_meshes, in its order: the base, a tube per
    link of non-zero length (from its first joint towards the next), a cylinder per joint (along
    its axis) and the end-effector sphere. Each part is symmetric about its direction, so a
    part at one pose moves to another by the rigid motion of its anchor."""
    anchors = [(positions[0], UP_Z)]
    anchors += [(a, (b - a) / np.linalg.norm(b - a)) for a, b in _links(positions)]
    anchors += [(p, w / np.linalg.norm(w)) for p, w in zip(positions[:-1], axes)]
    return anchors + [(positions[-1], UP_Z)]


def _links(positions):
    """(start, end) of each link of non-zero length, from the base to the end effector."""
    return [(a, b) for a, b in zip(positions[:-1], positions[1:]) if np.linalg.norm(b - a) > 1e-9]


def arm_meshes(arm, theta, scale=None):
    """The arm as meshes: [(mesh, colour), ...] with link tubes, joint cylinders and the base,
    in the order of arm_anchors."""
    pv = _pv()
    scale = float(reach(arm)) if scale is None else scale
    positions, axes, _ = frames(arm, theta)
    parts = [(pv.Cylinder(center=positions[0] - [0, 0, 0.03 * scale], direction=(0, 0, 1),
                          radius=0.09 * scale, height=0.06 * scale), COLORS["base"])]
    for a, b in _links(positions):
        parts.append((pv.Tube(pointa=a, pointb=b, radius=0.022 * scale, n_sides=16), COLORS["link"]))
    for p, w in zip(positions[:-1], axes):
        parts.append((pv.Cylinder(center=p, direction=w, radius=0.045 * scale,
                                  height=0.11 * scale, resolution=24), COLORS["joint"]))
    parts.append((pv.Sphere(center=positions[-1], radius=0.03 * scale), COLORS["joint"]))
    return parts


def trail_mesh(points, scale):
    """The end effector's path as a thin tube through the points (k, 3)."""
    pv = _pv()
    points = np.asarray(points, dtype=float)
    keep = np.r_[True, np.linalg.norm(np.diff(points, axis=0), axis=1) > 1e-9]
    points = points[keep]
    if len(points) < 2:
        return None
    return pv.lines_from_points(points).tube(radius=0.008 * scale, n_sides=8)


def add_meshes(plotter, parts, **style):
    """Add [(mesh, colour), ...] as one actor per colour, the parts of a colour merged into one
    mesh (they stay separate pieces): a few actors to build and draw instead of one per part.
    Returns [(merged mesh, indices of its parts), ...]."""
    by_colour = {}
    for i, (_, colour) in enumerate(parts):
        by_colour.setdefault(colour, []).append(i)
    groups = []
    for colour, members in by_colour.items():
        meshes = [parts[i][0] for i in members]
        merged = meshes[0].append_polydata(*meshes[1:]) if len(meshes) > 1 else meshes[0].copy()
        plotter.add_mesh(merged, color=colour, render=False, **style)
        groups.append((merged, members))
    return groups


def turn_onto(a, b):
    """The smallest rotation taking unit vector a onto unit vector b (3 x 3)."""
    v, c = np.cross(a, b), float(np.dot(a, b))
    if c < -1.0 + 1e-12:  # opposite: half a turn about any axis perpendicular to a
        w = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
        w /= np.linalg.norm(w)
        return 2.0 * np.outer(w, w) - np.eye(3)
    K = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + K + K @ K / (1.0 + c)


class MovingParts:
    """Parts added with add_meshes that then move rigidly with their anchors: a new pose moves
    the points already drawn instead of building every mesh again (solve_gif's frames)."""

    def __init__(self, plotter, parts, anchors, **style):
        self.anchors = [(np.asarray(o, float), np.asarray(d, float)) for o, d in anchors]
        self.groups = []
        for merged, members in add_meshes(plotter, parts, **style):
            sizes = [parts[i][0].n_points for i in members]
            owner = np.repeat(members, sizes)  # the part each merged point belongs to
            normals = merged.point_data.get("Normals")
            self.groups.append((merged, owner, np.array(merged.points),
                                None if normals is None else np.array(normals)))

    def move(self, anchors):
        """Move every part from its first anchor to the new one: p -> R (p - o) + o'."""
        turns, shifts = [], []
        for (o, d), (o_new, d_new) in zip(self.anchors, anchors):
            R = turn_onto(d, np.asarray(d_new, float))
            turns.append(R)
            shifts.append(np.asarray(o_new, float) - R @ o)
        turns, shifts = np.stack(turns), np.stack(shifts)
        for merged, owner, points, normals in self.groups:
            merged.points = np.einsum("nab,nb->na", turns[owner], points) + shifts[owner]
            if normals is not None:
                merged.point_data["Normals"] = np.einsum("nab,nb->na", turns[owner], normals)


def _camera(arm, scale):
    base = np.asarray(arm.base, dtype=float)
    focus = base + np.array([0.0, 0.0, 0.3 * scale])
    eye = focus + scale * np.array([1.9, -2.3, 1.2])
    return [tuple(eye), tuple(focus), (0.0, 0.0, 1.0)]


def scene(arm, theta, target=None, trail=None, window_size=WINDOW, ghost=None, plotter=None):
    """A pyvista Plotter showing the arm at theta.

    target  a 3-vector (drawn as a sphere) or a 4x4 pose (drawn as a triad);
    trail   end-effector positions (k, 3) drawn as a tube;
    ghost   another theta (e.g. the start), drawn translucent.
    The end effector's frame is drawn as a triad; the camera is fixed, so renders repeat.
    """
    p, _ = _scene(arm, theta, target, trail, window_size, ghost, plotter)
    return p


def _scene(arm, theta, target, trail, window_size, ghost, plotter):
    """scene(), and the arm with its end triad as MovingParts."""
    pv = _pv()
    scale = float(reach(arm))
    p = plotter if plotter is not None else pv.Plotter(window_size=list(window_size),
                                                       off_screen=pv.OFF_SCREEN or None)
    p.set_background("white")
    floor = pv.Plane(center=np.asarray(arm.base, dtype=float) - [0, 0, 0.061 * scale],
                     direction=(0, 0, 1), i_size=2.4 * scale, j_size=2.4 * scale)
    p.add_mesh(floor, color="#f2f2f2", ambient=0.6, diffuse=0.4, render=False)
    if ghost is not None:
        add_meshes(p, arm_meshes(arm, ghost, scale), opacity=0.25)
    pose = _posed_arm(p, arm, theta, scale)
    if target is not None:
        target = np.asarray(target, dtype=float)
        if target.shape == (4, 4):
            add_meshes(p, triad(target, 0.28 * scale), opacity=0.5)
            centre = target[:3, 3]
        else:
            centre = np.append(target, 0.0)[:3] if target.shape == (2,) else target
        p.add_mesh(pv.Sphere(center=centre, radius=0.025 * scale), color=COLORS["target"], opacity=0.6,
                   render=False)
    _draw_trail(p, trail, scale)
    p.camera_position = _camera(arm, scale)
    p.camera.view_angle = 24.0
    p._ikteach_alt = describe(arm, theta, target=target, trail=trail, ghost=ghost)
    return p, pose


def _posed_arm(plotter, arm, theta, scale):
    """The arm (smooth shaded) and its end triad, as MovingParts; _move_arm moves them."""
    positions, axes, T = frames(arm, theta)
    arm_parts = MovingParts(plotter, arm_meshes(arm, theta, scale), arm_anchors(positions, axes),
                            smooth_shading=True)
    end_triad = MovingParts(plotter, triad(T, 0.2 * scale), triad_anchors(T))
    return arm_parts, end_triad


def _move_arm(pose, arm, theta):
    arm_parts, end_triad = pose
    positions, axes, T = frames(arm, theta)
    arm_parts.move(arm_anchors(positions, axes))
    end_triad.move(triad_anchors(T))


def _draw_trail(plotter, trail, scale):
    """The trail as the actor named "trail" (replacing the last one); none for < 2 points."""
    mesh = trail_mesh(trail, scale) if trail is not None else None
    if mesh is not None:
        plotter.add_mesh(mesh, color=COLORS["trail"], render=False, name="trail")
    else:
        plotter.remove_actor("trail", render=False)


def render(plotter):
    """Render off screen to an (h, w, 3) uint8 image; the plotter stays usable (a plotter
    changed since its last render is rendered again: screenshot alone would not)."""
    plotter.render()  # nothing before the first render, which screenshot makes
    return np.asarray(plotter.screenshot(return_img=True))


def png_bytes(image):
    """An (h, w, 3) uint8 image as PNG bytes."""
    import matplotlib.image

    buf = io.BytesIO()
    matplotlib.image.imsave(buf, np.asarray(image), format="png")
    return buf.getvalue()


def show(plotter, alt=None):
    """Show a scene with the backend chosen by ik.notebook.setup(pyvista=...) (or
    pv.set_jupyter_backend): "static" renders off screen and displays a PNG with alt text
    (tests, CI, committed notebooks); any live backend ("trame", ...) hands the plotter to
    pyvista's interactive view. alt defaults to the description scene() attached."""
    pv = _pv()
    backend = pv.global_theme.jupyter_backend
    if backend in STATIC_BACKENDS:
        from IPython.display import HTML, display

        from .alt_text import img_html

        image = render(plotter)
        plotter.close()
        alt = alt or getattr(plotter, "_ikteach_alt", "A 3-D scene rendered with pyvista.")
        display(HTML(img_html(png_bytes(image), alt)))
        return None
    return plotter.show(jupyter_backend=backend)


def describe(arm, theta, target=None, trail=None, ghost=None):
    """Alt text for a scene: what is drawn and where the end effector is."""
    _, _, T = frames(arm, theta)
    words = [f"3-D view of a {arm.n_joints}-joint arm (blue links, orange joints) on a grey floor, "
             f"end effector at ({T[0, 3]:.2f}, {T[1, 3]:.2f}, {T[2, 3]:.2f}) with its x/y/z "
             "frame drawn red/green/blue"]
    scale = float(reach(arm))
    if target is not None:
        t = np.asarray(target, dtype=float)
        kind = "a translucent purple sphere and x/y/z frame" if t.shape == (4, 4) else "a translucent purple sphere"
        t = t[:3, 3] if t.shape == (4, 4) else np.append(t, 0.0)[:3]
        gap = float(np.linalg.norm(t - T[:3, 3]))
        where = ("at the end effector, hidden by its frame (reached)" if gap < 0.05 * scale
                 else f"{gap:.2f} from the end effector")
        words.append(f"the target at ({t[0]:.2f}, {t[1]:.2f}, {t[2]:.2f}) as {kind}, {where}")
    if ghost is not None:
        words.append("the start pose as a translucent ghost")
    if trail is not None and len(trail) > 1:
        trail = np.asarray(trail, dtype=float)
        length = float(np.linalg.norm(np.diff(trail, axis=0), axis=1).sum())
        words.append(f"the end effector's path from ({trail[0, 0]:.2f}, {trail[0, 1]:.2f}, {trail[0, 2]:.2f}) "
                     f"as a thin red tube {length:.2f} long")
    return "; ".join(words) + "."


def solve_gif(arm, trace_theta, path, target=None, frames_max=30, fps=8, window_size=(320, 240)):
    """Write a GIF of a solve: one frame per iterate of trace_theta (subsampled to at most
    frames_max), the end effector's path so far drawn as a trail. Returns the path.
    The scene is built once; each frame moves the arm's meshes and redraws the trail
    (12 frames of the iiwa: 0.85 -> 0.4 s)."""
    pv = _pv()
    thetas = np.asarray(trace_theta, dtype=float)
    idx = np.unique(np.linspace(0, len(thetas) - 1, min(frames_max, len(thetas))).round().astype(int))
    ends = end_path(arm, thetas)
    scale = float(reach(arm))
    p = pv.Plotter(window_size=list(window_size), off_screen=True)
    p.open_gif(str(path), fps=fps)
    _, pose = _scene(arm, thetas[idx[0]], target, None, window_size, None, p)  # trail: below
    for k in idx:
        _move_arm(pose, arm, thetas[k])
        _draw_trail(p, ends[: k + 1], scale)
        p.write_frame()
    p.close()
    return path


def show_gif(path, alt):
    """Display a GIF written by solve_gif (or any GIF) with alt text and a static fallback."""
    from .frames import GifView

    return GifView(path, alt)
