"""A live workspace map: a lambda slider and a method dropdown re-solve a grid of targets
with ik.solve_batch and redraw the map (iterations, final error or status) as a PNG.

    live = ik.pictures.live_map.LiveMap()      # widgets; live.widget to display in a notebook
    live.update(damping=0.2)          # what a control change does; returns the SweepMap
    live.png, live.still()            # the current picture; as HTML with alt text (static viewers)

The batch is compiled once per method; a new lambda is a traced number, so a change costs
one solve_batch over the grid and one small PNG render. Maps are kept per method and lambda
(the JT map once: lambda does not change it), so moving lambda under JT, switching back to a
method seen before or changing what is shown re-solves nothing. After each redraw the maps
one slider step either side of lambda are solved in a background thread (prefetch=True)
once the student has moved a control, while they look: a step of the slider then finds its map solved (a jump further,
or a move before the prefetch ends, solves or waits as before).

The map is SIZE x SIZE CSS pixels (at most the page's width), rendered at HIDPI times that;
only the map and its title are redrawn over a cached background. The browser shows it as an
<img> with alt text in an HTML widget (an Image widget has no alt). Displayed, the widget
also carries a still (PNG with alt text + status line) that static pages show in its place.
"""
import base64
import html
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np

from ..core.chain import planar_chain
from ..core.sweeps import sweep, target_grid
from .workspace_maps import STATUS_COLOR_NAMES, STATUS_COLORS, status_image

QUANTITIES = ("iterations", "error", "status")
MAP_METHODS = ("dls", "jt")  # pinv, sdls: an SVD per step, seconds per map
DAMPED = ("dls", "sdls")     # the methods whose map lambda changes
SIZE = 360    # CSS pixels, the map's width and height on the page
HIDPI = 2     # rendered at HIDPI x SIZE pixels
KEPT = 64     # maps kept (per method and lambda) before the oldest is dropped
_POOL = []    # the one background thread that prefetches maps, made when first needed


def _background():
    if not _POOL:
        _POOL.append(ThreadPoolExecutor(max_workers=1, thread_name_prefix="ikteach-live-map"))
    return _POOL[0]


def img_html(png_bytes, alt, size=SIZE):
    """The map as an <img> with alt text, SIZE CSS pixels wide at most the page's width."""
    data = base64.b64encode(png_bytes).decode("ascii")
    return (f'<img src="data:image/png;base64,{data}" alt="{html.escape(alt, quote=True)}" '
            f'width="{size}" height="{size}" style="display:block;width:100%;height:auto">')


def map_image(result, quantity):
    """The picture of one quantity of a SweepMap: iterations, log10 of the final error
    (n, n), or the status colours (n, n, 3)."""
    if quantity == "iterations":
        return np.asarray(result.iterations, dtype=float)
    if quantity == "error":
        return np.log10(np.maximum(np.asarray(result.error, dtype=float), 1e-16))
    if quantity == "status":
        return status_image(result.status)
    raise ValueError(f"quantity: expected one of {list(QUANTITIES)}, got {quantity!r}")


def compute_map(arm, grid, theta0, method="dls", damping=0.5, quantity="iterations", **kwargs):
    """Solve every grid target (ik.pictures.workspace_maps.sweep) and return (SweepMap, image)."""
    result = sweep(arm, grid, theta0, method=method, damping=damping, **kwargs)
    return result, map_image(result, quantity)


def _status_words():
    """'green converged, orange stalled, ...' for every status, three to a line."""
    words = [f"{STATUS_COLOR_NAMES[s]} {s}" for s in STATUS_COLORS]
    return ",\n".join(", ".join(words[k:k + 3]) for k in range(0, len(words), 3))


def _label(quantity, max_iter):
    return {"iterations": f"iterations, dark 0 to yellow {max_iter}",
            "error": "log10 of the final |e|, dark small to yellow large",
            "status": _status_words()}[quantity]


class LiveMap:
    """lambda slider, method and quantity dropdowns; each change redraws the map, solving
    only a map not solved before. tol=None: the solver's default, L/3000 (as ik.solve_batch)."""

    def __init__(self, arm=None, grid_n=128, theta0=(0.3, 0.3, 0.3), method="dls",
                 damping=0.5, quantity="iterations", tol=None, max_iter=100, prefetch=True):
        import ipywidgets as w

        from .stills import with_still

        self.arm = planar_chain([1.0, 1.0, 1.0]) if arm is None else arm
        self.grid = target_grid(self.arm, n=grid_n)
        self.theta0 = np.asarray(theta0, dtype=float)
        self.tol, self.max_iter = tol, max_iter
        self._maps = {}  # (method, lambda or None) -> SweepMap, or a Future of one (prefetch)
        self.prefetch = prefetch
        style = {"description_width": "auto"}
        self.damping = w.FloatSlider(value=damping, min=0.0, max=2.0, step=0.05,
                                     description="λ (dls)", readout_format=".2f", style=style,
                                     tooltip="damping lambda of damped least squares")
        self.method = w.Dropdown(options=list(MAP_METHODS), value=method, description="method",
                                 style=style, layout=w.Layout(width="auto"))
        self.quantity = w.Dropdown(options=list(QUANTITIES), value=quantity, description="show",
                                   style=style, layout=w.Layout(width="auto"))
        # a fixed CSS size (not stretched to the page), at most the page's width; an HTML
        # widget holding an <img alt=...>
        self.image = w.HTML(layout=w.Layout(width=f"{SIZE}px", max_width="calc(100% - 4px)",
                                            height="auto"))
        self.text = w.Label()
        from .stills import named_slider

        lam = named_slider(w, self.damping, "λ (dls)", "50px")  # labelled for screen readers
        lam.layout.width = "300px"
        controls = w.HBox([lam, self.method, self.quantity],
                          layout=w.Layout(flex_flow="row wrap", max_width="100%"))
        self.widget = with_still(w.VBox)([controls, self.text, self.image],
                                         layout=w.Layout(max_width="100%"))
        self.widget.still = lambda: (self.png, self.alt, self.summary, SIZE, SIZE,
                                     "move lambda or switch the method")
        self._build_figure()
        self._holding = False
        for control in (self.damping, self.method, self.quantity):
            control.observe(self._changed, names="value")
        self.update()

    def _build_figure(self):
        """Axes, labels and ticks drawn once as a cached background; the map and its title
        are drawn over it on each update."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        inches = SIZE / 100  # text in points is then points * 100 / 72 CSS pixels
        self._fig = Figure(figsize=(inches, inches), dpi=100 * HIDPI)
        self._canvas = FigureCanvasAgg(self._fig)
        self._ax = ax = self._fig.add_axes((0.15, 0.12, 0.8, 0.64))  # room for 4 title lines
        self._im = ax.imshow(np.zeros(self.grid.shape), origin="lower", extent=self.grid.extent,
                             interpolation="nearest")
        ax.set_aspect("equal")
        ax.set_xlabel("target x", fontsize=9)
        ax.set_ylabel("target y", fontsize=9)
        ax.tick_params(labelsize=8)
        ax.grid(False)
        self._title = ax.set_title("", fontsize=9)
        for artist in (self._im, self._title):
            artist.set_animated(True)
        self._canvas.draw()
        self._background = self._canvas.copy_from_bbox(self._fig.bbox)

    def _changed(self, _change):
        """A control moved in the browser: redraw, then prefetch the neighbours (only after a
        move: a notebook's Run All, which only displays the map, solves nothing extra)."""
        if not self._holding:
            self.update()
            self._prefetch(self.method.value, self.damping.value)

    def _key(self, method, damping):
        return (method, round(float(damping), 12) if method in DAMPED else None)

    def _keep(self, key, value):
        if len(self._maps) >= KEPT:
            self._maps.pop(next(iter(self._maps)))
        self._maps[key] = value

    def _sweep(self, method, damping):
        return sweep(self.arm, self.grid, self.theta0, method=method, damping=damping,
                     tol=self.tol, max_iter=self.max_iter)

    def map_for(self, method, damping):
        """The SweepMap of a method and lambda, solved once (lambda ignored by undamped methods);
        a map being prefetched is waited for, not solved again."""
        key = self._key(method, damping)
        if key not in self._maps:
            self._keep(key, self._sweep(method, damping))
        found = self._maps[key]
        if isinstance(found, Future):
            found = self._maps[key] = found.result()
        return found

    def _prefetch(self, method, damping):
        """Solve the maps one slider step either side of lambda in the background thread."""
        if not self.prefetch or method not in DAMPED:
            return
        step = self.damping.step
        for lam in (damping + step, damping - step):
            lam = round(lam, 10)
            key = self._key(method, lam)
            if self.damping.min <= lam <= self.damping.max and key not in self._maps:
                self._keep(key, _background().submit(self._sweep, method, lam))

    def update(self, damping=None, method=None, quantity=None):
        """Set any controls given, then redraw the map (solving it only if not solved before).
        Returns the SweepMap."""
        self._holding = True
        try:
            for control, value in ((self.damping, damping), (self.method, method),
                                   (self.quantity, quantity)):
                if value is not None:
                    control.value = value
        finally:
            self._holding = False
        method, lam = self.method.value, self.damping.value
        self.result = self.map_for(method, lam)
        counts = ", ".join(f"{k} {v}" for k, v in self.result.counts().items())
        shown = f"λ = {lam:.2f}" if method in DAMPED else "no λ"
        self.summary = f"{method}, {shown}: {counts}"
        self.text.value = self.summary
        self.alt = (f"Workspace map of {self.grid.shape[0]} x {self.grid.shape[1]} targets, "
                    f"coloured by {' '.join(_label(self.quantity.value, self.max_iter).split())}; "
                    f"{self.summary}.")
        self.png = self._draw(map_image(self.result, self.quantity.value))
        self.image.value = img_html(self.png, self.alt)
        return self.result

    def _draw(self, picture):
        from .stills import png

        self._im.set_data(picture)
        if self.quantity.value == "iterations":
            self._im.set_clim(0, self.max_iter)  # the same colours for every lambda
        elif picture.ndim == 2:
            self._im.set_clim(float(picture.min()), float(picture.max()))
        shown = f"λ = {self.damping.value:.2f}" if self.method.value in DAMPED else "λ unused"
        self._title.set_text(f"{self.method.value}, {shown}\n"
                             f"{_label(self.quantity.value, self.max_iter)}")
        self._canvas.restore_region(self._background)
        self._ax.draw_artist(self._im)
        self._ax.draw_artist(self._title)
        return png(self._canvas.buffer_rgba(), filtered=True)

    def still(self):
        """The current map as static HTML (an <img> with alt text), for viewers without a kernel
        (displaying .widget shows the same still where no kernel runs it)."""
        from IPython.display import HTML

        return HTML(img_html(self.png, self.alt))
