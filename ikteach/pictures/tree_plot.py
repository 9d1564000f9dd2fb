"""Drawing trees (and their targets) with matplotlib: a front view onto two world axes."""
import numpy as np

from ..core.tree import tree_frames


def tree_segments(arm, theta):
    """Line segments of the tree: each joint to its parent joint, each effector to its joint."""
    p, _, x = (np.asarray(a) for a in tree_frames(arm, theta))
    segs = [(p[q], p[j]) for j, q in enumerate(arm.parents) if q >= 0]
    segs += [(p[j], x[k]) for k, j in enumerate(arm.effector_parents)]
    return np.array(segs), p, x


def draw_tree(ax, arm, theta, targets=None, plane=(0, 1), color="C0"):
    """Draw the tree at theta (links, joints, effectors) and the targets; returns the artists."""
    i, j = plane
    segs, p, x = tree_segments(arm, theta)
    lines = [ax.plot(s[:, i], s[:, j], "-", color=color, lw=3, solid_capstyle="round")[0] for s in segs]
    joints = ax.plot(p[:, i], p[:, j], "o", color="k", ms=4)[0]
    effs = ax.plot(x[:, i], x[:, j], "s", color=color, ms=6)[0]
    t = np.empty((0, 3)) if targets is None else np.asarray(targets)
    tgt = ax.plot(t[:, i], t[:, j], "x", color="C3", ms=9, mew=2)[0]
    ax.set_aspect("equal")
    ax.set_xlabel("xyz"[i])
    ax.set_ylabel("xyz"[j])
    return lines, joints, effs, tgt


def animate_tree(arm, thetas, targets, plane=(0, 1), limits=((-2.5, 4.0), (-1.0, 2.5)), interval=50,
                 times=None, title="tree"):
    """A FuncAnimation of the tree following its targets (one frame per row of thetas), titled
    with the time of each frame (`times`, Buss's τ) when given; show it with ik.pictures.plot.show (still frame)."""
    import matplotlib.pyplot as plt

    from .plot import _animation

    fig, ax = plt.subplots(figsize=(5.5, 3.4))
    ax.set_xlim(*limits[0])
    ax.set_ylim(*limits[1])
    lines, joints, effs, tgt = draw_tree(ax, arm, thetas[0], targets[0], plane)
    effs.set_label("end effectors")
    tgt.set_label("targets")
    ax.legend(loc="upper right", fontsize=9)
    i, j = plane

    def frame(k):
        segs, p, x = tree_segments(arm, thetas[k])
        for line, s in zip(lines, segs):
            line.set_data(s[:, i], s[:, j])
        joints.set_data(p[:, i], p[:, j])
        effs.set_data(x[:, i], x[:, j])
        tgt.set_data(targets[k][:, i], targets[k][:, j])
        when = f"τ = {times[k]:5.2f}" if times is not None else f"frame {k}"  # Buss's time (his T)
        heading = ax.set_title(f"{title}: {when}", fontsize=9)
        return (*lines, joints, effs, tgt, heading)

    return _animation(fig, frame, np.arange(len(thetas)), interval=interval)
