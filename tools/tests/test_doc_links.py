"""Every relative link of the Markdown pages ([text](path)) points to a file or folder of the repository."""
import os
import re
import subprocess

import pytest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")


def markdown_files():
    try:
        out = subprocess.run(["git", "-C", REPO, "ls-files", "*.md"], capture_output=True, text=True,
                             check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout")
    return out.split()


def broken_links(path):
    bad = []
    with open(os.path.join(REPO, path), encoding="utf-8") as fh:
        text = re.sub(r"```.*?```", "", fh.read(), flags=re.S)  # code blocks hold no links
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target) or target.startswith("#"):
            continue  # http:, mailto:, anchors within the page
        rel = target.split("#", 1)[0]
        if not os.path.exists(os.path.normpath(os.path.join(REPO, os.path.dirname(path), rel))):
            bad.append(f"{path}: {target}")
    return bad


def test_relative_links_resolve():
    bad = [b for f in markdown_files() for b in broken_links(f)]
    assert not bad, "\n".join(bad)
