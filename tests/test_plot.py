"""Plot helpers: figures render, animations have the expected frames, still frames are PNGs."""
import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import ikteach as ik  # noqa: E402
from ikteach.pictures import plot  # noqa: E402

ARM = ik.planar_chain([1.0, 1.0, 1.0])
START = np.array([0.1, 0.2, 0.3])
PNG = b"\x89PNG"


def test_draw_arm_puts_the_joints_where_fk_says():
    fig, ax = plt.subplots()
    theta = np.array([0.3, -0.5, 0.9])
    links, joints, end = plot.draw_arm(ax, ARM, theta)
    xy = np.column_stack(links.get_data())
    np.testing.assert_allclose(xy, np.asarray(ik.joint_positions(ARM, theta)))
    np.testing.assert_allclose(np.column_stack(end.get_data())[0], np.asarray(ik.fk(ARM, theta)))
    plot.set_arm((links, joints, end), ARM, np.zeros(3))
    np.testing.assert_allclose(np.column_stack(end.get_data())[0], [3.0, 0.0])
    plt.close(fig)


def test_velocity_ellipse_has_the_singular_values_as_semi_axes():
    theta = np.array([0.4, 0.8, -0.3])
    J = np.asarray(ik.jacobian(ARM, theta))
    pts = plot.velocity_ellipse(J, n_points=2001)
    radii = np.linalg.norm(pts, axis=0)
    s = np.linalg.svd(J, compute_uv=False)
    assert radii.max() == pytest.approx(s[0], rel=1e-5)
    assert radii.min() == pytest.approx(s[1], rel=1e-5)


def test_velocity_ellipse_collapses_to_a_segment_at_a_singular_pose():
    pts = plot.velocity_ellipse(ik.jacobian(ARM, np.zeros(3)))
    # straight arm along x: the end effector can only move along y
    assert np.abs(pts[0]).max() < 1e-12 and np.abs(pts[1]).max() > 1.0


def test_frame_iterations_keep_first_and_last_and_the_limit():
    for k in (0, 3, 23, 24, 150, 1000):
        for spacing in ("linear", "log"):
            ks = plot.frame_iterations(k, 24, spacing)
            assert ks[0] == 0 and ks[-1] == k
            assert len(ks) == min(k + 1, 24)
            assert np.all(np.diff(ks) > 0)


def test_animate_solve_has_one_frame_per_shown_iteration_and_ends_at_the_solution():
    res = ik.solve(ARM, [2.5, 0.5], START, method="jt")
    anim = plot.animate_solve(ARM, res, [2.5, 0.5], max_frames=12)
    assert len(anim.iterations) == 12 and anim.iterations[-1] == res.iterations
    assert anim._save_count == 12 or len(list(anim.new_frame_seq())) == 12
    png = plot.still_png(anim)
    assert png.startswith(PNG)
    arm_ax = anim._fig.axes[0]
    tip = np.asarray(ik.fk(ARM, res.theta))
    ends = [l for l in arm_ax.lines if l.get_marker() == "s"]
    np.testing.assert_allclose(np.column_stack(ends[-1].get_data())[0], tip)
    assert "converged" in arm_ax.get_title()


def test_animate_race_draws_every_method_and_embeds_under_the_limit():
    results = {m: ik.solve(ARM, [3.5, 1.0], START, method=m, max_iter=200) for m in ("jt", "pinv", "dls")}
    anim = plot.animate_race(ARM, results, [3.5, 1.0], max_frames=10)
    assert len(anim._fig.axes) == 4
    assert list(anim.iterations) == list(plot.frame_iterations(200, 10, "log"))
    plot.still_png(anim)
    titles = [ax.get_title() for ax in anim._fig.axes[:3]]
    for name, title in zip(results, titles):
        assert title.startswith(name) and results[name].status in title
    html = anim.to_jshtml()
    assert html.count("data:image/png;base64") == 10
    assert len(html.encode()) < 4 * 2**20


def test_a_race_shares_one_scale_shows_ticks_and_grows_its_error_curves():
    results = {m: ik.solve(ARM, [3.5, 1.0], START, method=m, max_iter=60) for m in ("jt", "pinv", "dls")}
    anim = plot.animate_race(ARM, results, [3.5, 1.0], max_frames=6)
    arms, errors = anim._fig.axes[:3], anim._fig.axes[3]
    assert len({(ax.get_xlim(), ax.get_ylim()) for ax in arms}) == 1  # the same pose, the same size
    assert all(len(ax.get_xticks()) > 1 and len(ax.get_yticks()) > 1 for ax in arms)
    curves = errors.get_lines()[: len(results)]
    for j, k in enumerate(anim.iterations):
        anim.draw_frame(j)
        for curve, res in zip(curves, results.values()):
            assert len(curve.get_xdata()) == min(k, res.iterations) + 1


def test_plot_errors_draws_one_curve_per_result():
    fig, ax = plt.subplots()
    results = {m: ik.solve(ARM, [2.5, 0.5], START, method=m) for m in ("pinv", "dls")}
    lines = plot.plot_errors(ax, results, tol=1e-3)
    assert [l.get_label() for l in lines] == ["pinv", "dls"]
    for line, res in zip(lines, results.values()):
        np.testing.assert_allclose(line.get_ydata(), res.trace.error)
    plt.close(fig)


def test_motion_axes_zoom_to_every_joint_and_the_target():
    fig, ax = plt.subplots()
    thetas = [START, np.array([0.5, 0.4, 0.2])]
    target = [2.5, 0.5]
    plot.motion_axes(ax, ARM, thetas, targets=[target])
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    points = np.concatenate([np.asarray(ik.joint_positions(ARM, t))[:, :2] for t in thetas] + [[target]])
    assert np.all((points[:, 0] > x0) & (points[:, 0] < x1) & (points[:, 1] > y0) & (points[:, 1] < y1))
    assert x1 - x0 < 2 * float(ik.reach(ARM))  # tighter than the whole reach
    plt.close(fig)


@pytest.mark.parametrize("low, labels_at_least", [(0.3, 2), (1e-8, 4)])
def test_error_axis_has_enough_tick_labels(low, labels_at_least):
    fig, ax = plt.subplots()
    plot.plot_errors(ax, {"dls": np.geomspace(1.0, low, 20)})
    fig.canvas.draw()
    lo, hi = ax.get_ylim()
    labels = [t.get_text() for t in ax.get_yticklabels() if lo <= t.get_position()[1] <= hi]
    assert len([t for t in labels if t]) >= labels_at_least, labels
    plt.close(fig)


def test_an_animation_renders_each_saved_frame_once(monkeypatch):
    """No layout engine left behind: with one, every savefig renders twice (a dry run)."""
    arm = ik.planar_chain([1.0, 1.0, 1.0])
    res = ik.solve(arm, [1.5, 1.0], [0.3, 0.3, 0.3], method="jt")
    anim = plot.animate_solve(arm, res, [1.5, 1.0])
    assert anim._fig.get_layout_engine() is None
    renders = []
    original = matplotlib.figure.Figure.draw
    monkeypatch.setattr(matplotlib.figure.Figure, "draw",
                        lambda fig, renderer: renders.append(1) or original(fig, renderer))
    html = anim.to_jshtml()
    # matplotlib < 3.11 itself draws each saved frame twice (make test-lowest); ours adds none
    per_frame = 1 if tuple(int(v) for v in matplotlib.__version__.split(".")[:2]) >= (3, 11) else 2
    assert len(renders) == per_frame * html.count("data:image/png") == per_frame * len(anim.iterations)


def _png_pixels(png):
    import io

    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGBA"))


def _animation(kind):
    from ikteach.core import buss_trees
    from ikteach.pictures import tree_plot

    if kind == "solve":
        res = ik.solve(ARM, [1.5, 1.0], [0.3, 0.3, 0.3], method="jt")
        return plot.animate_solve(ARM, res, [1.5, 1.0])
    if kind == "race":
        race = {m: ik.solve(ARM, [3.5, 1.0], START, method=m, max_iter=60) for m in ("jt", "pinv", "dls")}
        return plot.animate_race(ARM, race, [3.5, 1.0], max_frames=6)
    if kind == "clips":  # the camera follows the hips: the drawing moves, the axes do not
        from ikteach.characters import bvh, skeleton
        from ikteach.pictures import character_plot

        sk, motion = bvh.load(bvh.walk_path())
        rig = skeleton.rig(sk)
        root, theta = skeleton.angles(rig, motion.frames[:40])
        points = skeleton.world_points(rig, root, theta)
        feet = [rig.points.index("LeftFoot"), rig.points.index("RightFoot")]
        contact = points[:, feet, 1] < 12.0
        return character_plot.animate_clips(rig, [points, points + [0, 3, 0]], ["a", "b"], root,
                                            contact=contact, feet=feet, every=8,
                                            footprints=points[contact.any(1), feet[0]])
    tree = buss_trees.y_tree()
    times = buss_trees.times(24)[::6]
    thetas = np.linspace(0.0, 0.8, len(times))[:, None] * np.ones(tree.n_joints)
    return tree_plot.animate_tree(tree, thetas, buss_trees.y_targets(times), times=times, title="Y")


@pytest.mark.parametrize("kind", ["solve", "race", "tree", "clips"])
def test_frame_pngs_match_full_redraws_except_where_moving_parts_overlap(kind, monkeypatch):
    """frame_pngs draws the still parts once: each frame must equal a full redraw of it,
    except inside the moving artists (painted over, not under, what stays still). A changing
    artist left out of the frame function (a title, say) would differ outside them."""
    anim = _animation(kind)
    renders = []
    original = matplotlib.figure.Figure.draw
    monkeypatch.setattr(matplotlib.figure.Figure, "draw",
                        lambda fig, renderer: renders.append(1) or original(fig, renderer))
    fast = [_png_pixels(png) for png in plot.frame_pngs(anim)]
    assert len(renders) == 1 and len(fast) == len(anim.iterations)
    monkeypatch.setattr(matplotlib.figure.Figure, "draw", original)
    fig = anim._fig
    for j, frame in enumerate(fast):
        full = _png_pixels(plot.still_png(anim, j))
        assert full.shape == frame.shape
        renderer = fig.canvas.get_renderer()
        inside = np.zeros(full.shape[:2], bool)
        for artist in anim.draw_frame(j):
            box = artist.get_window_extent(renderer)
            top = full.shape[0] - int(np.ceil(box.y1)) - 2
            inside[max(top, 0): full.shape[0] - int(box.y0) + 2, max(int(box.x0) - 2, 0): int(np.ceil(box.x1)) + 2] = True
        differs = np.any(full != frame, axis=-1)
        assert not np.any(differs & ~inside), f"frame {j} differs outside its moving artists"
        assert differs.mean() < 0.002, f"frame {j}: {differs.mean():.4f} of the pixels differ"


def test_save_gif_writes_every_frame_as_drawn_by_frame_pngs(tmp_path):
    from PIL import Image

    anim = _animation("clips")
    anim._fig.set_dpi(100)  # its own dpi, whatever rcParams an earlier test left
    path = plot.save_gif(anim, tmp_path / "walk.gif", fps=5, dpi=80)
    gif = Image.open(path)
    assert gif.n_frames == len(anim.iterations) == 5 and gif.info["duration"] == 200
    assert gif.size == (round(7.2 * 80), round(5.8 * 80))
    dpi = anim._fig.dpi
    assert dpi == 100  # the figure's own dpi is given back
    gif.seek(2)
    anim._fig.set_dpi(80)
    png = _png_pixels(plot.frame_pngs(anim)[2])
    anim._fig.set_dpi(dpi)
    assert np.abs(np.asarray(gif.convert("RGB"), float) - png[..., :3]).mean() < 8  # palette


def html_alt(anim):
    import html

    from ikteach.pictures import frames

    return html.escape(frames.animation_alt(anim), quote=True)


def test_to_html_embeds_the_blitted_frames_and_plays_like_to_jshtml():
    from ikteach.pictures import frames

    anim = _animation("solve")
    html = plot.to_html(anim, default_mode="once")
    reference = anim.to_jshtml(default_mode="once")
    assert html.count("data:image/png;base64") == len(anim.iterations)
    import re

    def page(h):  # the HTML and script around the frames, ids made equal
        return re.sub(r"[0-9a-f]{32}", "ID", re.sub(r"data:image/png;base64,[A-Za-z0-9+/=\\\n]+", "PNG", h))

    with_alt = reference.replace("<img id=", f'<img alt="{html_alt(anim)}" id=', 1)
    assert page(html) == page(frames.offline(with_alt))
    assert plot.embed_size(anim) == len(html.encode())


@pytest.mark.parametrize("kind", ["solve", "other"])
def test_animation_html_plays_offline_no_cdn_and_every_button_has_an_icon(kind):
    """matplotlib's player loads font-awesome from a CDN: offline its buttons would be blank."""
    import re

    anim = _animation("solve")
    if kind == "other":
        del anim.draw_frame  # an animation not made here: the to_jshtml path
    page = plot.to_html(anim)
    assert "https://maxcdn" in anim.to_jshtml()  # what matplotlib's own page needs
    assert not re.search(r"https?://|//cdn|font-awesome|<link\b", page)
    buttons = re.findall(r"<button\b.*?</button>", page, re.S)
    assert len(buttons) == 9 and all(b.count("<svg") == 1 and "<i " not in b for b in buttons)
    assert all(re.search(r'aria-label="[A-Z][a-z ]+"', b) for b in buttons)
    sliders = re.findall(r"<input\b[^>]*type=\"range\"[^>]*>", page)
    assert len(sliders) == 1 and 'aria-label="Animation frame"' in sliders[0]


def test_offline_refuses_a_page_with_an_icon_it_does_not_know():
    from ikteach.pictures import frames

    with pytest.raises(ValueError, match="page"):
        frames.offline('<button><i class="fa fa-rocket"></i></button>')


@pytest.mark.parametrize("kind", ["solve", "race", "tree", "clips"])
def test_text_in_every_animation_is_at_least_10_px_at_the_notebooks_dpi(kind):
    anim = _animation(kind)
    assert plot.smallest_text_px(anim._fig, dpi=80) >= plot.MIN_TEXT_PX - 0.5  # ik.notebook: 80


def test_save_gif_refuses_a_dpi_that_makes_text_unreadable(tmp_path):
    anim = _animation("clips")
    with pytest.raises(ValueError, match="dpi"):
        plot.save_gif(anim, tmp_path / "tiny.gif", dpi=50)  # 10 pt text: 7 px


@pytest.mark.parametrize("kind", ["solve", "tree"])
def test_an_animations_moving_picture_has_alt_text(kind):
    import re

    anim = _animation(kind)
    page = plot.to_html(anim)
    tags = re.findall(r"<img\b[^>]*>", page)
    assert tags and all(re.search(r'alt="Animation, \d+ frames\. [^"]+"', t) for t in tags)


def test_a_gif_view_carries_its_alt_text_and_needs_one(tmp_path):
    anim = _animation("clips")
    gif = plot.save_gif(anim, tmp_path / "walk.gif").read_bytes()
    data, meta = \
        plot.gif_view(gif, "two walkers")._repr_mimebundle_()
    assert 'alt="two walkers" src="data:image/gif;base64,' in data["text/html"]
    assert meta["image/png"]["alt"].endswith("two walkers")
    with pytest.raises(ValueError, match="alt"):
        plot.gif_view(gif, " ")


@pytest.mark.parametrize("every, repeats", [(6, True), (7, False)])
def test_the_walk_gif_repeats_frames_when_its_step_divides_the_gait_cycle(every, repeats):
    """The walk repeats every CYCLE s (30 frames) and the camera follows the hips: every 6th
    frame shows 5 poses over and over; every 7th frame never the same pose twice in 150."""
    from ikteach.characters import bvh, skeleton
    from ikteach.pictures import character_plot

    sk, motion = bvh.load(bvh.walk_path())
    rig = skeleton.rig(sk)
    root, theta = skeleton.angles(rig, motion.frames)
    points = skeleton.world_points(rig, root, theta)
    anim = character_plot.animate_clips(rig, [points], ["walk"], root, every=every,
                                        close_up=False)
    anim._fig.set_dpi(30)
    frames = [image.tobytes() for image in plot.frame_images(anim)]
    assert (len(set(frames)) < len(frames)) == repeats
