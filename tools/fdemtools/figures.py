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


def add_drift_axis(ax, unit_m: float, height_m: float):
    """A second displacement axis on top of ax: the drift ratio d / H in %, for displacements plotted in a unit of
    unit_m metres and a height H (m) over which the drift is taken (a wall's or a storey's)."""
    if not height_m > 0:
        raise ValueError("drift height must be > 0")
    k = 100.0 * unit_m / height_m
    sec = ax.secondary_xaxis("top", functions=(lambda x: x * k, lambda r: r / k))
    sec.set_xlabel(f"drift ratio (%) over H = {height_m:g} m")
    return sec


def run_stamp(summaries, limit: int | None = 4) -> str:
    """What made a figure, in one line: the fdem release and build (summary.json "fdem_version", "build": the
    source tree's commit when fdem was built) and each run's case with its hash ("case_hash": the case as resolved,
    its TOML after --set). A figure committed next to its case can then be checked against both. Runs written
    before these keys existed say "build unknown" / "no hash"."""
    builds, cases = [], []
    for s in summaries:
        if not s:
            continue
        b = f"fdem {s.get('fdem_version', '?')} build {s.get('build', 'unknown')}"
        if b not in builds:
            builds.append(b)
        c = f"{s.get('case', '?')} [{s.get('case_hash', 'no hash')}]"
        if c not in cases:
            cases.append(c)
    if not builds:
        return ""
    if limit is not None and len(cases) > limit:  # (a figure's corner; a report lists them all)
        cases = cases[:limit] + [f"and {len(cases) - limit} more"]
    return "; ".join(builds) + " | " + ", ".join(cases)


def _draw_stamp(fig, stamp: str):
    """The stamp small in the figure's bottom-left corner (save and savefig_stamped)."""
    fig.text(0.003, 0.003, stamp, fontsize=5.5, color="0.45", ha="left", va="bottom")


def stamp_of_runs(run_dirs) -> str:
    """run_stamp of the summary.json files of these run folders (those without one are left out)."""
    import json
    summaries = []
    for d in run_dirs:
        try:
            with open(os.path.join(d, "summary.json")) as f:
                summaries.append(json.load(f))
        except (OSError, ValueError):
            continue
    return run_stamp(summaries)


def savefig_stamped(fig, path: str, run_dirs, **kwargs) -> str:
    """fig.savefig(path, **kwargs) for a script's own figure, with the stamp of the runs it shows (stamp_of_runs) in
    the bottom-left corner and in the file's metadata, as save() writes it. Returns the stamp ("" without runs)."""
    stamp = stamp_of_runs(run_dirs)
    if stamp:
        _draw_stamp(fig, stamp)
        if path.lower().endswith((".png", ".svg")):
            kwargs.setdefault("metadata", {"Source": stamp})
    fig.savefig(path, **kwargs)
    return stamp


def save(fig, prefix: str, stamp: str = "") -> list:
    """Writes prefix.png and prefix.svg, closes the figure and returns both paths. stamp (run_stamp): written small
    in the figure's bottom-left corner and into both files' metadata ("Source")."""
    d = os.path.dirname(os.path.abspath(prefix))
    os.makedirs(d, exist_ok=True)
    paths = []
    with plt.rc_context(STYLE):
        if stamp:
            _draw_stamp(fig, stamp)
        fig.tight_layout()
        for ext in ("png", "svg"):
            p = f"{prefix}.{ext}"
            meta = {"Source": stamp} if stamp else None
            fig.savefig(p, bbox_inches="tight", metadata=meta)  # keeps legends placed outside the axes
            paths.append(p)
    plt.close(fig)
    return paths
