"""A set-aside component's mode in the point's physical limits and its
advice (docs/design.md, "plan26, session 26"; rank26's left items 1 and 2).

A component set aside (best relative sigma above 50 %) is not timed, so its
mode is not excited: its nonlinear run's peak tension, depth and slack must
not rule a point out, and the advice must not tell the user how to time it.
The real points are audit24's c04 (a 30 g part on a bifilar; Iyy from a
swing at +- 1490 % at spacing 0.04) on screens with the nonlinear runs, as
tests/test_rank26.py evaluates them without; the others are hand-made.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from bifilar.studies import sweep as sw
from bifilar.studies.ranking import guarded_limits, violations

DATA = Path(__file__).parent / "data" / "audit24"


@pytest.fixture(scope="module")
def c04():
    """c04 at spacing 0.04 (Iyy's swing, the roll and the torsion run) and
    0.06 (wires vertical: no Iyy; roll and torsion), screens with the runs
    (0.5 s CPU)."""
    from bifilar.config import read_yaml

    path = str(DATA / "c04_dronepart.yaml")
    cfg = read_yaml(path)
    st = sw.resolve_settings(cfg, tensions=True)
    return cfg, path, st, sw.run_sweep(cfg, path, [{"spacing": v} for v in (0.04, 0.06)], st, screen=True)


def _peak(p, comps):
    """The largest wire tension (N) in the runs of the modes ``comps`` are timed from, read from each run's
    own figures (``tension.by_mode``), not from what the limits read."""
    modes = {p["components"][c]["mode"] for c in comps if p["components"][c].get("mode")}
    return max(max(v["max"]) for m, v in p["tension"]["by_mode"].items() if m in modes)


def test_the_set_aside_components_run_does_not_decide_max_tension(c04):
    """At 0.04 Iyy's swing is the run with the highest tension (0.1521 N;
    the roll's 0.1472, the torsion's 0.1472): with --max-tension 0.15 the
    point was ruled out for a mode nobody excites.  Now its limits are the
    roll's and the torsion's runs, the swing's is listed as left out, and the
    point is feasible; counting every run (among None, main's rule) still
    rules it out.  Fails with the guarded figure over every run, or with the
    point's own peak in violations."""
    _, _, _, pts = c04
    p04, p06 = pts
    assert p04["tension"]["peak"] == pytest.approx(_peak(p04, ["Ixx", "Iyy", "Izz"]), rel=1e-15)
    own = _peak(p04, ["Ixx", "Izz"])
    assert own < 0.15 < p04["tension"]["peak"]  # the case: only the swing's run breaks the limit
    rec = sw.assess(pts, sw.Constraints(max_tension=0.15), None)
    assert rec["measurable"] == ["Ixx", "Izz"] and [a["component"] for a in rec["set_aside"]] == ["Iyy"]
    g = p04["guard_limits"]
    assert g["left_out"] == ["swing-x"] and g["peak"] == pytest.approx(own, rel=1e-15)
    assert g["depth"] == pytest.approx(max([p04["depth"]["rest"]] + [p04["depth"]["by_mode"][m]
                                                                      for m in ("roll", "torsion")]), rel=1e-15)
    assert [p["feasible"] for p in pts] == [True, True], [p["violations"] for p in pts]
    assert "guard_limits" not in p06  # every run counts there: the point's JSON as before
    # main's rule, every run counted: 0.04 breaks the limit by the swing's figure
    assert [n for n, _ in violations(p04, sw.Constraints(max_tension=0.15))] == ["max_tension"]
    # plan's search penalty reads the same figures: no excess at 0.04 with the ranked components
    from bifilar.studies.plan import _penalty

    ob = sum(p04["components"][k]["rel_sigma"] ** 16 for k in ("Ixx", "Izz")) ** (1 / 16)  # its 16-norm
    assert _penalty(p04, sw.Constraints(max_tension=0.15), None, ["Ixx", "Izz"]) == pytest.approx(ob, rel=1e-12)
    # and below the roll's peak too, its excess is the counted runs' (0.16 % over), not the swing's (3.5 %)
    assert _penalty(p04, sw.Constraints(max_tension=0.147), None, ["Ixx", "Izz"]) == pytest.approx(
        ob * (1 + 100 * (own / 0.147 - 1)), rel=1e-12)
    # the sweep's explanation of a point quotes the limits' figure and says which run was left out
    from bifilar.studies.recommend import explain

    line = next(x for x in explain(p04, sw.Constraints(max_tension=0.15), None, ["Ixx", "Izz"]) if "tension" in x)
    assert f"{own:.4g} N" in line and "swing-x run left out" in line


def _hand(runs: dict, comps: dict) -> dict:
    """A hand-made point: ``runs`` {mode: (peak N, depth m, slack wires)}, ``comps`` {name: mode}."""
    return {"params": {"spacing": 0.1}, "valid": True, "error": None,
            "components": {k: {"identifiable": True, "rel_sigma": 0.1, "mode": m, "separation": 0.5}
                           for k, m in comps.items()},
            "tension": {"rest": [1.0, 1.0], "peak": max(r[0] for r in runs.values()),
                        "slack": any(r[2] for r in runs.values()),
                        "slack_wires": sorted({w for r in runs.values() for w in r[2]}),
                        "by_mode": {m: {"max": [r[0], 1.0], "min": [0.0, 1.0], "slack_wires": r[2]}
                                    for m, r in runs.items()}},
            "depth": {"rest": 1.0, "max": max(r[1] for r in runs.values()),
                      "by_mode": {m: r[1] for m, r in runs.items()}}}


def test_slack_and_depth_of_a_set_aside_mode_are_left_out_a_shared_mode_stays():
    """Hand-made: the swing (Iyy's, set aside) goes slack and reaches 1.3 m;
    the torsion (Izz's) 1.1 m.  Ranked over Izz alone: neither the slack
    nor the depth limit 1.2 m is broken; where Izz is estimated from the
    swing too (a shared mode), both are.  Fails with the slack taken from
    the point's own figure, the depth's rest or runs swapped, or the shared
    mode dropped with the set-aside component."""
    runs = {"swing-x": (3.0, 1.3, [2]), "torsion": (2.0, 1.1, [])}
    c = sw.Constraints(max_depth=1.2, max_tension=2.5)
    p = _hand(runs, {"Iyy": "swing-x", "Izz": "torsion"})
    assert violations(p, c, None, ["Izz"]) == []
    assert guarded_limits(p, ["Izz"]) == {"peak": 2.0, "depth": 1.1, "slack_wires": [], "left_out": ["swing-x"]}
    assert {n for n, _ in violations(p, c, None, ["Iyy", "Izz"])} == {"slack", "max_depth", "max_tension"}
    shared = _hand(runs, {"Iyy": "swing-x", "Izz": "swing-x", "Ixx": "torsion"})
    assert {n for n, _ in violations(shared, c, None, ["Ixx", "Izz"])} == {"slack", "max_depth", "max_tension"}
    # no run counted (nothing ranked has a mode): the figures at rest, no slack
    assert guarded_limits(p, []) == {"peak": 1.0, "depth": 1.0, "slack_wires": [], "left_out": ["swing-x", "torsion"]}
    # a point from before the per-run figures (a resumed journal): its own figures, every run
    old = _hand(runs, {"Iyy": "swing-x", "Izz": "torsion"})
    del old["depth"]["by_mode"]
    assert guarded_limits(old, ["Izz"])["peak"] == 3.0 and violations(old, c, None, ["Izz"])


def test_the_advice_leaves_out_a_set_aside_components_mode(c04, monkeypatch):
    """How to time and the amplitude advice at 0.04: the roll (Ixx) and the
    torsion (Izz), not Iyy's swing ("swing-x ... for Iyy, 50 cycles per
    trial" before).  The amplitude advice is recorded, not computed (0.8 s):
    it gets the point with the counted components only.  Fails with the
    advice of every component (among not passed or not applied)."""
    import bifilar.studies.amplitude as amp
    from bifilar.studies.recommend import point_advice

    cfg, path, st, pts = c04
    got = []
    monkeypatch.setattr(amp, "amplitude_advice", lambda cfg, source, point, settings: got.append(point) or {})
    a = point_advice(pts[0], cfg, path, st, 0.1, None, None, ["Ixx", "Izz"])
    assert [(r["mode"], r["components"]) for r in a["how_to_time"]] == [("roll", ["Ixx"]), ("torsion", ["Izz"])]
    assert list(got[0]["components"]) == ["Ixx", "Izz"] and got[0]["periods"] == pts[0]["periods"]
    every = point_advice(pts[0], cfg, path, st, 0.1, None)  # no ranking given: every mode, as before
    assert [r["mode"] for r in every["how_to_time"]] == ["roll", "swing-x", "torsion"]
    assert list(got[1]["components"]) == ["Ixx", "Iyy", "Izz"]
