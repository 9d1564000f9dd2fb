"""The lab's interactive demo: drag the target, watch the arm follow.

    demo = ik.pictures.demo.Demo()          # widgets: target x, y, lambda, method, preset buttons
    demo.widget                    # display it in a notebook
    demo.update(x=3.5, y=1.0)      # what a slider change does; returns the Result

Every change re-solves from the same start theta0 with ik.solve, redraws the arm, its
start pose and the end effector's path, and prints one line: method, status and
iterations. The solve is compiled once per method (the target and lambda are traced
numbers), so a change costs a few milliseconds of solving. The picture the browser shows is
a small SVG (a few kB: lines, dots and a circle, drawn by the browser, sharp at any zoom;
role="img" with the alt text as its name) in an HTML widget: no PNG to render, send or
decode per move. Without a browser, call update() and read .result, .summary, .svg, .png.

The picture is SIZE x SIZE CSS pixels beside its controls (fits a 1280x720 laptop screen
with JupyterLab around it; narrower, at 200 % zoom, the controls wrap under it and the
picture shrinks to the page's width). Displayed, the widget also carries a still (a PNG
drawn by matplotlib at HIDPI x SIZE pixels, with alt text, + status line) that static pages
(GitHub, nbconvert HTML) show in its place; .png draws it (only the moving artists, over a
cached background).

The target sliders move in steps of STEP and every preset lies on that grid: the browser
snaps a slider to its grid and sends the snapped value back, so an off-grid preset would be
re-solved at another target (and, during Run All, after later cells had moved on).
"""
import html

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_hex
from matplotlib.figure import Figure

from . import plot
from .stills import named_slider, png, still_html, with_still  # noqa: F401  (ik.pictures.demo.png)
from ..core.chain import planar_chain, reach
from ..core.solve import solve

PRESETS = {
    "reachable": (2.5, 0.5),
    "near the edge": (2.99, 0.2),  # the "near edge" target of lectures 04 and 05
    "unreachable": (3.5, 1.0),
}
METHOD_NAMES = ("dls", "pinv", "jt")
STEP = 0.01         # the target sliders' step; presets lie on this grid (see on_grid)
SIZE = 400          # CSS pixels, the image's width and height on the page
HIDPI = 2           # rendered at HIDPI x SIZE pixels
CONTROLS_WIDTH = 370  # CSS pixels, the column of sliders, presets and status beside the image
FIT = "calc(100% - 4px)"  # a child's widest: the page less its 2 px margins (no scrollbar)


def summary(method, result):
    """The line the demo prints: method, status, iterations and the final error."""
    return (f"{method}: {result.status} after {result.iterations} iterations, "
            f"|e| = {result.error:.4f}")


def alt_text(arm, target, line):
    """A description of the demo's picture for screen readers and static pages."""
    return (f"Planar {arm.n_joints}-link arm inside its dashed reach circle, its start pose "
            f"in grey, reaching for the target (cross) at ({target[0]:.2f}, {target[1]:.2f}); "
            f"orange dots trace the end effector's path. {line}.")


def on_grid(value, start, step=STEP):
    """value rounded to the grid start + k * step, as a slider with that step snaps it."""
    return round(start + round((float(value) - start) / step) * step, 10)


def padded(thetas, n):
    """thetas (k, d) with its last row repeated up to n rows, so jitted maps see one shape."""
    thetas = np.asarray(thetas, dtype=float)
    return np.concatenate([thetas, np.repeat(thetas[-1:], max(n - len(thetas), 0), axis=0)])


def svg_picture(arm, theta0, theta, path, target, color, alt, size=SIZE, margin=1.3):
    """The demo's picture as SVG, drawn as plot.draw_reach/draw_arm/draw_target draw it (the
    still's PNG): the dashed reach circle, the start pose in grey, the end effector's path as
    orange dots, the arm (joints white dots, end a square) and the target (cross). Widths in
    CSS pixels are matplotlib's points x 100/72, as the PNG shows them at 100 dpi."""
    base = np.asarray(arm.base, dtype=float)[:2]
    r = margin * float(reach(arm))
    scale = 0.98 * size / (2 * r)  # the axes fill 98 % of the picture, as in the PNG

    def xy(points):
        p = np.atleast_2d(np.asarray(points, dtype=float))[:, :2]
        return np.stack([0.01 * size + (p[:, 0] - base[0] + r) * scale,
                         0.99 * size - (p[:, 1] - base[1] + r) * scale], axis=1)

    def pts(points):
        return " ".join(f"{x:.1f},{y:.1f}" for x, y in xy(points))

    pt = 100 / 72  # CSS pixels per point
    arm_xy = plot._xy(arm, theta)
    (cx, cy), (tx, ty), (ex, ey) = xy(base)[0], xy(target)[0], xy(arm_xy[-1])[0]
    dots = "".join(f"M{x:.1f} {y:.1f}h0" for x, y in xy(path))
    joints = "".join(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="{2.5 * pt:.2f}"/>'
                     for x, y in xy(arm_xy[:-1]))
    c, t, e = 4.5 * pt, 3 * pt, 3 * pt  # half the cross, half the end square
    alt = html.escape(alt, quote=True)
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {size} {size}" width="{size}" '
        f'height="{size}" role="img" aria-label="{alt}" style="display:block;width:100%;'
        f'height:auto;background:#fff"><title>{alt}</title>'
        f'<rect x="{0.01 * size:.1f}" y="{0.01 * size:.1f}" width="{0.98 * size:.1f}" '
        f'height="{0.98 * size:.1f}" fill="none" stroke="#000" stroke-width="{0.8 * pt:.2f}"/>'
        f'<circle cx="{cx:.1f}" cy="{cy:.1f}" r="{float(reach(arm)) * scale:.1f}" fill="none" '
        f'stroke="#999" stroke-width="{pt:.2f}" stroke-dasharray="{3.7 * pt:.1f} {1.6 * pt:.1f}"/>'
        f'<polyline points="{pts(plot._xy(arm, theta0))}" fill="none" stroke="#b3b3b3" '
        f'stroke-width="{2 * pt:.2f}" stroke-linecap="round" stroke-linejoin="round"/>'
        f'<g stroke="{to_hex("C1")}" stroke-opacity="0.7" fill="none" stroke-linecap="round">'
        f'<polyline points="{pts(path)}" stroke-width="{pt:.2f}"/>'
        f'<path d="{dots}" stroke-width="{2 * pt:.2f}"/></g>'
        f'<polyline points="{pts(arm_xy)}" fill="none" stroke="{color}" stroke-width="{3 * pt:.2f}" '
        f'stroke-linecap="round" stroke-linejoin="round"/>'
        f'<g fill="#fff" stroke="{color}" stroke-width="{pt:.2f}">{joints}</g>'
        f'<rect x="{ex - e:.1f}" y="{ey - e:.1f}" width="{2 * e:.1f}" height="{2 * e:.1f}" '
        f'fill="{color}"/>'
        f'<path d="M{tx - c:.1f} {ty - c:.1f}l{2 * c:.1f} {2 * c:.1f}M{tx - c:.1f} {ty + c:.1f}'
        f'l{2 * c:.1f} {-2 * c:.1f}" stroke="#000" stroke-width="{2 * pt:.2f}"/></svg>')


def _widgets():
    import ipywidgets as w

    class PresetButtons(w.HBox):
        """One button per preset; a click always applies it (also the same one twice).
        Setting .value to a preset's name does what its click does."""

        def __init__(self, presets, choose):
            self._presets, self._choose, self._value = presets, choose, None
            buttons = [w.Button(description=name, tooltip=f"target ({x:g}, {y:g})",
                                layout=w.Layout(width="auto"))
                       for name, (x, y) in presets.items()]
            for button in buttons:
                button.on_click(lambda b: setattr(self, "value", b.description))
            super().__init__(buttons, layout=w.Layout(flex_flow="row wrap"))

        @property
        def value(self):
            return self._value

        @value.setter
        def value(self, name):
            if name not in self._presets:
                raise ValueError(f"preset must be one of {list(self._presets)}, got {name!r}")
            self._value = name
            self._choose(name)

    DemoBox = with_still(w.HBox)  # the demo's layout; a static view shows its still

    return w, PresetButtons, DemoBox


class Demo:
    """Sliders for the target and lambda, a method dropdown and preset buttons, re-solving on change."""

    def __init__(self, arm=None, theta0=(0.1, 0.2, 0.3), target=PRESETS["reachable"],
                 method="dls", damping=0.5, tol=1e-3, max_iter=300, clamp=None):
        w, PresetButtons, DemoBox = _widgets()
        self.arm = planar_chain([1.0, 1.0, 1.0]) if arm is None else arm
        self.theta0 = np.asarray(theta0, dtype=float)
        self.tol, self.max_iter, self.clamp = tol, max_iter, clamp
        self.lo = -on_grid(1.3 * float(reach(self.arm)), 0.0)  # the target sliders' minimum
        style = {"description_width": "62px"}
        # width auto, not 100 %: a slider's margins on top of 100 % overflowed the column
        # (the stray horizontal scrollbar under the demo)
        slider = dict(min=self.lo, max=-self.lo, step=STEP, continuous_update=True,
                      readout_format=".2f", layout=w.Layout(width="auto"), style=style)
        self.x = w.FloatSlider(value=on_grid(target[0], self.lo), description="target x",
                               tooltip="x of the target the arm reaches for", **slider)
        self.y = w.FloatSlider(value=on_grid(target[1], self.lo), description="target y",
                               tooltip="y of the target the arm reaches for", **slider)
        self.damping = w.FloatSlider(value=damping, min=0.0, max=2.0, step=0.05,
                                     layout=w.Layout(width="auto"), style=style,
                                     description="λ (dls)", readout_format=".2f",
                                     tooltip="damping lambda of damped least squares")
        self.method = w.Dropdown(options=list(METHOD_NAMES), value=method, description="method",
                                 style=style, layout=w.Layout(width="auto"))
        self.preset = PresetButtons(PRESETS, self._preset_chosen)
        # SIZE px wide, at most the page's width (200 % zoom); height follows the width.
        # An HTML widget holding the SVG picture (its alt text is the SVG's name)
        self.image = w.HTML(layout=w.Layout(width=f"{SIZE}px", max_width=FIT, height="auto",
                                            flex="0 1 auto"))
        self.text = w.Label(layout=w.Layout(width="auto"))
        # each slider beside a number box that carries its label for screen readers
        self.labels = {"x": "target x", "y": "target y", "damping": "λ (dls)"}
        rows = [named_slider(w, getattr(self, name), text, style["description_width"])
                for name, text in self.labels.items()]
        controls = w.VBox([*rows, self.method, w.Label("presets"),
                           self.preset, self.text],
                          layout=w.Layout(width=f"{CONTROLS_WIDTH}px", max_width=FIT,
                                          flex="0 1 auto"))
        self.widget = DemoBox([self.image, controls],
                              layout=w.Layout(flex_flow="row wrap", align_items="flex-start",
                                              max_width="100%"))
        self.widget.still = lambda: (self.png, self.alt, self.summary, SIZE, SIZE,
                                     "drag the target")
        self._solved = None  # (x, y, damping, method) of the last solve
        self._build_figure(target)
        self._holding = False
        for control in (self.x, self.y, self.damping, self.method):
            control.observe(self._changed, names="value")
        self.result = None
        self.update()

    def _build_figure(self, target):
        """The static picture once (axes, reach circle, start pose) as a cached background;
        the path, arm and target are animated artists drawn over it on each update."""
        inches = SIZE / 100
        self._fig = Figure(figsize=(inches, inches), dpi=100 * HIDPI)
        self._canvas = FigureCanvasAgg(self._fig)
        self._ax = ax = self._fig.add_axes((0.01, 0.01, 0.98, 0.98))
        plot.arm_axes(ax, self.arm, margin=1.3)
        ax.set_xticks([])
        ax.set_yticks([])
        plot.draw_reach(ax, self.arm)
        plot.draw_arm(ax, self.arm, self.theta0, color="0.7", lw=2, joints=False)
        (self._path,) = ax.plot([], [], ".-", color="C1", lw=1, ms=3, alpha=0.7)
        self._arm = plot.draw_arm(ax, self.arm, self.theta0)
        self._target = plot.draw_target(ax, target)
        self._moving = [self._path, *self._arm, self._target]
        for artist in self._moving:
            artist.set_animated(True)
        self._canvas.draw()
        self._background = self._canvas.copy_from_bbox(self._fig.bbox)

    def _state(self):
        return (self.x.value, self.y.value, self.damping.value, self.method.value)

    def _changed(self, _change):
        """A control moved. A browser echoing back what the kernel set (the same value up to
        rounding) re-solves nothing."""
        if self._holding or self._solved is None:
            return
        same = all(a == b if isinstance(a, str) else abs(a - b) < 1e-9
                   for a, b in zip(self._state(), self._solved))
        if not same:
            self.update()

    def _preset_chosen(self, name):
        x, y = PRESETS[name]
        self.update(x=x, y=y)

    def update(self, x=None, y=None, damping=None, method=None):
        """Set any controls given (x and y rounded to the sliders' grid, as a slider would),
        then solve once and redraw. Returns the Result."""
        x, y = (None if v is None else on_grid(v, self.lo) for v in (x, y))
        self._holding = True
        try:
            for control, value in ((self.x, x), (self.y, y), (self.damping, damping),
                                   (self.method, method)):
                if value is not None:
                    control.value = value
        finally:
            self._holding = False
        target = np.array([self.x.value, self.y.value])
        self.result = solve(self.arm, target, self.theta0,
                            method=self.method.value, damping=self.damping.value,
                            tol=self.tol, max_iter=self.max_iter,
                            clamp=self.clamp)
        self.summary = summary(self.method.value, self.result)
        self.alt = alt_text(self.arm, target, self.summary)  # the still's <img alt>
        self.text.value = self.summary
        thetas = self.result.trace.theta
        self._end_path = plot.end_path(self.arm, padded(thetas, self.max_iter + 1))[: len(thetas)]
        self._png = None  # drawn when asked for (the still)
        self.svg = svg_picture(self.arm, self.theta0, self.result.theta, self._end_path, target,
                               to_hex(plot.color_for(self.method.value)), self.alt)
        self.image.value = self.svg
        self._solved = self._state()
        return self.result

    @property
    def png(self):
        """The current picture as a PNG drawn by matplotlib (HIDPI x SIZE pixels): the still."""
        if self._png is None:
            self._png = self._draw(np.array([self.x.value, self.y.value]))
        return self._png

    def _draw(self, target):
        """Move the animated artists, draw them over the cached background, return a PNG."""
        path = self._end_path
        self._path.set_data(path[:, 0], path[:, 1])
        plot.set_arm(self._arm, self.arm, self.result.theta)
        color = plot.color_for(self.method.value)
        for artist in self._arm:
            artist.set_color(color)
            artist.set_markeredgecolor(color)
        self._arm[1].set_markerfacecolor("white")
        self._target.set_data([target[0]], [target[1]])
        self._canvas.restore_region(self._background)
        for artist in self._moving:
            self._ax.draw_artist(artist)
        return png(self._canvas.buffer_rgba())
