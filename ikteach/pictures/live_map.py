"""A live workspace map: a lambda slider and a method dropdown re-solve a grid of targets
with ik.solve_batch and redraw the map (iterations, final error or status) as a PNG.

    live = ik.live_map.LiveMap()      # widgets; live.widget to display in a notebook
    live.update(damping=0.2)          # what a control change does; returns the SweepMap
    live.png, live.still()            # the current picture; as HTML with alt text (static viewers)

The batch is compiled once per method; a new lambda is a traced number, so a change costs
one solve_batch over the grid and one small PNG render.
"""
import io

import numpy as np

from ..core.chain import planar_chain
from ..core.workspace import sweep, target_grid
from .workspace_maps import status_image

QUANTITIES = ("iterations", "error", "status")
MAP_METHODS = ("dls", "jt")  # pinv, sdls: an SVD per step, seconds per map


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
    """Solve every grid target (ik.workspace.sweep) and return (SweepMap, image)."""
    result = sweep(arm, grid, theta0, method=method, damping=damping, **kwargs)
    return result, map_image(result, quantity)


def _label(quantity, max_iter):
    return {"iterations": f"iterations, dark 0 to yellow {max_iter}",
            "error": "log10 of the final |e|, dark small to yellow large",
            "status": "green converged, orange stalled, red max_iter, black diverged"}[quantity]


class LiveMap:
    """lambda slider, method and quantity dropdowns; each change recomputes the map."""

    def __init__(self, arm=None, grid_n=128, theta0=(0.3, 0.3, 0.3), method="dls",
                 damping=0.5, quantity="iterations", tol=1e-3, max_iter=100):
        import ipywidgets as w
        from matplotlib.figure import Figure

        self.arm = planar_chain([1.0, 1.0, 1.0]) if arm is None else arm
        self.grid = target_grid(self.arm, n=grid_n)
        self.theta0 = np.asarray(theta0, dtype=float)
        self.tol, self.max_iter = tol, max_iter
        self.damping = w.FloatSlider(value=damping, min=0.0, max=2.0, step=0.05,
                                     description="λ (dls)", readout_format=".2f")
        self.method = w.Dropdown(options=list(MAP_METHODS), value=method, description="method")
        self.quantity = w.Dropdown(options=list(QUANTITIES), value=quantity, description="show")
        self.image = w.Image(format="png")
        self.text = w.Label()
        self.widget = w.VBox([w.HBox([self.damping, self.method, self.quantity]), self.text,
                              self.image])
        self._fig = Figure(figsize=(4.2, 4.2), dpi=80)
        self._ax = self._fig.add_axes((0.13, 0.1, 0.83, 0.79))
        self._im = self._ax.imshow(np.zeros(self.grid.shape), origin="lower",
                                   extent=self.grid.extent, interpolation="nearest")
        self._ax.set_aspect("equal")
        self._ax.set_xlabel("target x", fontsize=8)
        self._ax.set_ylabel("target y", fontsize=8)
        self._ax.grid(False)
        self._title = self._ax.set_title("", fontsize=8)
        self._holding = False
        for control in (self.damping, self.method, self.quantity):
            control.observe(self._changed, names="value")
        self.update()

    def _changed(self, _change):
        if not self._holding:
            self.update()

    def update(self, damping=None, method=None, quantity=None):
        """Set any controls given, then recompute and redraw the map. Returns the SweepMap."""
        self._holding = True
        try:
            for control, value in ((self.damping, damping), (self.method, method),
                                   (self.quantity, quantity)):
                if value is not None:
                    control.value = value
        finally:
            self._holding = False
        self.result, picture = compute_map(
            self.arm, self.grid, self.theta0, method=self.method.value,
            damping=self.damping.value, quantity=self.quantity.value, tol=self.tol,
            max_iter=self.max_iter)
        counts = ", ".join(f"{k} {v}" for k, v in self.result.counts().items())
        self.summary = f"{self.method.value}, λ = {self.damping.value:.2f}: {counts}"
        self.text.value = self.summary
        self.png = self._draw(picture)
        self.image.value = self.png
        return self.result

    def _draw(self, picture):
        self._im.set_data(picture)
        if self.quantity.value == "iterations":
            self._im.set_clim(0, self.max_iter)  # the same colours for every lambda
        elif picture.ndim == 2:
            self._im.set_clim(float(picture.min()), float(picture.max()))
        self._title.set_text(f"{self.method.value}, λ = {self.damping.value:.2f}\n"
                             f"{_label(self.quantity.value, self.max_iter)}")
        buf = io.BytesIO()
        self._fig.savefig(buf, format="png")
        return buf.getvalue()

    def still(self):
        """The current map as static HTML (an <img> with alt text), for viewers without a kernel."""
        from IPython.display import HTML

        from .alt_text import figure_alt, img_html

        return HTML(img_html(self.png, f"Workspace map, {self.summary}. {figure_alt(self._fig)}"))
