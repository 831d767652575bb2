"""Puts tools/ on sys.path so the tests import fdemtools from any working directory, and gives helpers."""
import os
import subprocess
import sys

import pytest

TOOLS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if TOOLS not in sys.path:
    sys.path.insert(0, TOOLS)
os.environ.setdefault("MPLBACKEND", "Agg")

ENTRY = os.path.join(TOOLS, "fdem-tools")
DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


def run_cli(*args, cwd=None, env=None):
    """Runs the fdem-tools entry as a user would; returns (exit code, stdout, stderr)."""
    e = dict(os.environ)
    e["MPLBACKEND"] = "Agg"
    e.pop("FDEM_TOOLS_DEBUG", None)
    if env:
        e.update(env)
    r = subprocess.run([sys.executable, ENTRY, *map(str, args)], capture_output=True, text=True, cwd=cwd, env=e,
                       timeout=300)
    return r.returncode, r.stdout, r.stderr


def run_inprocess(*args, cwd=None, env=None):
    """Same as run_cli but in this process (no interpreter start-up): the exit code and both streams."""
    import contextlib
    import io
    from fdemtools.cli import main
    out, err = io.StringIO(), io.StringIO()
    old_cwd, old_env = os.getcwd(), dict(os.environ)
    try:
        if cwd:
            os.chdir(cwd)
        os.environ.pop("FDEM_TOOLS_DEBUG", None)
        if env:
            os.environ.update(env)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                rc = main([str(a) for a in args])
            except SystemExit as e:  # argparse usage errors
                rc = e.code
    finally:
        os.chdir(old_cwd)
        os.environ.clear()
        os.environ.update(old_env)
    return rc, out.getvalue(), err.getvalue()


@pytest.fixture
def cli():
    return run_inprocess


@pytest.fixture
def cli_subprocess():
    return run_cli
