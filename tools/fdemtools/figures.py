"""Matplotlib set-up shared by every figure: non-interactive backend, one house style, PNG + SVG output."""
from __future__ import annotations

import os

import matplotlib

if not os.environ.get("MPLBACKEND"):
    matplotlib.use("Agg")  # the tools run on headless machines; never open a window
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {
    "figure.figsize": (6.4, 4.6),
    "figure.dpi": 100,
    "savefig.dpi": 150,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "legend.frameon": False,
    "font.size": 10,
    "svg.fonttype": "none",  # text stays text in the SVG, editable in papers
}



def new_figure(*args, **kwargs):
    with plt.rc_context(STYLE):
        return plt.subplots(*args, **kwargs)


def save(fig, prefix: str) -> list:
    """Writes prefix.png and prefix.svg, closes the figure and returns both paths."""
    d = os.path.dirname(os.path.abspath(prefix))
    os.makedirs(d, exist_ok=True)
    paths = []
    with plt.rc_context(STYLE):
        fig.tight_layout()
        for ext in ("png", "svg"):
            p = f"{prefix}.{ext}"
            fig.savefig(p, bbox_inches="tight")  # keeps legends placed outside the axes
            paths.append(p)
    plt.close(fig)
    return paths
