"""Shared input/output for the fdem post-processing tools.

Everything here turns files into numpy arrays in SI units (m, N, J, s, Pa) or writes results; the
analysis modules never see units or file formats. Bad input raises ToolError with a one-line message
that the command line prints without a traceback.
"""
from __future__ import annotations

import csv
import hashlib
import json
import math
import os
import shutil
import subprocess
from dataclasses import dataclass, field

import numpy as np


from .errors import ToolError  # noqa: F401  (defined apart so that curves.py can raise it too)
from .curves import loading_work_sign, resolve_sign  # noqa: F401  (the load sign rule; names kept here too)


REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def fdem_binary(given: str | None, must_exist: bool = True) -> str:
    """The fdem executable (absolute path): --fdem, else $FDEM_BIN, else build/fdem/fdem of this repository.
    must_exist=False (dry runs): the path as it would be used."""
    path = given or os.environ.get("FDEM_BIN") or os.path.join(REPO, "build", "fdem", "fdem")
    resolved = shutil.which(path) if os.sep not in path else path
    if not resolved or not os.path.isfile(resolved) or not os.access(resolved, os.X_OK):
        if not must_exist:
            return os.path.abspath(path) if os.sep in path else path
        raise ToolError(f"fdem executable '{path}' not found (build it, set FDEM_BIN or give --fdem)")
    return os.path.abspath(resolved)


# ----------------------------------------------------------------------------------------------
# Case files: the tools never read a case file themselves. The engine resolves it (its TOML after --set and --unset,
# every default applied) and prints it as JSON (`fdem check CASE --json`, fdem --help); resolved_case asks it.

_RESOLVED: dict = {}  # (fdem, its stat, case path, digest of the case's bytes, sets, unsets) -> the parsed answer


def _override_pair(s) -> tuple:
    if isinstance(s, str):
        if "=" not in s:
            raise ToolError(f"--set '{s}': expected KEY=VALUE")
        k, v = s.split("=", 1)
        return k.strip(), v.strip()
    k, v = s
    return str(k), str(v)


def resolved_case(path: str, sets=(), unsets=(), fdem: str | None = None) -> dict:
    """The case as the engine will run it: the object `fdem check PATH --set K=V ... --unset K ... --json` prints
    (case_file, case_hash, overrides, case: the TOML tree after the overrides, resolved: the values the run uses with
    the defaults applied, mesh, notes, warnings). sets: (KEY, VALUE) pairs or "KEY=VALUE" strings, applied in order,
    then unsets. fdem: the executable (fdem_binary's rule). Cached per arguments while neither the case file nor the
    executable changes. Bad input raises ToolError with the engine's message."""
    exe = fdem_binary(fdem)
    sets = tuple(_override_pair(s) for s in sets)
    unsets = tuple(str(k) for k in unsets)
    if not os.path.isfile(path):
        raise ToolError(f"{path}: no such case file")  # the engine's words
    try:
        with open(path, "rb") as f:
            digest = hashlib.sha256(f.read()).hexdigest()
        st = os.stat(exe)
    except OSError as e:
        raise ToolError(f"{path}: cannot read the case file ({e.strerror})") from None
    key = (exe, st.st_size, st.st_mtime_ns, os.path.abspath(path), digest, sets, unsets)
    if key not in _RESOLVED:
        cmd = [exe, "check", path, "--json", "--threads", "1"]
        for k, v in sets:
            cmd += ["--set", f"{k}={v}"]
        for k in unsets:
            cmd += ["--unset", k]
        try:
            r = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=600)
        except (OSError, subprocess.SubprocessError) as e:
            raise ToolError(f"cannot run {exe} check: {e}") from None
        if r.returncode != 0:
            lines = [ln.strip() for ln in r.stderr.splitlines() if ln.strip() and not ln.startswith("warning:")]
            msg = "; ".join(ln[len("error: "):] if ln.startswith("error: ") else ln for ln in lines)
            raise ToolError(msg or f"fdem check {path} failed (exit {r.returncode})")
        try:
            j = json.loads(r.stdout)
        except ValueError:
            j = None
        if not isinstance(j, dict) or not isinstance(j.get("resolved"), dict):
            raise ToolError(f"{exe} check {path} --json printed no resolved case (an fdem without --json?)")
        _RESOLVED[key] = j
    return _RESOLVED[key]


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
    sign: float | None = None    # load sign the source states (a case's output.curve.sign), else None
    sign_source: str = ""        # where that sign comes from
    x_unit: str = "m"            # unit the displacement column was read in (SI after reading)
    y_unit: str = "N"            # unit the load column was read in
    unit_rules: tuple = ("SI run folder", "SI run folder")  # how each unit was found (given, column name, default)
    warnings: list = field(default_factory=list)  # unit warnings printed while reading
    columns_rule: str = "named by the run"     # how the columns were chosen (CSV: given, by name, the only two)


# ----------------------------------------------------------------------------------------------
# The load sign rule: curves.loading_work_sign and curves.resolve_sign (tools/README.md "Curves, signs and units")

SIGN_CHOICES = ("auto", "1", "-1")


def _case_curve_sign(run: "Run") -> tuple:
    """The load sign a run's case states: summary.json curve.sign, else the [output] curve.sign of the case file
    summary.json names (case_file, found from the working folder or beside the run folder), as the engine resolves
    it with the run's overrides (summary.json settings.overrides; resolved_case). (None, '') if none, or when the
    case cannot be resolved now (no fdem, a case edited since)."""
    c = run.summary.get("curve") or {}
    if c.get("sign") is not None:
        return _sign_value(c["sign"], f"{run.path}/summary.json curve.sign"), "case (summary.json curve.sign)"
    cf = run.summary.get("case_file")
    if not cf:
        return None, ""
    ov = (run.summary.get("settings") or {}).get("overrides") or {}
    ov = ov if isinstance(ov, dict) else {}
    sets = [(k, v) for k, v in ov.items() if v != "(unset)"]
    unsets = [k for k, v in ov.items() if v == "(unset)"]
    for p in (cf, os.path.join(run.path, cf), os.path.join(os.path.dirname(os.path.normpath(run.path)), cf)):
        if os.path.isfile(p):
            try:
                curve = resolved_case(p, sets, unsets)["resolved"].get("curve") or {}
            except ToolError:
                return None, ""
            if isinstance(curve, dict) and curve.get("sign") is not None:
                return _sign_value(curve["sign"], f"{p}: output.curve.sign"), f"case ({p} output.curve.sign)"
            return None, ""
    return None, ""


def _sign_value(v, where: str) -> float:
    try:
        f = float(v)
    except (TypeError, ValueError):
        f = 0.0
    if f not in (1.0, -1.0):
        raise ToolError(f"{where}: expected 1 or -1, got {v!r}")
    return f


# ----------------------------------------------------------------------------------------------
# Units of CSV columns (tools/README.md "Curves, signs and units")

DEFAULT_X_UNIT, DEFAULT_Y_UNIT = "m", "N"  # every command's default for a CSV column without a unit in its name


def unit_from_name(name: str, table: dict) -> str | None:
    """The unit a column name carries: 'd_mm', 'F_kN', 'disp_m', 'load_N', 'd [mm]', 'F (kN)', 'u.mm'. None if
    the name ends in no known unit of `table` (matched exactly, so 'm' is metres and 'M' nothing)."""
    import re
    n = name.strip()
    m = re.search(r"[\[(]\s*([A-Za-z*]+)\s*[\])]\s*$", n)
    if m and m.group(1) in table:
        return m.group(1)
    m = re.search(r"[_.\s-]([A-Za-z*]+)$", n)
    if m and m.group(1) in table:
        return m.group(1)
    return None


def column_unit(name: str, given: str | None, table: dict, default: str, what: str, source: str) -> tuple:
    """(unit, rule) of a CSV column: the unit given on the command line, else the unit its name carries, else
    the default. A given unit that contradicts the name is used, with a warning."""
    named = unit_from_name(name, table)
    if given:
        unit_factor(given, table, what)
        if named and named != given:
            warn(f"{source}: column '{name}' is named in {named} but --{'x' if what == 'length' else 'y'}-unit "
                 f"says {given}; reading it in {given}")
        return given, "given"
    if named:
        return named, "column name"
    return default, "default"


def name_without_unit(name: str) -> str:
    """A column name without the unit it ends in ('d_mm' -> 'd', 'F (kN)' -> 'F', 'H' -> 'H'), any known unit."""
    import re
    n = name.strip()
    for table in (LENGTH_UNITS, FORCE_UNITS, STRESS_UNITS, ENERGY_UNITS):
        if unit_from_name(n, table):
            m = re.search(r"\s*[\[(]\s*[A-Za-z*]+\s*[\])]\s*$", n) or re.search(r"[_.\s-][A-Za-z*]+$", n)
            return n[:m.start()] if m else n
    return n


def renamed(name: str, unit: str) -> str:
    """The name a column would need to say `unit`: its name without its unit, then _unit ('F_N' -> 'F_kN')."""
    return f"{name_without_unit(name)}_{unit}"


def _is_named(name: str, letters: tuple, words: tuple) -> bool:
    import re
    stem = name_without_unit(name).strip().lower()
    if any(re.fullmatch(rf"{c}([_\s.\-(\[].*)?", stem) for c in letters):
        return True
    return any(stem.startswith(w) for w in words)


def is_displacement_name(name: str) -> bool:
    """d, u, d_*, u_*, disp*, displacement*, delta* (after the unit is taken off the name)."""
    return _is_named(name, ("d", "u"), ("disp", "delta"))


def is_load_name(name: str) -> bool:
    """F, H, P, F_*, H_*, P_*, load*, force* (after the unit is taken off the name)."""
    return _is_named(name, ("f", "h", "p"), ("load", "force"))


def pick_columns(names: list, x: str | None, y: str | None, source: str) -> tuple:
    """(x, y, rule) of a CSV curve: the columns given; else the one column whose name says displacement (d_*, u_*,
    disp*) and the one whose name says load (F_*, H*, P_*, load*); else, in a file of exactly two columns, those two
    in order. Anything else needs --x and --y (was: the first two columns, whatever they hold: `time,d_mm,F_kN`
    read the time as the displacement and d_mm as the load)."""
    if x and y:
        return x, y, "given"
    given = x or y
    if x is None:
        c = [n for n in names if is_displacement_name(n) and n != y]
        x = c[0] if len(c) == 1 else None
    if y is None:
        c = [n for n in names if is_load_name(n) and n != x]
        y = c[0] if len(c) == 1 else None
    if x and y:
        return x, y, "given and by name" if given else "by name"
    if len(names) == 2:
        rest = [n for n in names if n not in (x, y)]
        x = x or rest.pop(0)
        y = y or rest.pop(0)
        return x, y, "the only two columns, in order"
    dn = [n for n in names if is_displacement_name(n)]
    ln = [n for n in names if is_load_name(n)]
    raise ToolError(f"{source}: cannot tell the displacement and load columns from the names ({', '.join(names)}; "
                    f"displacement-like: {', '.join(dn) or 'none'}, load-like: {', '.join(ln) or 'none'}): give "
                    "--x DISPLACEMENT_COLUMN --y LOAD_COLUMN")


# Magnitudes that suggest the other unit in a structural test: a displacement of 1 m or more, a load below 100 N.
SUSPECT_X_M, SUSPECT_Y_N = 1.0, 100.0


def check_magnitudes(c: "Curve", rule_x: str = "", rule_y: str = "") -> list:
    """Warnings (printed and returned) when a CSV curve's magnitudes look like another unit than the one it was
    read in: a largest |displacement| of 1 m or more (mm read as m?) or below 1 um (m read as mm?); a largest |load|
    below 100 N (kN read as N?). Only warnings: a test may be that large or that small."""
    out = []
    ax = float(np.max(np.abs(c.x))) if len(c.x) else 0.0
    ay = float(np.max(np.abs(c.y))) if len(c.y) else 0.0
    src = f"{c.source}: column '{{}}' read in {{}} ({{}})"
    def fix(name, unit, flag, other_table, what):
        """The suggestion: another unit for this column, or another column when its name carries the other kind's
        unit (a load column named d_mm is the displacement, not a load in the wrong unit)."""
        theirs = unit_from_name(name, other_table)
        if theirs:
            return f"its name says {theirs}, a {what}: pick the right column with --{flag}"
        return f"--{flag}-unit {unit} or name it '{renamed(name, unit)}'"
    if ax >= SUSPECT_X_M:
        out.append(src.format(c.x_name, c.x_unit, rule_x or "unit") +
                   f" reaches {ax / LENGTH_UNITS[c.x_unit]:.4g} {c.x_unit} = {ax:.4g} m: mm? ("
                   + fix(c.x_name, "mm", "x", FORCE_UNITS, "force") + ")")
    elif 0 < ax < 1e-6:
        out.append(src.format(c.x_name, c.x_unit, rule_x or "unit") + f" reaches only {ax:.3g} m: m? (--x-unit m)")
    if 0 < ay < SUSPECT_Y_N:
        out.append(src.format(c.y_name, c.y_unit, rule_y or "unit") + f" reaches only {ay:.3g} N: kN? ("
                   + fix(c.y_name, "kN", "y", LENGTH_UNITS, "length") + ")")
    for w in out:
        warn(w)
    return out


def warn(msg: str) -> None:
    """A warning line on stdout (with the results; stderr keeps the one line of an error)."""
    print(f"warning: {msg}", flush=True)


def _si_from_run_unit(unit: str, kind: str, path: str, col: str) -> float:
    table = LENGTH_UNITS if kind == "length" else FORCE_UNITS
    if not unit:
        return 1.0  # the run contract is SI
    if unit not in table:
        raise ToolError(f"{path}: column '{col}' has unit '{unit}', expected a {kind}")
    return table[unit]


def load_curve(source: str, x: str | None = None, y: str | None = None, x_unit: str | None = None,
               y_unit: str | None = None, stage: int | None = None, partial: bool = False,
               label: str | None = None) -> Curve:
    """A load-displacement curve in SI from a run folder (summary.json names the columns and their units) or a CSV
    file (columns by name, else the first two; units given, else read from the column names, else m and N). `stage`
    keeps only the rows of that stage. A run folder's curve carries the load sign its case states, if any."""
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
        sign, sign_src = (None, "")
        if y == (run.summary.get("curve") or {}).get("y"):
            sign, sign_src = _case_curve_sign(run)
        return Curve(xs, ys, label or run.name, source, x, y, t, sign, sign_src)
    if os.path.isdir(source):
        raise ToolError(f"{source}: a folder but not a run folder (no summary.json or history.csv)")
    tab = read_table(source)
    if len(tab.names) < 2 and (x is None or y is None):
        raise ToolError(f"{source}: needs at least two columns")
    x, y, col_rule = pick_columns(tab.names, x, y, source)
    ux, rx = column_unit(x, x_unit, LENGTH_UNITS, DEFAULT_X_UNIT, "length", source)
    uy, ry = column_unit(y, y_unit, FORCE_UNITS, DEFAULT_Y_UNIT, "force", source)
    xs, ys = tab.numeric(x) * LENGTH_UNITS[ux], tab.numeric(y) * FORCE_UNITS[uy]
    t = tab.numeric("time") if tab.has("time") and tab.col("time").dtype.kind == "f" else None
    if stage is not None and tab.has("stage"):
        keep = tab.numeric("stage") == stage
        xs, ys = xs[keep], ys[keep]
        t = t[keep] if t is not None else None
    stem = os.path.splitext(os.path.basename(source))[0]
    c = Curve(xs, ys, label or stem, source, x, y, t, x_unit=ux, y_unit=uy, unit_rules=(rx, ry), columns_rule=col_rule)
    c.warnings = check_magnitudes(c, rx, ry)
    return c


def stage_curve(c: Curve, load_sign: str | float | None = "auto") -> tuple:
    """The curve as `validate` and `eeep` measure a run's loading stage: x = |x - x_0| (displacement from the first
    row kept), y = sign x load (resolve_sign). Returns (x, y, sign, rule)."""
    x, y = np.asarray(c.x, float), np.asarray(c.y, float)
    sign, rule = resolve_sign(c, load_sign)
    return np.abs(x - x[0]), sign * y, sign, rule


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
