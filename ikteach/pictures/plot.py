"""Pictures of arms: drawing, velocity ellipses, error curves and convergence animations.

Every helper draws on a matplotlib Axes you pass in (or builds its own small figure) and
returns what it drew, so notebooks and exercises can combine them freely:

    fig, ax = plt.subplots()
    ik.pictures.plot.arm_axes(ax, arm)                    # equal aspect, limits from the arm's reach
    ik.pictures.plot.draw_arm(ax, arm, theta)             # links, joints, end effector
    ik.pictures.plot.draw_target(ax, target)
    ik.pictures.plot.draw_path(ax, arm, res.trace.theta)  # end-effector path over the iterations
    ik.pictures.plot.draw_ellipse(ax, arm, theta)         # velocity (manipulability) ellipse
    ik.pictures.plot.plot_errors(ax, {"dls": res})        # ||e|| per iteration, log scale
    anim = ik.pictures.plot.animate_solve(arm, res, target)          # arm beside its error curve
    anim = ik.pictures.plot.animate_race(arm, {"jt": r1, "dls": r2}, target)
    ik.pictures.plot.show(anim)                           # still frame (PNG) + playable JS animation

Planar arms are drawn in their plane; spatial chains are drawn projected on x-y.
"""
import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from ..core.chain import reach
from ..core.jacobian import jacobian
from ..core import kinematics
from ..core.kinematics import joint_positions
from .frames import (MIN_TEXT_PX, _animation, embed_size, fixed_layout, frame_images,  # noqa: F401
                     frame_pngs, gif_view, save_gif, show, smallest_text_px, still_png, to_html)

METHOD_COLORS = {"jt": "C0", "pinv": "C3", "dls": "C2"}
MAX_FRAMES = 16
TRAIL = 30  # end-effector positions kept behind each arm in a race


def _xy(arm, theta):
    return np.asarray(joint_positions(arm, jnp.asarray(theta, dtype=float)))[:, :2]


def color_for(name, k=0):
    """The course's colour for a method name ("jt", "pinv", "dls"), else the k-th default."""
    return METHOD_COLORS.get(name, f"C{k % 10}")


def arm_axes(ax, arm, margin=1.25, targets=()):
    """Equal aspect, limits +-margin x reach around the base (widened to show `targets`)."""
    base = np.asarray(arm.base)[:2]
    r = margin * float(reach(arm))
    lo, hi = base - r, base + r
    for t in targets:
        t = np.asarray(t, dtype=float)[:2]
        lo, hi = np.minimum(lo, t - 0.2 * r / margin), np.maximum(hi, t + 0.2 * r / margin)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    return ax


def motion_axes(ax, arm, thetas, targets=(), pad=0.12):
    """Equal aspect, limits zoomed to the motion: every joint of the arm at each of `thetas`
    and the targets, with `pad` x the larger side around them (at least 10 % of the reach)."""
    points = [_xy(arm, t) for t in thetas] + [np.asarray(t, dtype=float)[None, :2] for t in targets]
    points = np.concatenate(points)
    lo, hi = points.min(axis=0), points.max(axis=0)
    half = max(float(np.max(hi - lo)) / 2 * (1 + 2 * pad), 0.1 * float(reach(arm)))
    mid = (lo + hi) / 2
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_aspect("equal")
    return ax


def draw_reach(ax, arm, **kw):
    """The outer workspace boundary: a dashed circle of radius reach(arm) about the base."""
    kw = {"color": "0.6", "ls": "--", "lw": 1, "fill": False, **kw}
    circle = plt.Circle(np.asarray(arm.base)[:2], float(reach(arm)), **kw)
    ax.add_patch(circle)
    return circle


def draw_arm(ax, arm, theta, color="C0", alpha=1.0, lw=3, label=None, joints=True):
    """The arm at theta: links as a thick line, joints as dots, the end effector as a square.

    Returns (links, joints, end) Line2D artists (joints/end are None when joints=False);
    update an existing drawing with set_arm(artists, arm, theta).
    """
    p = _xy(arm, theta)
    (links,) = ax.plot(p[:, 0], p[:, 1], "-", color=color, lw=lw, alpha=alpha, label=label,
                       solid_capstyle="round", zorder=3)
    jts = end = None
    if joints:
        (jts,) = ax.plot(p[:-1, 0], p[:-1, 1], "o", ms=5, mfc="white", mec=color, alpha=alpha,
                         zorder=4)
        (end,) = ax.plot(p[-1:, 0], p[-1:, 1], "s", ms=6, color=color, alpha=alpha, zorder=4)
    return links, jts, end


def set_arm(artists, arm, theta):
    """Move arm artists made by draw_arm to a new theta (for animations)."""
    p = _xy(arm, theta)
    links, jts, end = artists
    links.set_data(p[:, 0], p[:, 1])
    if jts is not None:
        jts.set_data(p[:-1, 0], p[:-1, 1])
        end.set_data(p[-1:, 0], p[-1:, 1])
    return artists


def draw_target(ax, target, color="k", label="target"):
    """The target as a cross."""
    t = np.asarray(target, dtype=float)
    (mark,) = ax.plot([t[0]], [t[1]], "x", color=color, ms=9, mew=2, label=label, zorder=5)
    return mark


def end_path(arm, thetas):
    """End-effector positions (k, 2) along a sequence of joint vectors (k, n)."""
    return kinematics.end_path(arm, thetas)[:, :2]


def draw_path(ax, arm, thetas, color="C0", **kw):
    """The end effector's path over a sequence of joint vectors (a trace), dots at iterates."""
    p = end_path(arm, thetas)
    (line,) = ax.plot(p[:, 0], p[:, 1], ".-", color=color, lw=1, ms=3, alpha=0.7, **kw)
    return line


def velocity_ellipse(J, n_points=100):
    """Points of {J u : ||u|| = 1}, the image of the unit joint-velocity sphere (2, n_points).

    With J = U diag(sigma) V^T the ellipse has semi-axes sigma_i u_i; it collapses to a
    segment where sigma_min = 0 (a singular pose).
    """
    J = np.asarray(J, dtype=float)[:2]
    U, s, _ = np.linalg.svd(J)
    s = np.pad(s, (0, 2 - s.size))
    t = np.linspace(0.0, 2.0 * np.pi, n_points)
    return U @ (s[:, None] * np.vstack([np.cos(t), np.sin(t)]))


def draw_ellipse(ax, arm, theta, scale=0.3, color="C1", **kw):
    """The velocity ellipse of J(theta), scaled by `scale`, centred on the end effector."""
    pts = scale * velocity_ellipse(jacobian(arm, np.asarray(theta, dtype=float)))
    tip = _xy(arm, theta)[-1]
    (line,) = ax.plot(tip[0] + pts[0], tip[1] + pts[1], "-", color=color, lw=1.5, **kw)
    return line


def plot_errors(ax, results, tol=None):
    """||e|| against iteration (log scale) for {label: Result or array of errors}."""
    lines = []
    for k, (name, res) in enumerate(results.items()):
        err = np.asarray(getattr(getattr(res, "trace", None), "error", res), dtype=float)
        (line,) = ax.semilogy(np.arange(err.size), np.maximum(err, 1e-16), "-",
                              color=color_for(name, k), label=name)
        lines.append(line)
    if tol is not None:
        ax.axhline(tol, color="0.5", ls=":", lw=1, label="tol")
    _error_axis(ax)
    ax.legend(loc="best", fontsize=9)
    return lines


def _tick_text(y, _pos=None):
    """0.5, 2, 1e-3: plain tick labels (mathtext is slow to redraw per frame)."""
    return f"{y:g}" if 1e-2 <= y < 1e4 else f"{y:.0e}".replace("e-0", "e-").replace("e+0", "e")


def _error_axis(ax):
    """Label a log error axis with enough ticks: 1-2-5 per decade when it spans few decades."""
    ax.set_xlabel("iteration")
    ax.set_ylabel("|e|")
    lo, hi = ax.get_ylim()
    few = np.log10(hi / lo) < 3 if lo > 0 else False
    ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0) if few else (1.0,)))
    ax.yaxis.set_major_formatter(FuncFormatter(_tick_text))
    ax.yaxis.set_minor_formatter(NullFormatter())


def frame_iterations(iterations, max_frames=MAX_FRAMES, spacing="linear"):
    """Which iterations to show: 0..iterations, at most max_frames of them, first and last kept.

    spacing="log" crowds the frames at the start, where the arm moves most.
    """
    if iterations + 1 <= max_frames:
        return np.arange(iterations + 1)
    if spacing == "log":
        ks = np.geomspace(1, iterations + 1, max_frames) - 1
    else:
        ks = np.linspace(0, iterations, max_frames)
    ks = np.unique(np.round(ks).astype(int))
    # rounding merges early log frames: fill back up with the smallest missing iterations
    missing = np.setdiff1d(np.arange(iterations + 1), ks)[: max_frames - ks.size]
    return np.union1d(ks, missing)


def _error_label(res, k):
    k = min(k, res.iterations)
    return f"it {k}: |e|={res.trace.error[k]:.3g}"


def _finish(res):
    return f"{res.status} after {res.iterations}"


def animate_solve(arm, result, target, max_frames=MAX_FRAMES, title=None, spacing="linear",
                  figsize=(8.0, 3.4)):
    """The arm converging (left) beside its error curve (right), one frame per shown iteration.

    Returns a matplotlib FuncAnimation (display it with ik.pictures.plot.show); anim.iterations lists
    the iteration of each frame and anim.still is the last frame's index.
    """
    ks = frame_iterations(result.iterations, max_frames, spacing)
    fig, (ax, ax_err) = plt.subplots(1, 2, figsize=figsize, gridspec_kw={"width_ratios": [1, 1.2]})
    motion_axes(ax, arm, result.trace.theta[ks], targets=[target])
    draw_reach(ax, arm, label="reach")
    draw_arm(ax, arm, result.trace.theta[0], color="0.7", lw=2, joints=False, label="start pose")
    draw_target(ax, target)
    path = end_path(arm, result.trace.theta)
    (trail,) = ax.plot([], [], ".-", color="C1", lw=1, ms=3, label="end-effector path")
    arm_artists = draw_arm(ax, arm, result.trace.theta[0], label="arm")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=3, fontsize=9, frameon=False)
    heading = ax.set_title(title or "", fontsize=9)
    err = np.maximum(result.trace.error, 1e-16)
    ax_err.semilogy(np.arange(err.size), err, "-", color="0.75")
    (done,) = ax_err.semilogy([], [], "-", color="C0")
    (now,) = ax_err.semilogy([], [], "o", color="C0")
    _error_axis(ax_err)
    ax_err.set_xlim(-0.5, max(result.iterations, 1) + 0.5)

    def frame(j):
        k = ks[j]
        set_arm(arm_artists, arm, result.trace.theta[k])
        trail.set_data(path[: k + 1, 0], path[: k + 1, 1])
        done.set_data(np.arange(k + 1), err[: k + 1])
        now.set_data([k], [err[k]])
        label = _error_label(result, k)
        if k == result.iterations:
            label += f" ({_finish(result)})"
        heading.set_text(f"{title}\n{label}" if title else label)
        return (*arm_artists, trail, done, now, heading)

    return _animation(fig, frame, ks, interval=250)


def animate_race(arm, results, target, max_frames=MAX_FRAMES, spacing="log", figsize=None):
    """Several methods racing to one target: one arm panel per method and a shared error panel.

    results maps a label ("jt", "pinv", "dls", ...) to its Result from the same start.
    Frames follow a common iteration counter; a method that has stopped stays at its end.
    The arm panels share one scale (every method's motion) and show their ticks; each error
    curve grows with the frames up to the iteration shown.
    """
    names = list(results)
    longest = max(r.iterations for r in results.values())
    ks = frame_iterations(longest, max_frames, spacing)
    n = len(names)
    figsize = figsize or (max(7.5, 2.5 * n), 5.4)
    fig = plt.figure(figsize=figsize)
    grid = fig.add_gridspec(2, n, height_ratios=[1.1, 1])
    axes = [fig.add_subplot(grid[0, k]) for k in range(n)]
    ax_err = fig.add_subplot(grid[1, :])
    artists, trails, headings, paths, dots = [], [], [], [], []
    every = np.concatenate([r.trace.theta[np.minimum(ks, r.iterations)] for r in results.values()])
    for k, (name, ax) in enumerate(zip(names, axes)):
        res, c = results[name], color_for(name, k)
        motion_axes(ax, arm, every, targets=[target])  # one scale for every panel
        draw_reach(ax, arm)
        draw_target(ax, target, label=None)
        paths.append(end_path(arm, res.trace.theta))
        trails.append(ax.plot([], [], ".-", color=c, lw=0.8, ms=2, alpha=0.6)[0])
        artists.append(draw_arm(ax, arm, res.trace.theta[0], color=c, lw=2.5))
        headings.append(ax.set_title(name, fontsize=9))
        ax.tick_params(labelsize=9)
        ax.locator_params(nbins=4)
    curves = plot_errors(ax_err, results)  # full curves set the axis limits; frames cut them
    for k, name in enumerate(names):
        res = results[name]
        dots.append(ax_err.plot([], [], "o", color=color_for(name, k), ms=5)[0])
    marker = ax_err.axvline(0, color="0.4", lw=1)
    if longest > 30:  # early iterations matter most: stretch them
        ax_err.set_xscale("symlog", linthresh=10)
        ax_err.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:.0f}"))
    ax_err.set_xlim(0, longest * 1.05 + 0.5)
    ax_err.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9)

    def frame(j):
        k = ks[j]
        drawn = [marker]
        marker.set_xdata([k, k])
        for name, art, trail, head, path, dot, curve in zip(names, artists, trails, headings, paths, dots, curves):
            res = results[name]
            kk = min(k, res.iterations)
            curve.set_data(np.arange(kk + 1), np.maximum(res.trace.error[: kk + 1], 1e-16))
            set_arm(art, arm, res.trace.theta[kk])
            first = max(0, kk - TRAIL)
            trail.set_data(path[first: kk + 1, 0], path[first: kk + 1, 1])
            dot.set_data([kk], [max(res.trace.error[kk], 1e-16)])
            state = _finish(res) if k >= res.iterations else f"iteration {kk}"
            head.set_text(f"{name}: {state}\n|e| = {res.trace.error[kk]:.3g}")
            drawn += [*art, trail, head, dot, curve]
        return drawn

    return _animation(fig, frame, ks, interval=300)
