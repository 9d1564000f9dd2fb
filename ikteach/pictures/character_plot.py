"""Drawing characters with matplotlib: stick figures seen from the side or the front, the
feet's paths against their contacts, and clips side by side as an animation."""
import numpy as np

VIEWS = {"side": (2, 1), "front": (0, 1), "top": (0, 2)}   # BVH: z forward, y up, x left
# Seen from above with z (forward) up the page, the character's left (+x) is on the page's
# left: the top view's x axis runs right to left (the front view's runs left to right).
MIRRORED = {"top"}


def _plane(view):
    if view not in VIEWS:
        raise ValueError(f"view: expected one of {sorted(VIEWS)}, got {view!r}")
    return VIEWS[view]


def stick_segments(rig, points):
    """Bone segments (b, 2, 3) of a rig whose world points are `points` (m, 3)."""
    points = np.asarray(points)
    return np.array([[points[a], points[b]] for a, b in rig.bones()])


def bone_colors(rig):
    """A colour per bone: the left side blue, the right side orange, the rest grey."""
    side = {"Left": "C0", "Right": "C1"}
    names = [rig.points[b] if isinstance(rig.points[b], str) else rig.points[b][0] for _, b in rig.bones()]
    return [next((c for prefix, c in side.items() if n.startswith(prefix)), "0.35") for n in names]


def draw_skeleton(ax, rig, points, view="side", color=None, alpha=1.0, label=None):
    """Draw one pose (world points (m, 3) of rig.points) as a stick figure; returns the artists.
    color None: left limbs blue, right limbs orange (bone_colors)."""
    i, j = _plane(view)
    colors = bone_colors(rig) if color is None else [color] * len(rig.bones())
    lines = [ax.plot(s[:, i], s[:, j], "-", color=c, lw=2.5, alpha=alpha, solid_capstyle="round",
                     label=label if k == 0 else None)[0]
             for k, (s, c) in enumerate(zip(stick_segments(rig, points), colors))]
    dots = ax.plot(np.asarray(points)[:, i], np.asarray(points)[:, j], "o", color="k", ms=2.5, alpha=alpha)[0]
    ax.set_aspect("equal", adjustable="datalim")
    if view in MIRRORED and not ax.xaxis_inverted():
        ax.invert_xaxis()
    ax.set_xlabel("xyz"[i] + (" (cm, increasing to the left)" if view in MIRRORED else " (cm)"))
    ax.set_ylabel("xyz"[j] + " (cm)")
    return lines, dots


def plot_slide(ax, times, feet, footprints, contact, labels, axis=2):
    """Each foot's offset from its footprint along `axis` (default z, the walking direction)
    in the frames it is planted: 0 for a foot that stays put, a ramp for one that skates."""
    offset = np.asarray(feet)[..., axis] - np.asarray(footprints)[..., axis]
    for k, label in enumerate(labels):
        ax.plot(times, np.where(contact[:, k], offset[:, k], np.nan), "-", color=f"C{k}", lw=2, label=label)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"foot - footprint, {'xyz'[axis]} (cm)")


def animate_clips(rig, clips, titles, root, view="side", every=3, interval=100, contact=None,
                  feet=None, footprints=None, close_up=True):
    """A FuncAnimation of clips (each (F, m, 3) world points of rig.points), one column each,
    every `every`-th frame, the camera following root (F, 3). With contact (F, k) and `feet`
    (indices into rig.points) a planted foot gets a red dot; footprints (n, 3) are drawn as
    grey crosses; close_up adds a row that looks at the feet from near the ground.

    The camera follows by moving the drawing, not the axes (x is measured from the root), so
    the axes stay still and ik.pictures.plot.frame_pngs / save_gif draw them once."""
    import matplotlib.pyplot as plt

    from .plot import _animation

    i, j = _plane(view)
    clips, root = [np.asarray(c) for c in clips], np.asarray(root)
    shown = list(range(0, len(clips[0]), every))
    top = max(c[..., j].max() for c in clips) + 10
    rows = [(110.0, (-5.0, top))] + ([(45.0, (-3.0, 30.0))] if close_up else [])
    fig, axes = plt.subplots(len(rows), len(clips), figsize=(3.6 * len(clips), 2.9 * len(rows)),
                             squeeze=False, gridspec_kw={"height_ratios": [3, 1.3][:len(rows)]})
    panels = []
    for r, (half, ylim) in enumerate(rows):
        for c, (clip, title) in enumerate(zip(clips, titles)):
            ax = axes[r, c]
            ax.axhline(0, color="0.6", lw=1)
            prints = ax.plot([], [], "x", color="0.4", ms=6, mew=1.5)[0]
            lines, dots = draw_skeleton(ax, rig, clip[0], view)
            ax.set_aspect("auto")
            ax.set_xlim(-half, half)
            ax.set_ylim(*ylim)
            ax.set_xlabel(f"{'xyz'[i]} from the root (cm)")
            marks = ax.plot([], [], "o", color="C3", ms=6, zorder=5)[0]
            if r == 0:
                ax.set_title(title, fontsize=10)
            panels.append((lines, dots, marks, prints, clip))

    def frame(k):
        f = shown[k]
        shift = np.zeros(3)
        shift[i] = root[f, i]
        out = []
        for lines, dots, marks, prints, clip in panels:
            pose = clip[f] - shift
            for line, s in zip(lines, stick_segments(rig, pose)):
                line.set_data(s[:, i], s[:, j])
            dots.set_data(pose[:, i], pose[:, j])
            if contact is not None:
                planted = pose[[p for p, c in zip(feet, contact[f]) if c]].reshape(-1, 3)
                marks.set_data(planted[:, i], planted[:, j])
            if footprints is not None:
                prints.set_data(footprints[:, i] - shift[i], footprints[:, j])
            out += [prints, *lines, dots, marks]
        return out

    anim = _animation(fig, frame, shown, interval)
    anim.still = 0
    return anim
