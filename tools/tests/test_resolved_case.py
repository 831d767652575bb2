"""Issue 52 (5): the tools take case values only from the engine's resolved case (`fdem check CASE --json`, read by
common.resolved_case); no module of fdemtools reads a case file or re-implements --set and the defaults."""
import json
import os
import re
import shutil
import subprocess

import pytest

from fdemtools import common

HERE = os.path.dirname(os.path.abspath(__file__))
PACKAGE = os.path.join(os.path.dirname(HERE), "fdemtools")
REPO = os.path.dirname(os.path.dirname(HERE))
TINY = os.path.join(HERE, "data", "tiny_shear.toml")


def fdem_bin():
    return os.environ.get("FDEM_BIN") or os.path.join(REPO, "build", "fdem", "fdem")


@pytest.fixture
def fdem():
    if not os.path.isfile(fdem_bin()):
        pytest.fail(f"no fdem executable at {fdem_bin()} (build it or set FDEM_BIN)")
    return fdem_bin()


def run(fdem, *args):
    return subprocess.run([fdem, *map(str, args)], capture_output=True, text=True, timeout=300)


def check_hash(stdout: str) -> str:
    m = re.search(r"case hash ([0-9a-f]{16})", stdout)
    assert m, stdout
    return m.group(1)


def test_no_module_reads_a_case_file():
    """A source scan: no module imports a TOML reader (tomllib, tomli, toml, tomlkit), so none can parse a case file
    or re-apply --set and the defaults beside the engine."""
    reader = re.compile(r"^\s*(import|from)\s+(tomllib|tomli|toml|tomlkit|pytoml)\b|__import__\(\s*['\"]toml",
                        re.MULTILINE)
    found = []
    for d, _, files in os.walk(PACKAGE):
        for f in files:
            if f.endswith(".py"):
                p = os.path.join(d, f)
                with open(p, encoding="utf-8") as fh:
                    text = fh.read()
                found += [f"{os.path.relpath(p, PACKAGE)}: {m.group(0).strip()}" for m in reader.finditer(text)]
                if "tomllib" in text:  # also a lazy import inside a function
                    found.append(f"{os.path.relpath(p, PACKAGE)}: mentions tomllib")
    assert not found, "modules reading TOML themselves: " + "; ".join(found)


def test_json_hash_is_the_check_hash_and_defaults_show(tmp_path, fdem):
    r = run(fdem, "check", TINY, "--json")
    assert r.returncode == 0, r.stderr
    j = json.loads(r.stdout)  # stdout is the object alone
    assert j["case_hash"] == check_hash(run(fdem, "check", TINY).stdout)
    assert j["case_file"] == TINY and j["overrides"] == []
    assert j["case"]["geometry"]["mesh_size"] == 0.05 and "numerics" not in j["case"]
    res = j["resolved"]
    assert res["name"] == "tiny-shear" and res["geometry"] == {**res["geometry"], "type": "rectangle",
                                                              "mesh_size_m": 0.05}
    # no [numerics] in the file: the engine's defaults
    assert res["numerics"]["safety"] == 0.8 and res["numerics"]["dt_automatic"] is True
    assert res["numerics"]["dt_fixed_s"] is None and res["numerics"]["dt_s"] > 0
    st = res["stages"][0]
    assert st["name"] == "shear" and st["duration_s"] == 0.1 and st["local_damping"] == 0.3
    assert st["contact_damping"] == 0 and st["mass_damping_1_s"] == 0
    assert res["curve"] == {"x": "u_top", "y": "F_base", "sign": None} and res["reference"] is None
    assert j["mesh"]["triangles"] > 0
    # the tools' reader gives the same object
    assert common.resolved_case(TINY, fdem=fdem) == j


def test_set_and_unset_change_the_resolved_value_and_the_hash(tmp_path, fdem):
    plain = common.resolved_case(TINY, fdem=fdem)
    s = common.resolved_case(TINY, [("numerics.safety", "0.5")], fdem=fdem)
    assert s["resolved"]["numerics"]["safety"] == 0.5 and s["case"]["numerics"]["safety"] == 0.5
    assert s["case_hash"] != plain["case_hash"]
    assert s["case_hash"] == check_hash(run(fdem, "check", TINY, "--set", "numerics.safety=0.5").stdout)
    assert s["overrides"] == [["numerics.safety", "0.5"]]
    # --unset: the key goes and its default applies
    u = common.resolved_case(TINY, unsets=["stages.1.local_damping"], fdem=fdem)
    assert "local_damping" not in u["case"]["stages"][0] and u["resolved"]["stages"][0]["local_damping"] == 0
    assert u["case_hash"] != plain["case_hash"]
    # "KEY=VALUE" strings as the command lines give them
    assert common.resolved_case(TINY, ["numerics.safety=0.5"], fdem=fdem) == s


def test_bad_key_exit_1_empty_stdout_and_one_line_error(tmp_path, fdem):
    r = run(fdem, "check", TINY, "--set", "numerics.bogus=1", "--json")
    assert r.returncode == 1 and r.stdout == "" and "numerics.bogus" in r.stderr
    with pytest.raises(common.ToolError, match="numerics.bogus"):
        common.resolved_case(TINY, [("numerics.bogus", "1")], fdem=fdem)
    with pytest.raises(common.ToolError, match="no such case file"):
        common.resolved_case(str(tmp_path / "none.toml"), fdem=fdem)


def test_an_edited_case_is_resolved_again(tmp_path, fdem):
    """The cache is per arguments and per contents of the case file: an edit in the same process is seen."""
    case = tmp_path / "c.toml"
    shutil.copy(TINY, case)
    a = common.resolved_case(str(case), fdem=fdem)
    case.write_text(case.read_text().replace("duration = 0.1 ", "duration = 0.2 "))
    b = common.resolved_case(str(case), fdem=fdem)
    assert a["resolved"]["stages"][0]["duration_s"] == 0.1 and b["resolved"]["stages"][0]["duration_s"] == 0.2
    assert a["case_hash"] != b["case_hash"]
