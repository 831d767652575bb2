"""provenance: which committed figures still match their cases (issue 51, 7).

Every figure the tools write carries a stamp (figures.run_stamp): "fdem VERSION build BUILD | CASE [HASH], ...",
small in a corner and as the PNG text chunk / SVG metadata "Source". This command reads the stamps of the PNG files
under the given paths, finds each named case among the case files under --cases (by its [case] name, as `fdem check
--json` reads it), takes the case's hash as it stands now from the same answer, and reports per figure:
  ok          every case it names hashes as when the figure was made;
  stale       a case changed since (the figure must be regenerated: it no longer shows what the case gives);
  unknown     a case it names is not found (renamed or removed);
  unstamped   the figure carries no stamp (made before stamps, or by a script that does not stamp).
The build each figure was made with is listed too (a commit: `git log BUILD..` shows what changed in the code
since); a build with uncommitted changes ("BUILD-dirty") is flagged beside an ok figure and counted apart: no commit
rebuilds the program that drew it. Exit code 0 when every figure is ok, 2 otherwise (--strict), else 0 with the report.
"""
from __future__ import annotations

import os
import re

from .common import ToolError, fdem_binary, resolved_case, write_csv

STAMP = re.compile(r"^fdem (?P<version>\S+) build (?P<build>\S+)(?:; fdem .*?)? \| (?P<cases>.*)$")
CASE = re.compile(r"(?P<name>[^,\[\]]+?) \[(?P<hash>[0-9a-f]{16}|no hash)\]")


def read_stamp(path: str) -> str:
    """A PNG's "Source" text chunk, or a Markdown report's "Source: " line (validate's report.md)."""
    if path.endswith(".md"):
        with open(path, encoding="utf-8", errors="replace") as f:
            for line in f:
                if line.startswith("Source: "):
                    return line[len("Source: "):].strip()
        return ""
    from PIL import Image
    with Image.open(path) as im:
        return (im.info.get("Source") or "").strip()


def parse_stamp(stamp: str) -> dict | None:
    """{"version", "build", "cases": [(name, hash or None)]} of a stamp, None if it is not one."""
    m = STAMP.match(stamp)
    if not m:
        return None
    cases = [(c.group("name").strip(), None if c.group("hash") == "no hash" else c.group("hash"))
             for c in CASE.finditer(m.group("cases"))]
    return {"version": m.group("version"), "build": m.group("build"), "cases": cases}


def _norm(name: str) -> str:
    return "".join(ch for ch in name.lower() if ch.isalnum())


class CaseFinder:
    """[case] name -> case file among the TOML files under root, each name as the engine resolves the file
    (common.resolved_case); files whose stem looks like the name are asked first, so that a figure's case costs one
    `fdem check` or a few, not one per case file. The answers (the name and the case hash) are kept."""

    def __init__(self, root: str, fdem: str):
        self.fdem = fdem
        self.files = []
        for d, _, files in os.walk(root):
            self.files += [os.path.join(d, f) for f in sorted(files) if f.endswith(".toml")]
        self.resolved = {}  # path -> resolved case, or the engine's message (str) for a file it refuses

    def _resolve(self, path: str):
        if path not in self.resolved:
            try:
                self.resolved[path] = resolved_case(path, fdem=self.fdem)
            except ToolError as e:
                self.resolved[path] = str(e)
        return self.resolved[path]

    def find(self, name: str) -> str | None:
        want = _norm(name)
        for p in sorted(self.files, key=lambda f: _norm(os.path.splitext(os.path.basename(f))[0]) != want):
            rc = self._resolve(p)
            if isinstance(rc, dict) and rc["resolved"].get("name") == name:
                return p
        return None

    def refused(self) -> list:
        return [f"{p}: {m}" for p, m in self.resolved.items() if isinstance(m, str)]

    def hash(self, path: str) -> str:
        rc = self._resolve(path)
        if isinstance(rc, str):
            raise ToolError(f"fdem check {path} gave no case hash: {rc}")
        return rc["case_hash"]


def check(paths: list, cases_root: str, fdem: str) -> list:
    pngs = []  # figures, and validate's Markdown reports
    for p in paths:
        if os.path.isdir(p):
            for d, _, files in os.walk(p):
                pngs += [os.path.join(d, f) for f in sorted(files)
                         if f.endswith(".png") or (f.endswith(".md") and f.startswith("validate"))]
        elif p.endswith(".png") or p.endswith(".md"):
            pngs.append(p)
        else:
            raise ToolError(f"{p}: not a folder, a PNG file or a Markdown report")
    finder = CaseFinder(cases_root, fdem)
    rows = []
    for png in sorted(pngs):
        stamp = read_stamp(png)
        parsed = parse_stamp(stamp) if stamp else None
        if not parsed:
            rows.append({"figure": png, "status": "unstamped", "build": "", "cases": "", "detail": ""})
            continue
        status, detail = "ok", []
        # A case named with several hashes: its runs with --set overrides beside the plain one (validate's
        # half-rate check, a study's grid): the figure matches the case if one of them is the case as it stands.
        by_name = {}
        for name, h in parsed["cases"]:
            by_name.setdefault(name, []).append(h)
        for name, hs in by_name.items():
            path = finder.find(name)
            if path is None:
                status = "unknown" if status == "ok" else status
                refused = finder.refused()
                detail.append(f"{name}: no case of that name under {cases_root}"
                              + (f" ({len(refused)} file(s) there fdem check refuses, e.g. {refused[0]})"
                                 if refused else ""))
                continue
            now = finder.hash(path)
            if all(h is None for h in hs):
                status = "stale" if status in ("ok", "unknown") else status
                detail.append(f"{name}: the figure's run carried no hash")
            elif now not in hs:
                status = "stale"
                made = ", ".join(f"[{h}]" for h in hs if h)
                detail.append(f"{name}: made from {made}, {os.path.relpath(path)} now hashes [{now}]")
        if parsed["build"].endswith("-dirty"):
            detail.append(f"made by build {parsed['build']}, which had uncommitted changes: regenerate it from a "
                          "committed build to make it reproducible")
        rows.append({"figure": png, "status": status, "build": parsed["build"],
                     "cases": ", ".join(n for n, _ in parsed["cases"]), "detail": "; ".join(detail)})
    return rows


def cmd_provenance(args):
    rows = check(args.paths, args.cases, fdem_binary(args.fdem))
    if not rows:
        raise ToolError("no PNG figure or validate report under " + ", ".join(args.paths))
    width = max(len(os.path.relpath(r["figure"])) for r in rows)
    for r in rows:
        print(f"{os.path.relpath(r['figure']):<{width}}  {r['status']:<9}  {r['build'] or '-':<14}  "
              + (r["detail"] or r["cases"]))
    counts = {s: sum(r["status"] == s for r in rows) for s in ("ok", "stale", "unknown", "unstamped")}
    dirty = sum(r["status"] == "ok" and r["build"].endswith("-dirty") for r in rows)
    print(", ".join(f"{n} {s}" for s, n in counts.items()) + f" of {len(rows)} figures and reports"
          + (f" ({dirty} of the ok ones made by a build with uncommitted changes)" if dirty else ""))
    if args.csv:
        write_csv(args.csv, list(rows[0].keys()), [list(r.values()) for r in rows])
        print(f"wrote {args.csv}")
    return 2 if args.strict and counts["ok"] != len(rows) else 0


def add_parser(sub):
    p = sub.add_parser("provenance", help="which committed figures still match their cases (stamps against hashes)",
                       description=__doc__.split("\n\n")[1] if __doc__ else None)
    p.add_argument("paths", nargs="*", default=["cases"], metavar="PATH", help="folders or PNG files (default: cases)")
    p.add_argument("--cases", default="cases", help="folder of the case files the stamps name (default: cases)")
    p.add_argument("--fdem", help="fdem executable (default: $FDEM_BIN, else build/fdem/fdem)")
    p.add_argument("--csv", help="also write the table to this CSV file")
    p.add_argument("--strict", action="store_true", help="exit 2 unless every figure is ok")
    p.set_defaults(func=cmd_provenance)

