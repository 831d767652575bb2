"""The case file reference (cases/REFERENCE.md) and the case reader's sources stay in step: every key name the reader
asks for (a string literal passed to a Reader method in fdem/case.cpp, fdem/case_geometry.cpp, fdem/case_stages.cpp
and the kinds' files fdem/load_*.cpp and fdem/support_*.cpp, which read their own keys: fdem/load.hpp,
fdem/support.hpp) has an entry in the reference, and every entry names a key the sources ask for (no stale entries).
Key names only: the tables they belong to are checked, for the keys the shipped cases use, by
tests/core/test_case_reference.cpp."""
import glob
import os
import re

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
READERS = ["fdem/case.cpp", "fdem/case_geometry.cpp", "fdem/case_stages.cpp"] + sorted(
    os.path.relpath(p, REPO)
    for pattern in ("load_*.cpp", "support_*.cpp")
    for p in glob.glob(os.path.join(REPO, "fdem", pattern)))
REFERENCE = os.path.join(REPO, "cases", "REFERENCE.md")

METHODS = r"(?:number|integer|boolean|string|numbers|vec2|table|tables|has|node)"
# r.number("E", ...), top.table("case", ...), fr.string("type", ...): the key is the first argument.
LITERAL_CALL = re.compile(r"\.\s*" + METHODS + r"\(\s*\"([A-Za-z_][A-Za-z0-9_]*)\"")
# Helpers that take the key as a literal and pass it on: read_dof_set(ctx, r, "fix", ...), read_function(ctx, r,
# "function"), and the velocity components' `key = c == 0 ? "vx" : "vy"`.
HELPER_CALL = re.compile(r"\b(?:read_dof_set|read_function)\(\s*ctx\s*,\s*\w+\s*,\s*\"([A-Za-z_][A-Za-z0-9_]*)\"")
KEY_TERNARY = re.compile(r"key\s*=\s*[^;]*?\?\s*\"(\w+)\"\s*:\s*\"(\w+)\"")
# A Reader method called with anything but a literal: only the helpers' `key` parameter is known to this scan.
OTHER_CALL = re.compile(r"\.\s*" + METHODS + r"\(\s*([^\"\s)][^,)]*)\s*,")
KNOWN_VARIABLES = {"key"}


def source_keys():
    keys, unknown = set(), []
    for rel in READERS:
        with open(os.path.join(REPO, rel), encoding="utf-8") as fh:
            text = fh.read()
        code = re.sub(r"//[^\n]*", "", text)
        keys.update(LITERAL_CALL.findall(code))
        keys.update(HELPER_CALL.findall(code))
        for a, b in KEY_TERNARY.findall(code):
            keys.update((a, b))
        for arg in OTHER_CALL.findall(code):
            if arg.strip() not in KNOWN_VARIABLES and not arg.strip().startswith("std::string(key)"):
                unknown.append(f"{rel}: a Reader method called with the key {arg.strip()!r}")
    return keys, unknown


def documented_keys(path=REFERENCE):
    """Full key paths: every `code span` of a heading is a table path that the rows below it belong to (none: the
    top level); a table row whose first cell is a `code span` documents that key in each of those tables. The same
    rule as tests/core/test_case_reference.cpp."""
    keys, prefixes = set(), [""]
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            if line.startswith("#"):
                prefixes = re.findall(r"`([^`]*)`", line) or [""]
            elif line.startswith("| `"):
                key = re.match(r"\| `([^`]*)`", line).group(1)
                keys.update(f"{p}.{key}" if p else key for p in prefixes)
    return keys


def last_name(path):
    """The key's own name: the last part of its path, without the array mark."""
    return path.split(".")[-1].removesuffix("[]")


def test_the_scan_finds_the_reader_keys():
    keys, unknown = source_keys()
    assert not unknown, "\n".join(unknown) + "\n(extend the scan in tools/tests/test_case_reference.py)"
    # Known keys of each kind of call: a literal, a helper's literal, the ternary.
    for k in ("thickness", "GI", "servo", "fix", "rigid", "gravity_function", "vx", "vy", "openings", "spring"):
        assert k in keys, k
    assert len(keys) > 100


def test_every_key_of_the_reader_is_in_the_reference():
    keys, _ = source_keys()
    names = {last_name(p) for p in documented_keys()}
    missing = sorted(keys - names)
    assert not missing, "keys the case reader asks for with no entry in cases/REFERENCE.md: " + ", ".join(missing)


def test_every_key_of_the_reference_is_read():
    keys, _ = source_keys()
    # The names of materials, groups and regions are chosen by the user; [regions] maps them without a Reader.
    stale = sorted(p for p in documented_keys() if last_name(p) not in keys and last_name(p) != "NAME")
    assert not stale, "entries of cases/REFERENCE.md that the case reader never asks for: " + ", ".join(stale)


def test_the_reference_is_linked_from_the_cases_readme():
    with open(os.path.join(REPO, "cases", "README.md"), encoding="utf-8") as fh:
        assert "(REFERENCE.md)" in fh.read()
