"""The CLI's entry point runs its command on one BLAS thread unless the
user says otherwise; importing bifilar changes no environment
(bifilar.cli.limit_blas_threads; docs/performance.md, "minor25").

Each subprocess starts without the thread variables (tests/conftest.py sets
OPENBLAS_NUM_THREADS=1 for the suite), calls the entry point as the
console script does (``main([...])``, here ``--help``), then imports numpy
and reads the thread count OpenBLAS itself uses (its
``*_get_num_threads*`` symbol, where numpy's wheel ships scipy-openblas;
left out elsewhere): the variable must be set before numpy loads it.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

from bifilar.cli import BLAS_THREAD_VARS, limit_blas_threads
from conftest import ROOT

PROBE = r"""
import ctypes, glob, json, os, sys
before = {v: os.environ.get(v) for v in %(vars)r}
import bifilar, bifilar.cli
imported = {v: os.environ.get(v) for v in %(vars)r}
try:
    bifilar.cli.main(["--help"])
except SystemExit:
    pass
after = {v: os.environ.get(v) for v in %(vars)r}
import numpy
threads = None
for lib in glob.glob(os.path.join(os.path.dirname(numpy.__file__), "..", "numpy.libs", "*openblas*")):
    f = getattr(ctypes.CDLL(lib), "scipy_openblas_get_num_threads64_", None)
    threads = f() if f is not None else None
print(json.dumps({"before": before, "imported": imported, "after": after, "threads": threads}))
"""


def _probe(**env):
    base = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARS}
    out = subprocess.run([sys.executable, "-c", PROBE % {"vars": BLAS_THREAD_VARS}], cwd=ROOT,
                         env={**base, "PYTHONPATH": str(ROOT), **env}, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_entry_point_sets_one_thread_when_unset_and_import_does_not():
    d = _probe()
    assert all(v is None for v in d["before"].values())
    assert d["imported"] == d["before"]  # importing bifilar (and bifilar.cli) changes nothing
    assert d["after"]["OPENBLAS_NUM_THREADS"] == "1" and d["after"]["MKL_NUM_THREADS"] == "1"
    assert d["after"]["OMP_NUM_THREADS"] is None
    if d["threads"] is not None:  # OpenBLAS took it: set before numpy's first import
        assert d["threads"] == 1


def test_entry_point_respects_a_users_value():
    d = _probe(OPENBLAS_NUM_THREADS="2")
    assert d["after"]["OPENBLAS_NUM_THREADS"] == "2" and d["after"]["MKL_NUM_THREADS"] is None
    if d["threads"] is not None:
        assert d["threads"] == 2
    d = _probe(OMP_NUM_THREADS="2")  # OpenBLAS reads OMP_NUM_THREADS too: the user's choice, left alone
    assert d["after"]["OPENBLAS_NUM_THREADS"] is None and d["after"]["OMP_NUM_THREADS"] == "2"


def test_numpy_already_imported_leaves_the_environment(monkeypatch):
    """In a process that has loaded numpy (a library user, this test run)
    the BLAS has read its threads already: nothing to set."""
    for v in BLAS_THREAD_VARS:
        monkeypatch.delenv(v, raising=False)
    assert "numpy" in sys.modules
    assert limit_blas_threads() is False
    assert all(os.environ.get(v) is None for v in BLAS_THREAD_VARS)
