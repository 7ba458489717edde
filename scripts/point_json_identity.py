#!/usr/bin/env python
"""Dump, for an A/B identity check of two trees, ``evaluate_point``'s JSON
(:func:`bifilar.jsonable.to_jsonable`; it has no timing key) of a set of
sweep points and ``bifilar simulate --json`` of every ``configs/*.yaml``
(``runtime_s`` removed), one line each, to stdout.

Run it from each tree's root (so that tree's ``bifilar`` is imported, not
the installed copy; the first line names the file imported) and compare the
outputs byte for byte::

    (cd /path/to/base && python scripts/point_json_identity.py > /tmp/a.txt)
    (cd /path/to/mine && python scripts/point_json_identity.py > /tmp/b.txt)
    diff <(tail -n +2 /tmp/a.txt) <(tail -n +2 /tmp/b.txt) && echo identical

``--no-simulate``: the points only (the simulate runs take ~10 s).
``--sweeps``: also whole sweeps by ``run_sweep`` (one process: since
sigbatch29 their points in chunks sharing their sigma-point and
start-pose batches), one line a point: the 28-point boat sweep of issue
14, the drone (second-order sigmas), the trifilar and audit24's c04
(sigma points that turn).  The script only calls ``run_sweep``, so this
file may be run from a tree that predates the option (``cd OLD &&
python /path/to/this/script --sweeps``: OLD's bifilar is imported).
Written for session 27 (runs27: a point's runs' Python around odeint).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path.cwd()
sys.path.insert(0, str(ROOT))

import bifilar  # noqa: E402
from bifilar.config import read_yaml  # noqa: E402
from bifilar.studies import sweep as sw  # noqa: E402

C = ROOT / "configs"
#: (config, the point's parameters, settings overrides): the three bench_sweep cases, a grid of the boat,
#: the drone, the hangings, the 6.4 cylinder, a point at amplitude 0.3, four elastic wires
POINTS = [(C / "thesis_plate_rest.yaml", {"spacing": 3.0}, {}),
          (C / "solar_boat.yaml", {"spacing": 3.0}, {}),
          (C / "trifilar_kth.yaml", {}, {}),
          (C / "solar_boat.yaml", {"spacing": 1.0, "length": 2.0}, {}),
          (C / "solar_boat.yaml", {"spacing": 4.0, "length": 5.0}, {}),
          (C / "solar_boat.yaml", {"spacing": 1.0, "length": 2.0}, {"amplitude": 0.3}),
          (C / "thesis_plate_rest.yaml", {"spacing": 2.0}, {}),
          (C / "drone_parallel.yaml", {}, {}),
          (C / "thesis_lin1_torsion.yaml", {}, {}),
          (C / "thesis_lin2_pitch.yaml", {}, {}),
          (C / "thesis_lin3_roll.yaml", {}, {}),
          (C / "thesis_cylinder_6_4.yaml", {}, {}),
          (C / "trifilar_kth.yaml", {}, {"amplitude": 0.3}),
          (ROOT / "tests" / "data" / "audit24" / "c07t.yaml", {}, {"lengths": [1.19] * 4})]
#: ``lengths``: the config's rig.lengths replaced (c07t's wire 4 is slack at rest as written)

#: (config, grid) of ``--sweeps``
SWEEPS = [(C / "solar_boat.yaml", [{"spacing": s, "length": L} for s in (1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0)
                                   for L in (2.0, 3.0, 4.0, 5.0)]),
          (C / "drone_parallel.yaml", [{"length": L} for L in (0.8, 1.0, 1.2, 1.5, 2.0)]),
          (C / "trifilar_kth.yaml", [{"length": L} for L in (1.0, 1.6, 2.2)]),
          (ROOT / "tests" / "data" / "audit24" / "c04_dronepart.yaml", [{"spacing": 0.06}, {"spacing": 0.05},
                                                                        {"length": 0.4}])]


def _drop_runtime(doc) -> None:
    """Every ``runtime_s`` key of ``doc`` removed, at any depth."""
    if isinstance(doc, dict):
        doc.pop("runtime_s", None)
        for v in doc.values():
            _drop_runtime(v)
    elif isinstance(doc, list):
        for v in doc:
            _drop_runtime(v)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-simulate", action="store_true", help="the sweep points only")
    ap.add_argument("--sweeps", action="store_true", help="also whole sweeps by run_sweep, a line a point")
    args = ap.parse_args(argv)
    print("bifilar imported from", bifilar.__file__)
    for path, params, over in POINTS:
        cfg = read_yaml(path)
        over = dict(over)
        if "lengths" in over:
            cfg["rig"]["lengths"] = over.pop("lengths")
        st = sw.resolve_settings(cfg)
        if over:
            st = dataclasses.replace(st, **over)
        doc = sw.evaluate_point(cfg, str(path), params, st)
        print(path.name, json.dumps(params, sort_keys=True), json.dumps(over, sort_keys=True), json.dumps(doc))
    if args.sweeps:
        for path, grid in SWEEPS:
            cfg = read_yaml(path)
            for params, doc in zip(grid, sw.run_sweep(cfg, str(path), grid, sw.resolve_settings(cfg))):
                print(path.name, "sweep", json.dumps(params, sort_keys=True), json.dumps(doc))
    if not args.no_simulate:
        for path in sorted(C.glob("*.yaml")):
            p = subprocess.run([sys.executable, "-m", "bifilar", "simulate", str(path), "--json"], cwd=ROOT,
                               capture_output=True, text=True)
            try:
                doc = json.loads(p.stdout)
            except ValueError:
                print(path.name, "simulate exit", p.returncode, p.stdout.strip()[-300:], p.stderr.strip()[-300:])
                continue
            _drop_runtime(doc)
            print(path.name, "simulate exit", p.returncode, json.dumps(doc, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
