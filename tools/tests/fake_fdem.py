#!/usr/bin/python3
"""A stand-in for the fdem executable, for testing the batch and study logic only (no physics).

`fake_fdem.py run CASE --out DIR [--set k=v ...] [--threads N] [--quiet]` appends its --set list to the file
named by $FAKE_FDEM_LOG and writes a run folder following the contract. The "peak load" depends on the settings
in a known way: peak = 10 kN * (1 + mesh_size) * (1 + rate) * (1 + damping); wall time = 0.01 / mesh_size^2.
A setting `fail=true` (or `fail_below=H` with a mesh size below H) makes it exit 2 with a failed summary (its
monitors written all the same); `slow=SECONDS` makes it sleep first; `die=TEXT` makes
it print "error: TEXT" as the engine does for bad input and exit 1 before writing any summary. With `ref=1` the summary
carries a [reference] result (monitor F, quantity peak, value 10 kN, computed = the peak). `ref_quantity=first_peak` makes it
that quantity, computed = 0.9 x the peak (`final`: the peak). With `reaction=1` the load
F is recorded as a reaction (negative: -peak), and so is the reference's computed value, as the engine writes it.
Like fdem, SIGTERM stops it with status "interrupted" and exit 143; it then also writes a checkpoint file
(checkpoint.bin). `run --help` lists `--restart RUN_DIR` only when $FAKE_FDEM_RESTART is 1; `--restart DIR` is
logged (key "--restart") and skips the `slow` sleep.
`fake_fdem.py check CASE [--set k=v ...] [--unset k ...] --json` answers as `fdem check --json` does, for any TOML file
(no validation, no mesh): the tree with the overrides applied, a case hash of that tree, and a "resolved" object of
the same shape as the engine's for the keys the tools read (check_json). Not logged.
"""
import json
import os
import signal
import sys
import time


def _value(text: str):
    """A --set value as fdem parses it: TOML, or a bare word as a string."""
    import tomllib
    try:
        return tomllib.loads("v = " + text)["v"]
    except tomllib.TOMLDecodeError:
        return text


def _walk(tree, parts):
    cur = tree
    for p in parts:
        cur = cur[int(p) - 1] if isinstance(cur, list) else cur.setdefault(p, {})
    return cur


def check_json(case: str, overrides: list) -> dict:
    """What `fdem check CASE --json` prints, for a stand-in case: overrides are ("k", "v") to set or ("k", None) to
    unset, in order. Defaults as the engine's (numerics.safety 0.8, damping 0 and kept by later stages)."""
    import hashlib
    import tomllib
    with open(case, "rb") as f:
        tree = tomllib.load(f)
    for k, v in overrides:
        parts = k.split(".")
        parent = _walk(tree, parts[:-1])
        if v is None:
            del parent[parts[-1]]
        elif isinstance(parent, list):
            parent[int(parts[-1]) - 1] = _value(v)
        else:
            parent[parts[-1]] = _value(v)
    geo = tree.get("geometry") or {}
    here = os.path.dirname(case)
    gfile = os.path.join(here, geo["file"]) if isinstance(geo.get("file"), str) else None
    num = tree.get("numerics") or {}
    stages, damp = [], {"local_damping": 0, "contact_damping": 0, "mass_damping": 0}
    for st in tree.get("stages") or []:
        damp.update({k: st[k] for k in damp if k in st})
        stages.append({"name": st.get("name", ""), "local_damping": damp["local_damping"],
                       "contact_damping": damp["contact_damping"], "mass_damping_1_s": damp["mass_damping"]})
    curve = (tree.get("output") or {}).get("curve")
    resolved = {
        "name": (tree.get("case") or {}).get("name", os.path.splitext(os.path.basename(case))[0]),
        "geometry": {"type": geo.get("type", "rectangle"), "mesh_size_m": geo.get("mesh_size"),
                     "mesh_size_beam_m": geo.get("mesh_size_beam"), "mesh_size_base_m": geo.get("mesh_size_base"),
                     "file": gfile},
        "numerics": {"dt_fixed_s": num.get("dt"), "dt_automatic": "dt" not in num, "safety": num.get("safety", 0.8),
                     "dt_s": 1e-6},
        "materials": {}, "interfaces": [], "stages": stages,
        "curve": None if not isinstance(curve, dict) else {"x": curve.get("x"), "y": curve.get("y"),
                                                           "sign": curve.get("sign")},
        "reference": tree.get("reference"),
        "files": [gfile] if gfile and os.path.isfile(gfile) else [],
    }
    text = json.dumps(tree, sort_keys=True, default=str)
    return {"case_file": case, "case_hash": hashlib.sha256(text.encode()).hexdigest()[:16],
            "overrides": [[k, "(unset)" if v is None else v] for k, v in overrides], "case": tree,
            "resolved": resolved, "mesh": {"triangles": 0, "nodes": 0, "cohesive_elements": 0}, "notes": [],
            "warnings": []}


def check(argv) -> int:
    case, overrides, i = argv[0], [], 1
    while i < len(argv):
        if argv[i] == "--set":
            k, v = argv[i + 1].split("=", 1); overrides.append((k, v)); i += 2
        elif argv[i] == "--unset":
            overrides.append((argv[i + 1], None)); i += 2
        elif argv[i] == "--threads":
            i += 2
        else:
            i += 1
    try:
        j = check_json(case, overrides)
    except Exception as e:  # a stand-in: any failure is bad input
        print(f"error: {case}: {type(e).__name__}: {e}", file=sys.stderr)
        return 1
    print(json.dumps(j, default=str))
    return 0


def main(argv):
    if argv[:1] == ["check"] and len(argv) > 1:
        return check(argv[1:])
    if argv[:2] == ["run", "--help"]:
        print("usage: fake_fdem.py run CASE --out DIR [--set KEY=VALUE] [--threads N] [--quiet]"
              + (" [--restart RUN_DIR]" if os.environ.get("FAKE_FDEM_RESTART") == "1" else ""))
        return 0
    if len(argv) < 2 or argv[0] != "run":
        return 1
    out, sets, restart = None, {}, None
    i = 2
    while i < len(argv):
        if argv[i] == "--out":
            out = argv[i + 1]; i += 2
        elif argv[i] == "--restart":
            restart = argv[i + 1]; i += 2
        elif argv[i] == "--set":
            k, v = argv[i + 1].split("=", 1); sets[k] = v; i += 2
        elif argv[i] == "--threads":
            i += 2
        else:
            i += 1
    summ = {"case": "fake", "status": "running", "curve": {"x": "u", "y": "F"}, "columns": {"u": "m", "F": "N"}}

    def stop(signum, frame):
        os.makedirs(out, exist_ok=True)
        with open(os.path.join(out, "checkpoint.bin"), "w") as f:
            f.write("fake checkpoint\n")
        with open(os.path.join(out, "summary.json"), "w") as f:
            json.dump(dict(summ, status="interrupted"), f)
        sys.exit(128 + signum)
    signal.signal(signal.SIGTERM, stop)
    log = os.environ.get("FAKE_FDEM_LOG")
    if log:
        with open(log, "a") as f:
            f.write(json.dumps(dict(sets, **({"--restart": restart} if restart else {})), sort_keys=True) + "\n")
    if "die" in sets:
        print("fdem: reading the case")
        print(f"error: {sets['die']}", file=sys.stderr)
        return 1
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summ, f)
    if "slow" in sets and not restart:
        time.sleep(float(sets["slow"]))
    h = float(sets.get("geometry.mesh_size", 0.1))
    rate = float(sets.get("rate", 0.0))
    damp = float(sets.get("damping", 0.0))
    peak = 10e3 * (1 + h) * (1 + rate) * (1 + damp)
    n = 21
    sgn = -1.0 if sets.get("reaction") == "1" else 1.0
    with open(os.path.join(out, "history.csv"), "w") as f:
        f.write("time,step,stage,u,F,E_kin,W_ext,D_frac\n")
        for k in range(n):
            u = 1e-3 * k / (n - 1)
            F = peak * min(1.0, 2 * k / (n - 1))
            f.write(f"{k * 0.1},{k},1,{u},{sgn * F},0,{F * u},{0.3 * F * u}\n")
    failed = sets.get("fail") == "true" or h < float(sets.get("fail_below", 0))
    summ.update({"status": "failed" if failed else "completed", "message": "made to fail" if failed else "",
                 "n_triangles": int(1 / h ** 2), "n_nodes": int(1 / h ** 2), "dt": 1e-6, "steps": 20,
                 "wall_time_s": 0.01 / h ** 2, "cpu_time_s": 0.02 / h * (1 + float(sets.get("damping", 0))),
                 "threads": 1,
                 "monitors": {"u": {"min": 0, "max": 1e-3, "final": 1e-3},
                              "F": {"min": min(0, sgn * peak), "max": max(0, sgn * peak), "final": sgn * peak}},
                 "energy": {"balance_error": 0.001 * (1 + h)},
                 "settings": sets})
    if sets.get("ref") == "1":
        q = sets.get("ref_quantity", "peak")
        got = {"peak": peak, "first_peak": 0.9 * peak, "final": peak}[q]
        summ["reference"] = {"monitor": "F", "quantity": q, "value": 10e3, "source": "fake", "computed": sgn * got,
                             "relative_error": (got - 10e3) / 10e3}
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summ, f)
    return 2 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
