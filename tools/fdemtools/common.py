"""Shared input/output for the fdem post-processing tools.

Everything here turns files into numpy arrays in SI units (m, N, J, s, Pa) or writes results; the
analysis modules never see units or file formats. Bad input raises ToolError with a one-line message
that the command line prints without a traceback.
"""
from __future__ import annotations

import csv
import json
import math
import os
from dataclasses import dataclass, field

import numpy as np


class ToolError(Exception):
    """Bad input or a state the tools cannot work with; the message is shown to the user as one line."""


# Unit -> factor to SI. Lengths to m, forces to N, stresses to Pa, energies to J.
LENGTH_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "in": 0.0254, "ft": 0.3048}
FORCE_UNITS = {"N": 1.0, "kN": 1e3, "MN": 1e6, "lbf": 4.4482216152605, "kip": 4448.2216152605}
STRESS_UNITS = {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "psi": 6894.757293168361}
ENERGY_UNITS = {"J": 1.0, "kJ": 1e3, "N*m": 1.0, "kN*mm": 1.0, "kN*m": 1e3}


# One colour per fracture mode in every figure (crack maps, damage plots).
MODE_COLOURS = {"I": "#d62728", "II": "#1f77b4", "mixed": "#9467bd"}
MODE_NAMES = {"I": "tension (I)", "II": "shear (II)", "mixed": "mixed (I-II)"}


def unit_factor(unit: str, table: dict, what: str) -> float:
    if unit not in table:
        raise ToolError(f"unknown {what} unit '{unit}' (known: {', '.join(table)})")
    return table[unit]


@dataclass
class Table:
    """A CSV file as columns. Numeric columns are float arrays; others stay arrays of str."""
    path: str
    names: list
    columns: dict = field(default_factory=dict)

    def __len__(self):
        return len(next(iter(self.columns.values()))) if self.columns else 0

    def has(self, name: str) -> bool:
        return name in self.columns

    def col(self, name: str) -> np.ndarray:
        if name not in self.columns:
            raise ToolError(f"{self.path}: no column '{name}' (columns: {', '.join(self.names)})")
        return self.columns[name]

    def numeric(self, name: str) -> np.ndarray:
        c = self.col(name)
        if c.dtype.kind not in "fiu":
            raise ToolError(f"{self.path}: column '{name}' is not numeric")
        return c


def _to_float(s: str):
    try:
        return float(s)
    except ValueError:
        return None


def read_table(path: str) -> Table:
    """Reads a delimited text table (comma, semicolon, tab or blanks) with one header row.

    Lines starting with '#' are comments. If the first row is all numbers there is no header and the
    columns are called col1, col2, ...
    """
    if not os.path.isfile(path):
        raise ToolError(f"{path}: no such file")
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            lines = [ln for ln in f.read().splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    except UnicodeDecodeError:
        raise ToolError(f"{path}: not a text file") from None
    if not lines:
        raise ToolError(f"{path}: empty file")
    head = lines[0]
    if "," in head:
        rows = list(csv.reader(lines))
    elif ";" in head:
        rows = list(csv.reader(lines, delimiter=";"))
    elif "\t" in head:
        rows = list(csv.reader(lines, delimiter="\t"))
    else:
        rows = [ln.split() for ln in lines]
    rows = [[c.strip() for c in r] for r in rows]
    if all(_to_float(c) is not None for c in rows[0]):
        names = [f"col{i + 1}" for i in range(len(rows[0]))]
        body = rows
    else:
        names, body = rows[0], rows[1:]
    if len(set(names)) != len(names):
        raise ToolError(f"{path}: repeated column names in the header")
    ncol = len(names)
    for i, r in enumerate(body):
        if len(r) != ncol:
            raise ToolError(f"{path}: data row {i + 1} has {len(r)} fields, the header has {ncol}")
    t = Table(path, list(names))
    for j, name in enumerate(names):
        vals = [r[j] for r in body]
        nums = [_to_float(v) for v in vals]
        if all(v is not None for v in nums):
            t.columns[name] = np.array(nums, dtype=float)
        else:
            t.columns[name] = np.array(vals, dtype=object)
    return t


# ----------------------------------------------------------------------------------------------
# Run folders


@dataclass
class Run:
    path: str
    summary: dict
    history: Table | None

    @property
    def name(self) -> str:
        return self.summary.get("case") or os.path.basename(os.path.normpath(self.path))

    @property
    def status(self) -> str:
        return self.summary.get("status", "unknown")

    def unit(self, column: str) -> str:
        return (self.summary.get("columns") or {}).get(column, "")

    def curve_columns(self) -> tuple:
        c = self.summary.get("curve") or {}
        x, y = c.get("x"), c.get("y")
        if not x or not y:
            raise ToolError(f"{self.path}: summary.json names no load-displacement curve ('curve': {{'x','y'}}); "
                            "give --x and --y")
        return x, y


def is_run_folder(path: str) -> bool:
    return os.path.isdir(path) and (os.path.isfile(os.path.join(path, "summary.json"))
                                    or os.path.isfile(os.path.join(path, "history.csv")))


def read_summary(path: str) -> dict | None:
    """summary.json of a run folder, or None if there is none (or it is unreadable: a run being written)."""
    p = os.path.join(path, "summary.json")
    if not os.path.isfile(p):
        return None
    try:
        with open(p, encoding="utf-8") as f:
            s = json.load(f)
    except (OSError, ValueError):
        return None
    return s if isinstance(s, dict) else None


def load_run(path: str, allow_unfinished: bool = False, need_history: bool = True) -> Run:
    if not os.path.isdir(path):
        raise ToolError(f"{path}: no such run folder")
    s = read_summary(path)
    if s is None:
        if not allow_unfinished:
            raise ToolError(f"{path}: no readable summary.json (unfinished run?); --partial reads it anyway")
        s = {"status": "unknown"}
    if s.get("status") != "completed" and not allow_unfinished:
        msg = s.get("message") or ""
        raise ToolError(f"{path}: run status is '{s.get('status', 'unknown')}', not 'completed'"
                        + (f" ({msg})" if msg else "") + "; --partial reads it anyway")
    hist = None
    hp = os.path.join(path, "history.csv")
    if os.path.isfile(hp):
        hist = read_table(hp)
    elif need_history:
        raise ToolError(f"{path}: no history.csv")
    return Run(path, s, hist)


# ----------------------------------------------------------------------------------------------
# Curves


@dataclass
class Curve:
    x: np.ndarray       # m
    y: np.ndarray       # N
    label: str
    source: str
    x_name: str
    y_name: str
    t: np.ndarray | None = None  # s, when known


def _si_from_run_unit(unit: str, kind: str, path: str, col: str) -> float:
    table = LENGTH_UNITS if kind == "length" else FORCE_UNITS
    if not unit:
        return 1.0  # the run contract is SI
    if unit not in table:
        raise ToolError(f"{path}: column '{col}' has unit '{unit}', expected a {kind}")
    return table[unit]


def load_curve(source: str, x: str | None = None, y: str | None = None, x_unit: str = "m", y_unit: str = "N",
               stage: int | None = None, partial: bool = False, label: str | None = None) -> Curve:
    """A load-displacement curve in SI from a run folder (summary.json names the columns) or a CSV file
    (columns by name, else the first two). `stage` keeps only the rows of that stage (run folders)."""
    if is_run_folder(source):
        run = load_run(source, allow_unfinished=partial)
        if x is None or y is None:
            cx, cy = run.curve_columns()
            x, y = x or cx, y or cy
        h = run.history
        xs = h.numeric(x) * _si_from_run_unit(run.unit(x), "length", source, x)
        ys = h.numeric(y) * _si_from_run_unit(run.unit(y), "force", source, y)
        t = h.numeric("time") if h.has("time") else None
        if stage is not None:
            keep = h.numeric("stage") == stage
            if not keep.any():
                raise ToolError(f"{source}: no rows of stage {stage}")
            xs, ys = xs[keep], ys[keep]
            t = t[keep] if t is not None else None
        return Curve(xs, ys, label or run.name, source, x, y, t)
    if os.path.isdir(source):
        raise ToolError(f"{source}: a folder but not a run folder (no summary.json or history.csv)")
    tab = read_table(source)
    if x is None or y is None:
        if len(tab.names) < 2:
            raise ToolError(f"{source}: needs at least two columns")
        x, y = x or tab.names[0], y or tab.names[1]
    fx = unit_factor(x_unit, LENGTH_UNITS, "length")
    fy = unit_factor(y_unit, FORCE_UNITS, "force")
    xs, ys = tab.numeric(x) * fx, tab.numeric(y) * fy
    t = tab.numeric("time") if tab.has("time") and tab.col("time").dtype.kind == "f" else None
    if stage is not None and tab.has("stage"):
        keep = tab.numeric("stage") == stage
        xs, ys = xs[keep], ys[keep]
        t = t[keep] if t is not None else None
    stem = os.path.splitext(os.path.basename(source))[0]
    return Curve(xs, ys, label or stem, source, x, y, t)


def check_finite(c: Curve) -> None:
    if len(c.x) == 0:
        raise ToolError(f"{c.source}: the curve has no points")
    bad = ~(np.isfinite(c.x) & np.isfinite(c.y))
    if bad.any():
        i = int(np.argmax(bad))
        raise ToolError(f"{c.source}: non-finite value in row {i + 1} of columns '{c.x_name}', '{c.y_name}'")


# ----------------------------------------------------------------------------------------------
# Output


def _jsonable(v):
    if isinstance(v, dict):
        return {str(k): _jsonable(w) for k, w in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(w) for w in v]
    if isinstance(v, np.ndarray):
        return [_jsonable(w) for w in v.tolist()]
    if isinstance(v, (np.floating, float)):
        f = float(v)
        return f if math.isfinite(f) else None
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, np.bool_):
        return bool(v)
    return v


def write_json(path: str, obj) -> str:
    d = os.path.dirname(os.path.abspath(path))
    os.makedirs(d, exist_ok=True)
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(_jsonable(obj), f, indent=2)
        f.write("\n")
    os.replace(tmp, path)
    return path


def write_csv(path: str, header: list, rows: list) -> str:
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(header)
        for r in rows:
            w.writerow(["" if (isinstance(v, float) and not math.isfinite(v)) else v for v in r])
    return path


def output_prefix(source: str, suffix: str, out: str | None) -> str:
    """Where a single-figure command writes: --out PREFIX, else <run>/post/<suffix> for a run folder, else
    <csv folder>/<csv stem>_<suffix>."""
    if out:
        return out
    if is_run_folder(source):
        return os.path.join(source, "post", suffix)
    stem = os.path.splitext(source)[0]
    return f"{stem}_{suffix}"
