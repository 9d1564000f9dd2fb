"""Alt text for matplotlib figures in notebooks: an <img alt="..."> instead of a bare PNG.

JupyterLab (4.6) and nbconvert (7.17) ignore an "alt" key in an image/png output's metadata,
but both keep the alt attribute of an <img> in a text/html output. So, once registered (by
ik.notebook.setup()), a figure displays as text/html holding its PNG as a data URI and an alt
text made of its titles and axis labels; the text/plain fallback carries the same words.
"""
import base64
import html
import io
import re

MAX_ALT = 300  # characters: a screen reader reads all of it


def plain(text):
    """Mathtext and line breaks made readable: '$\\alpha^*$\\nstep' -> 'alpha^* step'."""
    text = re.sub(r"\\(?:mathrm|mathbf|mathit|text|operatorname)\{([^}]*)\}", r"\1", text)
    text = re.sub(r"\\top\b", "T", text)
    text = re.sub(r"\\([A-Za-z]+)", r"\1", text)
    text = text.replace("\\|", "‖")
    return " ".join(text.replace("$", "").replace("{", "").replace("}", "").split())


def _axes_text(ax):
    """'title (y label against x label; legend: a, b)' for one axes, or '' when it says nothing."""
    title = " ".join(t for t in (ax.get_title("left"), ax.get_title(), ax.get_title("right")) if t)
    x, y = ax.get_xlabel(), ax.get_ylabel()
    details = [f"{y} against {x}" if x and y else (x or y)]
    legend = ax.get_legend()
    if legend is not None:
        details.append("legend: " + ", ".join(t.get_text() for t in legend.get_texts()))
    details = "; ".join(d for d in details if d)
    text = f"{title} ({details})" if title and details else (title or details)
    return plain(text)


def figure_alt(fig):
    """One line describing a figure from its suptitle, axes titles and axis labels."""
    suptitle = plain(fig.get_suptitle())
    panels = [t for t in (_axes_text(ax) for ax in fig.axes) if t]
    n = len(fig.axes)
    lead = suptitle or ("Figure" if n <= 1 else f"Figure with {n} panels")
    text = f"{lead}: " + "; ".join(panels) if panels else lead
    return text if len(text) <= MAX_ALT else text[: MAX_ALT - 1] + "…"


def img_html(png, alt):
    """An <img> tag holding PNG bytes as a data URI, with alt text (escaped)."""
    data = base64.b64encode(png).decode("ascii")
    return f'<img alt="{html.escape(alt, quote=True)}" src="data:image/png;base64,{data}"/>'


def figure_png(fig):
    """The figure as PNG bytes, as the inline backend would draw it (tight bounding box)."""
    buf = io.BytesIO()
    fig.canvas.print_figure(buf, format="png", bbox_inches="tight")
    return buf.getvalue()


def figure_html(fig):
    """text/html for a figure: its PNG with alt text; None for an empty figure."""
    if not fig.axes and not fig.images and not fig.patches:
        return None
    return img_html(figure_png(fig), figure_alt(fig))


def register(shell):
    """Make `shell` display matplotlib figures as <img alt=...> (text/html) instead of a PNG.

    The inline backend registers its PNG formatter when it loads, so it is loaded first;
    calling this again is harmless. Returns True when registered."""
    import matplotlib as mpl
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    plt.switch_backend(mpl.get_backend())  # load the inline backend now, not at the first plot
    formatters = shell.display_formatter.formatters
    formatters["image/png"].pop(Figure, None)
    formatters["image/svg+xml"].pop(Figure, None)
    formatters["text/html"].for_type(Figure, figure_html)
    formatters["text/plain"].for_type(Figure, lambda fig, p, cycle: p.text(figure_alt(fig)))
    return True

