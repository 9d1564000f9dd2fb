"""Animations as pictures: lay a figure out once, draw its frames (only what moves is
redrawn), encode them as PNGs, GIFs or a playable HTML animation, and show one in a notebook
with its still frame and alt text. ik.pictures.plot re-exports these (ik.pictures.plot.show, ik.pictures.plot.save_gif,
ik.pictures.plot.gif_view). Text in a frame is at least MIN_TEXT_PX pixels tall (smallest_text_px).
"""
import io
import re

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.animation import FuncAnimation

MIN_TEXT_PX = 10  # the smallest text an animation or GIF may show, in pixels (9 pt at 80 dpi)


def smallest_text_px(fig, dpi=None):
    """The height in pixels of the smallest visible text in a figure drawn at dpi (default:
    the figure's): font size in points x dpi / 72. Tick labels count, empty texts do not."""
    from matplotlib.text import Text

    fig.canvas.draw()  # makes the tick labels
    sizes = [t.get_fontsize() for t in fig.findobj(Text) if t.get_visible() and t.get_text()]
    return min(sizes) * (dpi or fig.dpi) / 72 if sizes else None


def fixed_layout(fig):
    """tight_layout once, then no layout engine: tight_layout leaves a placeholder engine, and
    with any engine every savefig renders the figure twice (a dry run first), which doubled
    the cost of every animation frame."""
    fig.tight_layout()
    fig.set_layout_engine(None)


def _animation(fig, frame, ks, interval):
    """Lay the figure out at its last frame (the longest titles), wrap it in a FuncAnimation
    that remembers the iterations it shows, its still frame and its frame function (which
    returns every artist a frame changes), and close the figure."""
    frame(len(ks) - 1)
    fixed_layout(fig)
    anim = FuncAnimation(fig, frame, frames=len(ks), interval=interval, blit=False, repeat=True)
    anim.iterations = ks
    anim.still = len(ks) - 1
    anim.draw_frame = frame
    plt.close(fig)
    return anim


def still_png(anim, frame=None):
    """PNG bytes of one frame of an animation (default: its still frame, the last one)."""
    anim._init_draw()
    anim._draw_frame(anim.still if frame is None else frame)
    buf = io.BytesIO()
    anim._fig.savefig(buf, format="png")
    return buf.getvalue()


def frame_pngs(anim):
    """PNG bytes of every frame of an animation made here (see frame_images). Each frame is
    encoded on a worker thread while the next is drawn: zlib runs without Python's lock, so
    the encoding (40-45 % of the drawing's time) overlaps it on a second core."""
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=2) as pool:
        encoding = frame_images(anim, each=lambda image: pool.submit(_png_bytes, image))
        return [future.result() for future in encoding]


def _png_bytes(image):
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(image).save(buf, format="png")
    return buf.getvalue()


def frame_images(anim, each=None):
    """Every frame of an animation made here as an RGBA array, drawing what stays still once;
    with `each`, the list of each(array) called as every frame is drawn.

    The figure is drawn once without the artists a frame changes (the arm, trail, titles...);
    each frame restores that background and draws only those artists on it, as blitting does
    on screen. A full redraw spent most of its time on unchanging axes, ticks and legends.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    anim._init_draw()  # counts as drawn: no "deleted without rendering" warning
    fig = anim._fig
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    moving = list(anim.draw_frame(0))
    for artist in moving:
        artist.set_animated(True)  # left out of canvas.draw()
    try:
        canvas.draw()
        background = canvas.copy_from_bbox(fig.bbox)
        images = []
        for j in range(len(anim.iterations)):
            drawn = _in_draw_order(fig, anim.draw_frame(j))
            canvas.restore_region(background)
            for artist in drawn:
                fig.draw_artist(artist)
            image = np.array(canvas.buffer_rgba())
            images.append(image if each is None else each(image))
    finally:
        for artist in moving:
            artist.set_animated(False)
    return images


def save_gif(anim, path, fps=5, dpi=None):
    """Write an animation made here as a looping GIF, its frames from frame_images (what stays
    still drawn once), like anim.save(path, writer="pillow", fps=fps, dpi=dpi). A dpi at which
    the figure's smallest text would be under MIN_TEXT_PX pixels is a ValueError."""
    from PIL import Image

    fig = anim._fig
    small = smallest_text_px(fig, dpi)
    if small is not None and small < MIN_TEXT_PX - 0.5:
        least = MIN_TEXT_PX * (dpi or fig.dpi) / small
        raise ValueError(f"dpi: {dpi} draws text {small:.1f} px tall, under {MIN_TEXT_PX} px; "
                         f"use a dpi of at least {least:.0f}")
    old_dpi = fig.dpi
    if dpi is not None:
        fig.set_dpi(dpi)
    try:
        frames = [Image.fromarray(image) for image in frame_images(anim)]
    finally:
        fig.set_dpi(old_dpi)
    frames[0].save(path, save_all=True, append_images=frames[1:], duration=int(1000 / fps),
                   loop=0)
    return path


def _in_draw_order(fig, artists):
    """The artists in the order a full draw paints them: axes by axes, by zorder, then as added."""
    rank = {}
    for a, ax in enumerate(fig.axes):
        for c, child in enumerate(ax.get_children()):
            rank[id(child)] = (a, child.get_zorder(), c)
    return sorted(artists, key=lambda artist: rank.get(id(artist), (len(fig.axes), 0, 0)))


def animation_alt(anim):
    """Alt text of an animation's moving picture: its figure's titles and labels, frame count."""
    from .alt_text import figure_alt

    frames = len(getattr(anim, "iterations", ())) or "several"
    return f"Animation, {frames} frames. {figure_alt(anim._fig)}"


def _with_alt(page, alt):
    """matplotlib's JavaScript animation shows its frames in an <img> without alt: add it."""
    import html

    return page.replace("<img id=", f'<img alt="{html.escape(alt, quote=True)}" id=', 1)


# matplotlib's player draws its buttons with font-awesome icons from a CDN stylesheet: offline
# (a lecture hall, a book opened from disk) the buttons are blank. Each icon becomes an inline
# SVG (16 x 16, drawn in the text colour); the buttons keep their title and aria-label.
_ICON_PATHS = {
    "fa fa-minus": "M2 7h12v2H2z",
    "fa fa-plus": "M7 2h2v5h5v2H9v5H7V9H2V7h5z",
    "fa fa-play": "M4 2l10 6-10 6z",
    "fa fa-play fa-flip-horizontal": "M12 2L2 8l10 6z",
    "fa fa-pause": "M3 2h4v12H3zM9 2h4v12H9z",
    "fa fa-step-forward": "M3 2l8 6-8 6zM11 2h2v12h-2z",
    "fa fa-step-backward": "M13 2L5 8l8 6zM3 2h2v12H3z",
    "fa fa-fast-forward": "M1 2l6 6-6 6zM7 2l6 6-6 6zM13 2h2v12h-2z",
    "fa fa-fast-backward": "M15 2L9 8l6 6zM9 2L3 8l6 6zM1 2h2v12H1z",
}
_CDN_STYLESHEET = re.compile(r'<link rel="stylesheet"\s+href="https?://[^"]*font-awesome[^"]*">\s*')


def _icon_svg(path):
    return ('<svg width="14" height="14" viewBox="0 0 16 16" aria-hidden="true" focusable="false" '
            f'style="vertical-align:middle"><path fill="currentColor" d="{path}"/></svg>')


_UNNAMED_SLIDER = re.compile(r'(<input\b(?![^>]*\baria-label=)[^>]*class="anim-slider")')


def offline(page):
    """matplotlib's animation HTML without its font-awesome stylesheet from a CDN: every
    button icon an inline SVG, so the page plays with its buttons drawn with no network; its
    frame slider named for screen readers ("Animation frame": matplotlib's has no name).
    An icon or an outside URL this does not know is a ValueError (a new matplotlib's player)."""
    page = _CDN_STYLESHEET.sub("", page)
    page = _UNNAMED_SLIDER.sub(r'\1 aria-label="Animation frame"', page)
    for name, path in _ICON_PATHS.items():
        page = page.replace(f'<i class="{name}"></i>', _icon_svg(path))
    left = re.findall(r'<i class="fa[^"]*"></i>|https?://[^\s"\'<>]+', page)
    if left:
        raise ValueError(f"page: animation HTML still needs {sorted(set(left))[:3]} (update _ICON_PATHS)")
    return page


def to_html(anim, default_mode="loop"):
    """The animation as playable JavaScript HTML, like anim.to_jshtml() but with frames from
    frame_pngs (each frame draws only what moves), alt text on its <img> and no outside URL
    (offline: the buttons' icons inline); other animations use to_jshtml, made offline alike."""
    if not hasattr(anim, "draw_frame"):
        return offline(_with_alt(anim.to_jshtml(default_mode=default_mode), animation_alt(anim)))
    import base64
    import tempfile
    from pathlib import Path

    from matplotlib.animation import HTMLWriter

    writer = HTMLWriter(fps=1000 / anim._interval, embed_frames=True, default_mode=default_mode)
    frames = [base64.encodebytes(png).decode("ascii") for png in frame_pngs(anim)]
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder, "animation.html")
        writer.setup(anim._fig, path, dpi=anim._fig.dpi)
        writer._saved_frames = frames
        writer.finish()
        return offline(_with_alt(path.read_text(), animation_alt(anim)))


def show(anim, frame=None):
    """Display an animation in a notebook: first its still frame as a PNG with alt text
    (readable where scripts do not run, e.g. on GitHub), then the playable JavaScript."""
    from IPython.display import HTML, display

    from .alt_text import figure_alt, img_html

    png = still_png(anim, frame)
    display(HTML(img_html(png, "Still frame of an animation. " + figure_alt(anim._fig))))
    display(HTML(to_html(anim, default_mode="once")))


def embed_size(anim):
    """Size in bytes of the animation as embedded JavaScript HTML (to keep under the limit)."""
    return len(to_html(anim).encode())


class GifView:
    """A GIF for a notebook: an animated <img> with alt text (text/html) and its last frame as
    a PNG (image/png, with the same alt) for static renderers that drop HTML."""

    def __init__(self, gif, alt):
        from pathlib import Path

        if not alt or not str(alt).strip():
            raise ValueError("alt: a GIF needs a text that says what it shows")
        self.gif = gif if isinstance(gif, bytes) else Path(gif).read_bytes()
        self.alt = alt

    def last_frame_png(self):
        from PIL import Image

        with Image.open(io.BytesIO(self.gif)) as im:
            im.seek(im.n_frames - 1)
            buf = io.BytesIO()
            im.convert("RGB").save(buf, format="png")
        return buf.getvalue()

    def _repr_mimebundle_(self, **kwargs):
        import base64
        import html

        data = base64.b64encode(self.gif).decode("ascii")
        tag = f'<img alt="{html.escape(self.alt, quote=True)}" src="data:image/gif;base64,{data}"/>'
        png = base64.b64encode(self.last_frame_png()).decode("ascii")
        return ({"text/html": tag, "image/png": png, "text/plain": f"GIF: {self.alt}"},
                {"image/png": {"alt": f"Last frame of the GIF. {self.alt}"}})


def gif_view(gif, alt):
    """Display a GIF (bytes or a path) in a notebook with alt text and a static fallback."""
    return GifView(gif, alt)
