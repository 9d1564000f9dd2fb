"""Stills for widgets: what a notebook shows where a widget will be when no kernel runs it.

A widget box made by with_still() displays as the live widget in a running notebook and, in
the same output, as a still (its current PNG with alt text and a caption) for GitHub, static
HTML pages and a notebook opened before Run All: those show the richest output they can
render, the still, instead of "VBox(...)" or "model not found". Also a fast PNG writer for
widget images (redrawn on every slider move), and named_slider: a slider a screen reader names.
"""
import base64
import html
import struct
import zlib

import numpy as np


def png(rgba, filtered=False):
    """An (h, w, 3 or 4) uint8 image as RGB PNG bytes, written for speed: zlib's run-length
    strategy (a plot is mostly runs of one colour), several times faster than a
    general-purpose PNG encoder at a similar size. No row filter by default (line drawings);
    filtered=True for blocks of colour such as an upscaled map: each row stores its pixels'
    differences to their left neighbours (PNG filter 1, "Sub"), or nothing but filter 2
    ("Up") where it repeats the row above, so repeats become zero runs (the 128 x 128 map at
    720 x 720 pixels: 490 kB -> 83 kB, and faster)."""
    rgb = np.asarray(rgba)[..., :3]
    h, w, _ = rgb.shape
    flat = rgb.reshape(h, -1)
    rows = np.zeros((h, 3 * w + 1), dtype=np.uint8)  # each row: its filter byte, then pixels
    if filtered:
        rows[:, 0] = 1
        rows[:, 1:4] = flat[:, :3]
        np.subtract(flat[:, 3:], flat[:, :-3], out=rows[:, 4:])  # modulo 256, as PNG wants
        repeat = np.zeros(h, dtype=bool)
        repeat[1:] = (flat[1:] == flat[:-1]).all(axis=1)
        rows[repeat] = 0
        rows[repeat, 0] = 2
    else:
        rows[:, 1:] = flat
    packer = zlib.compressobj(6, zlib.DEFLATED, 15, 9, zlib.Z_RLE)
    pixels = packer.compress(rows.tobytes()) + packer.flush()

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)  # 8-bit RGB, no interlace
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", pixels) + chunk(b"IEND", b"")


def still_html(png_bytes, alt, line, width, height, what="drag the target"):
    """A widget as static HTML: its image (at most the page's width) with alt text and the
    status line under it."""
    data = base64.b64encode(png_bytes).decode("ascii")
    return (f'<figure style="margin:0"><img src="data:image/png;base64,{data}" '
            f'width="{width}" height="{height}" style="max-width:100%;height:auto" '
            f'alt="{html.escape(alt, quote=True)}">'
            f"<figcaption><code>{html.escape(line)}</code> (a still: run the notebook to "
            f"{html.escape(what)})</figcaption></figure>")


def with_still(box):
    """A subclass of the ipywidgets box class `box` whose display carries a still: give an
    instance a .still function returning (png bytes, alt text, status line, width, height,
    what the live widget lets you do)."""

    class BoxWithStill(box):
        def _repr_mimebundle_(self, **kwargs):
            data = super()._repr_mimebundle_(**kwargs)
            png_bytes, alt, line, width, height, what = self.still()
            data.update({"text/plain": line,
                         "text/html": still_html(png_bytes, alt, line, width, height, what),
                         "image/png": base64.b64encode(png_bytes).decode("ascii")})
            return data, {"image/png": {"width": width, "height": height, "alt": alt}}

    BoxWithStill.__name__ = BoxWithStill.__qualname__ = f"{box.__name__}WithStill"
    return BoxWithStill


def named_slider(w, slider, description, label_width):
    """A slider row a screen reader can name. ipywidgets 8.1 ties a slider's description to
    nothing (its handle is a <div role="slider"> without a name: Chromium's accessibility tree
    reads "slider, 2.5"), while a number box's description is its <label for=...>. So the
    row is a number box labelled `description` (the readout: typed into, or stepped with the
    arrow keys) linked to the slider beside it, which keeps its tooltip and loses its own
    description and readout. `w` is the ipywidgets module; the row's .link is the link."""
    number = w.BoundedFloatText(value=slider.value, min=slider.min, max=slider.max,
                                step=slider.step, description=description,
                                tooltip=slider.tooltip, style={"description_width": label_width},
                                layout=w.Layout(width=f"calc({label_width} + 70px)",
                                                flex="0 0 auto"))
    slider.description, slider.readout = "", False
    slider.layout.flex, slider.layout.min_width = "1 1 auto", "60px"
    row = w.HBox([number, slider], layout=w.Layout(width="auto", max_width="100%",
                                                   align_items="center"))
    # linked in the kernel, rounded: the browser's slider sends values such as
    # 3.5000000000000013 (min + k * step in floats), which the box would show as they are
    row.link = w.link((slider, "value"), (number, "value"),
                      transform=(lambda v: round(v, 10), lambda v: v))
    return row
