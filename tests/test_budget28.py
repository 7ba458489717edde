"""Session 28 (budget28): a sweep point's components share the per-scene
half of their linear budgets' input columns (``budget.SceneInputs``): the
same numbers as each component's own columns, bit for bit.

* ``honest_stds`` of the Solar Boat (spacing 3, Ixx Iyy Izz), the drone
  and audit27's drawn a03 (each component at its best mode), as shipped
  and with every budget forced to second order (so every input's column
  and quadratic reaches the std, as tests/test_fixed28.py does): every
  ``input_columns`` answer, every linear budget (covariance, contributions,
  T_lin, gain), every second-order budget and the stds, against the
  per-component path (``scene_inputs`` returning None: the code before);
* ``SceneInputs.rows`` declines what is not its problem (an amplitude
  factor not exactly 1, other ``unc``, another scene).
"""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.estimation import budget as bm
from bifilar.estimation import second_order as so

from conftest import CONFIGS


def _bits(x) -> bytes:
    return np.asarray(x, float).tobytes()


def _scenes():
    from bifilar.config import read_yaml, scene_from_dict
    from bifilar.studies.shorthands import apply_params

    boat = apply_params(read_yaml(CONFIGS / "solar_boat.yaml"), {"spacing": 3.0}, "boat")[0]
    drawn = CONFIGS.parent / "tests" / "data" / "audit27" / "a03_drawn.yaml"
    return {"Solar Boat": scene_from_dict(boat, "boat", warn=False),
            "drone": scene_from_dict(read_yaml(CONFIGS / "drone_parallel.yaml"), "drone", warn=False),
            "a03_drawn": scene_from_dict(read_yaml(drawn), "a03", warn=False)}


def _runs(monkeypatch, name: str, forced: bool, shared: bool, used: list) -> list:
    """Everything the honest stds of scene ``name`` compute on the way, as bytes."""
    from bifilar.estimation import honest, invert
    from bifilar.estimation.sensitivity import best_mode_for, period_sensitivity
    from bifilar.estimation.uncertainty import default_uncertainty

    seen: list = []
    real_cols, real_budget, real_so, real_rows = bm.input_columns, bm._budget, so.second_order, bm.SceneInputs.rows

    def cols(*a, **k):
        out = real_cols(*a, **k)
        seen.append(("cols", [(key, _bits(v)) for key, v in out[0].items()], sorted(out[1].items()), out[2]))
        return out

    def budget(*a, **k):
        b, deg, T_lin, ctx = real_budget(*a, **k)
        seen.append(("budget", _bits(b.covariance), [(key, _bits(v)) for key, v in b.contributions.items()],
                     deg, _bits(T_lin), _bits(ctx.gain), list(ctx.inputs), sorted(ctx.sigmas.items())))
        return b, deg, T_lin, ctx

    def second(*a, **k):
        b, failed = real_so(*a, **k)
        seen.append(("2nd", _bits(b.covariance), [(key, _bits(v)) for key, v in b.contributions.items()], failed))
        return b, failed

    def rows(self, *a, **k):
        idx = real_rows(self, *a, **k)
        used.append(idx is not None)
        return idx

    monkeypatch.setattr(bm, "input_columns", cols)
    monkeypatch.setattr(bm, "_budget", budget)
    monkeypatch.setattr(invert, "_budget", budget)
    monkeypatch.setattr(so, "second_order", second)
    monkeypatch.setattr(invert, "second_order", second)
    monkeypatch.setattr(bm.SceneInputs, "rows", rows)
    if not shared:
        from bifilar.estimation import honest as hn

        monkeypatch.setattr(hn, "scene_inputs", lambda *a, **k: None)
    if forced:
        monkeypatch.setattr(so, "LINEAR_ENOUGH", 0.0)
        monkeypatch.setattr(so, "OFFSET_ENOUGH", 0.0)
    scene = _scenes()[name]
    sens = period_sensitivity(scene)
    unc = default_uncertainty()
    req = [(c, best_mode_for(sens, c) + 1) for c in ("Ixx", "Iyy", "Izz")]
    out = honest.honest_stds(scene, req, unc, unc["timing"], rest=sens.rest, sens=sens)
    seen.append(("stds", _bits(out)))
    monkeypatch.undo()
    return seen


@pytest.mark.parametrize("name", ["Solar Boat", "drone", "a03_drawn"])
def test_shared_input_columns_equal_each_components_own(monkeypatch, name):
    for forced in (False, True):
        used: list = []
        got = _runs(monkeypatch, name, forced, True, used)
        # the shared columns served every component (the first included)
        assert used.count(True) == 3, used
        ref = _runs(monkeypatch, name, forced, False, [])
        assert [s[0] for s in got] == [s[0] for s in ref] and got == ref
        if forced:  # every budget went to second order: every input's column reached a std
            assert sum(s[0] == "2nd" and any(k.endswith("(2nd order)") for k, _ in s[2]) for s in got) >= 1


def test_scene_inputs_decline_what_is_not_their_problem():
    from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
    from bifilar.estimation.problem import build_problem
    from bifilar.estimation.uncertainty import default_uncertainty

    scene = _scenes()["Solar Boat"]
    unc = default_uncertainty()
    meas = MeasurementSet([Hanging("ref", scene, np.eye(3))], [Measurement("torsion", 1.9, 1e-3, "period", "--period")])
    pb = build_problem(meas, ["Izz"], unc)
    vals = pb.values(pb.prior)
    si = bm.scene_inputs(pb, vals, unc, {})
    assert si.rows(pb, vals, np.ones(1), unc) is not None
    a = bm.input_columns(pb, vals, np.ones(1), unc, {}, shared=si)
    b = bm.input_columns(pb, vals, np.ones(1), unc, {})
    assert [(k, _bits(v)) for k, v in a[0].items()] == [(k, _bits(v)) for k, v in b[0].items()] and a[1] == b[1]
    assert si.rows(pb, vals, np.array([1.0 + 2e-16]), unc) is None  # r not exactly 1: (J r) c != (J c) r
    assert si.rows(pb, vals, np.ones(1), {**unc, "length": 2 * unc["length"]}) is None
    other = dict(vals, Izz=vals["Izz"] * 1.01)
    assert si.rows(pb, other, np.ones(1), unc) is None


def test_taken_at_once_the_entries_are_the_loops_products():
    # _columns fills a column's measured entries with one fancy-indexed product where every mode matched:
    # the same IEEE products as the per-entry loop before (no reduction), amplitude factors r != 1 included
    rng = np.random.default_rng(28)
    J = rng.standard_normal((7, 5)) * 10.0 ** rng.uniform(-9, 9, (7, 5))
    r = 1.0 + rng.standard_normal(4) * 1e-3
    ka, ra = np.array([0, 1, 2, 3]), np.array([3, 0, 6, 3])
    for j in range(5):
        col = np.zeros(4)
        col[ka] = J[ra, j] * r[ka]
        loop = np.zeros(4)
        for k in range(4):
            loop[k] = J[ra[k], j] * r[k]
        assert col.tobytes() == loop.tobytes()
