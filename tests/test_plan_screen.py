"""`plan` searches on screen points and confirms the best in full
(bifilar.studies.plan, "Screens and confirmation"): its answer must be the
one the search on full points gives, both where the linear budget holds
(the Solar Boat: the screens' path is the full one) and where it does not
(the shallow-CoM wheel: second order matters, so the search reruns in full)."""

from __future__ import annotations

import pytest

from bifilar.config import read_yaml
from bifilar.studies import plan as plan_mod
from bifilar.studies import sweep as sw

from conftest import CONFIGS
from test_uncertainty_pins import wheel_cfg


def _full_only(monkeypatch):
    """The search on full points only (screens disabled): the reference."""
    ev, rs = plan_mod.evaluate_point, plan_mod.run_sweep
    monkeypatch.setattr(plan_mod, "evaluate_point", lambda *a, screen=False, **k: ev(*a, **k))
    monkeypatch.setattr(plan_mod, "run_sweep", lambda *a, screen=False, **k: rs(*a, **k))


@pytest.mark.parametrize("case", ["Solar Boat", "shallow wheel"])
def test_screened_plan_equals_the_full_search(case, monkeypatch):
    if case == "Solar Boat":
        cfg, bounds = read_yaml(CONFIGS / "solar_boat.yaml"), [("spacing", 1.0, 4.0)]
        st = sw.resolve_settings(cfg)
    else:  # the CoM 15-45 mm below the attachments: the honest sigma is second order at the shallow end
        cfg, bounds = wheel_cfg(), [("height", 0.015, 0.045)]
        st = sw.resolve_settings(cfg, components=("Izz",), tensions=False)
    kw = {"target": None, "max_local": 4}
    screened = plan_mod.plan(cfg, case, bounds, st, sw.Constraints(), **kw)
    with monkeypatch.context() as m:
        _full_only(m)
        full = plan_mod.plan(cfg, case, bounds, st, sw.Constraints(), **kw)
    assert screened.best["params"] == full.best["params"]
    assert screened.best["objective"] == full.best["objective"]
    assert not screened.best.get("screen")
    assert screened.to_json() == full.to_json()
    if case == "shallow wheel":
        # the linear sigma would have misled the screens: the honest one differs at the optimum
        lin = sw.evaluate_point(cfg, case, screened.best["params"], st, screen=True)
        assert lin["components"]["Izz"]["sigma"] != screened.best["components"]["Izz"]["sigma"]
