"""Lazy start (issue 14): the CLI's entry points do not load scipy's heavy
submodules or matplotlib before a computation needs them.

Each check runs in a fresh interpreter (this test process has long imported
everything) and inspects ``sys.modules``; no timing is asserted (the start-up
time is measured by ``scripts/bench_startup.py``).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from conftest import CONFIGS, ROOT

HEAVY = ("scipy.optimize", "scipy.linalg", "scipy.integrate", "scipy.special", "matplotlib")


def _loaded_after(code: str) -> list[str]:
    """Heavy modules present in sys.modules after running ``code`` in a fresh interpreter."""
    probe = code + (
        "\nimport sys, json\n"
        f"print(json.dumps(sorted(m for m in sys.modules if m.startswith({HEAVY!r}))), file=sys.stderr)\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    r = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, cwd=ROOT, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stderr.strip().splitlines()[-1])


def _cli(argv: list[str]) -> str:
    return (
        "import sys, runpy\n"
        f"sys.argv = ['bifilar', *{argv!r}]\n"
        "try:\n    runpy.run_module('bifilar', run_name='__main__')\nexcept SystemExit as e:\n"
        "    assert not e.code, e.code\n"
    )


def test_importing_the_cli_loads_no_heavy_module():
    assert _loaded_after("import bifilar.cli") == []


@pytest.mark.parametrize("argv", [["--help"], ["modes", "--help"], ["simulate", "--help"], ["sweep", "--help"]])
def test_help_loads_no_heavy_module(argv):
    assert _loaded_after(_cli(argv)) == []


def test_modes_json_loads_no_scipy():
    """The rest pose (Newton start) and the modes (numpy eigensolver) need no scipy."""
    loaded = _loaded_after(_cli(["modes", str(CONFIGS / "thesis_plate_rest.yaml"), "--json"]))
    assert loaded == []
