"""The lab's interactive demo: drag the target, watch the arm follow.

    demo = ik.demo.Demo()          # widgets: target x, y, lambda, method, preset
    demo.widget                    # display it in a notebook
    demo.update(x=3.5, y=1.0)      # what a slider change does; returns the Result

Every change re-solves from the same start theta0 with ik.solve, redraws the arm, its
start pose and the end effector's path into an image widget, and prints one line:
method, status and iterations. The solve is compiled once per method (the target and
lambda are traced numbers), so a change costs a few milliseconds of solving plus one
small PNG render. Without a browser, call update() and read .result, .summary, .png.
"""
import io

import numpy as np
from matplotlib.figure import Figure

from . import plot
from .chain import planar_chain, reach
from .solve import solve

PRESETS = {
    "reachable": (2.5, 0.5),
    "near the edge": (2.99, 0.2),  # the "near edge" target of lectures 04 and 05
    "unreachable": (3.5, 1.0),
}
METHOD_NAMES = ("dls", "pinv", "jt")


def summary(method, result):
    """The line the demo prints: method, status, iterations and the final error."""
    return (f"{method}: {result.status} after {result.iterations} iterations, "
            f"|e| = {result.error:.4f}")


class Demo:
    """Sliders for the target and lambda, a method dropdown and presets, re-solving on change."""

    def __init__(self, arm=None, theta0=(0.1, 0.2, 0.3), target=PRESETS["reachable"],
                 method="dls", damping=0.5, tol=1e-3, max_iter=300, clamp=None):
        import ipywidgets as w

        self.arm = planar_chain([1.0, 1.0, 1.0]) if arm is None else arm
        self.theta0 = np.asarray(theta0, dtype=float)
        self.tol, self.max_iter, self.clamp = tol, max_iter, clamp
        r = 1.3 * float(reach(self.arm))
        slider = dict(min=-r, max=r, step=0.05, continuous_update=True, readout_format=".2f")
        self.x = w.FloatSlider(value=float(target[0]), description="target x", **slider)
        self.y = w.FloatSlider(value=float(target[1]), description="target y", **slider)
        self.damping = w.FloatSlider(value=damping, min=0.0, max=2.0, step=0.05,
                                     description="λ (dls)", readout_format=".2f")
        self.method = w.Dropdown(options=list(METHOD_NAMES), value=method, description="method")
        self.preset = w.ToggleButtons(options=list(PRESETS), value=None, description="preset")
        self.image = w.Image(format="png")
        self.text = w.Label()
        self.widget = w.VBox([w.HBox([w.VBox([self.x, self.y]),
                                      w.VBox([self.damping, self.method])]),
                              self.preset, self.text, self.image])
        self._fig = Figure(figsize=(3.8, 3.8), dpi=80)
        self._ax = ax = self._fig.add_axes((0.02, 0.02, 0.96, 0.9))
        plot.arm_axes(ax, self.arm, margin=1.3)
        ax.set_xticks([])
        ax.set_yticks([])
        plot.draw_reach(ax, self.arm)
        plot.draw_arm(ax, self.arm, self.theta0, color="0.7", lw=2, joints=False)
        (self._path,) = ax.plot([], [], ".-", color="C1", lw=1, ms=3, alpha=0.7)
        self._arm = plot.draw_arm(ax, self.arm, self.theta0)
        self._target = plot.draw_target(ax, target)
        self._title = ax.set_title("", fontsize=8)
        self._holding = False
        for control in (self.x, self.y, self.damping, self.method):
            control.observe(self._changed, names="value")
        self.preset.observe(self._preset_chosen, names="value")
        self.result = None
        self.update()

    def _changed(self, _change):
        if not self._holding:
            self.update()

    def _preset_chosen(self, change):
        if change["new"] is not None:
            x, y = PRESETS[change["new"]]
            self.update(x=x, y=y)

    def update(self, x=None, y=None, damping=None, method=None):
        """Set any controls given, then solve once and redraw. Returns the Result."""
        self._holding = True
        try:
            for control, value in ((self.x, x), (self.y, y), (self.damping, damping),
                                   (self.method, method)):
                if value is not None:
                    control.value = value
        finally:
            self._holding = False
        target = np.array([self.x.value, self.y.value])
        self.result = solve(self.arm, target, self.theta0, method=self.method.value,
                            damping=self.damping.value, tol=self.tol, max_iter=self.max_iter,
                            clamp=self.clamp)
        self.summary = summary(self.method.value, self.result)
        self.text.value = self.summary
        self.png = self._draw(target)
        self.image.value = self.png
        return self.result

    def _draw(self, target):
        """Move the persistent artists (cheaper than redrawing the axes) and render a PNG."""
        res = self.result
        path = plot.end_path(self.arm, res.trace.theta)
        self._path.set_data(path[:, 0], path[:, 1])
        plot.set_arm(self._arm, self.arm, res.theta)
        color = plot.color_for(self.method.value)
        for artist in self._arm:
            artist.set_color(color)
        self._arm[1].set_markerfacecolor("white")
        self._target.set_data([target[0]], [target[1]])
        self._title.set_text(self.summary)
        buf = io.BytesIO()
        self._fig.savefig(buf, format="png")
        return buf.getvalue()
