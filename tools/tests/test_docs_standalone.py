"""The documentation stands on its own (issue 31 point 12): no citation of FORMULATION or CASES.md, two documents
that are not in the repository, in the READMEs, case files, tools' help texts and code comments."""
import os
import re
import subprocess

import pytest

from conftest import run_inprocess

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PATTERN = re.compile(r"FORMULATION|CASES\.md")


def tracked_files():
    try:
        out = subprocess.run(["git", "-C", REPO, "ls-files"], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout")
    return [f for f in out.splitlines() if f != "tools/tests/test_docs_standalone.py"]


def test_no_citation_of_documents_outside_the_repository():
    hits = []
    for f in tracked_files():
        p = os.path.join(REPO, f)
        try:
            with open(p, encoding="utf-8") as fh:
                for i, line in enumerate(fh, 1):
                    if PATTERN.search(line):
                        hits.append(f"{f}:{i}: {line.strip()[:100]}")
        except (UnicodeDecodeError, OSError):
            continue  # binary files (figures)
    assert not hits, "\n".join(hits)


@pytest.mark.parametrize("cmd", [[], ["eeep"], ["hysteresis"], ["ductility-fit"], ["plot"], ["cracks"], ["batch"],
                                 ["study", "mesh"], ["study", "speed"], ["validate"],
                                 ["limit"]])
def test_help_texts_cite_nothing_outside(cmd):
    rc, out, err = run_inprocess(*cmd, "--help")
    assert rc == 0 and out
    assert not PATTERN.search(out), out


@pytest.mark.parametrize("cmd", [[], ["eeep"], ["hysteresis"], ["ductility-fit"], ["plot"], ["cracks"], ["batch"],
                                 ["study"], ["study", "mesh"], ["study", "speed"], ["validate"]])
def test_help_texts_show_no_doubled_percent(cmd):
    """Issue 51 (13): argparse %-formats help strings (written '95 %%') but not descriptions, so the descriptions of
    ductility-fit and validate showed a literal '95 %%'."""
    rc, out, err = run_inprocess(*cmd, "--help")
    assert rc == 0 and out
    assert "%%" not in out, out
    if cmd in (["ductility-fit"], ["validate"]):
        assert " % " in out  # the percent sign is still there, once
