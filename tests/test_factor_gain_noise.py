"""The factor gain ``g = r + T_lin dr/dI dI/dT`` of a stated amplitude must
not rest on integration noise (docs/design.md, "drdi, session 13").  The
6.4 cylinder's Ixx is timed on its swing-y, whose period Ixx barely moves
(``T_lin dI/dT`` ~ 1.7e6 kg m^2): the forward difference ``dr/dI`` over
the 1e-4 step (1.4e-3 kg m^2) of the sweep's runs (3 periods, rtol 1e-8)
was -1.7e-7, the converged value 2.6e-10, so the gain was 0.713 instead of
1.0004 and the sweep's sigma 313.7 kg m^2 against ~223.7.  Now the two runs
of a difference whose noise could move the gain by more than
``FACTOR_GAIN_NOISE`` are run again at a tighter rtol, in the sweep and in
invert by the same rule (``solve.factor_step_rtol``)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from bifilar.analysis.batch import simulate_batch
from bifilar.analysis.equilibrium import rest_pose
from bifilar.config import load_scene, read_yaml
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
from bifilar.estimation.solve import FACTOR_GAIN_NOISE, factor_step_rtol
from bifilar.studies import sweep as sw

from conftest import CONFIGS

CYL = CONFIGS / "thesis_cylinder_6_4.yaml"
A = 0.05


@pytest.fixture(scope="module")
def converged():
    """(r, T_lin, T_lin dI/dT, dr/dIxx) of the cylinder's swing-y at 0.05,
    independent of the code under test's difference: central differences
    over Ixx +- 1e-2 of the largest moment (0.14 kg m^2) of runs at rtol
    1e-12 (measured: 2.61e-10 from 3 and 10 periods, steps 1e-3 and 1e-2,
    against 2.3e-10 .. 2.7e-10 at tighter steps, where rounding shows), and
    dT_lin/dIxx from the same scenes' linear periods."""
    scene = load_scene(CYL)
    rest = rest_pose(scene)
    h = 1e-2 * float(np.max(np.linalg.eigvalsh(scene.inertia)))
    scenes = []
    for s in (-1, 0, 1):
        inertia = np.array(scene.inertia, float)
        inertia[0, 0] += s * h
        scenes.append(replace(scene, inertia=inertia))
    runs = simulate_batch(scenes, mode="swing-y", amplitude=A, periods=3, rtol=1e-12, health=False)
    r = [x.period / x.linear_period for x in runs]
    T_lin = runs[1].linear_period
    dT_dI = (runs[2].linear_period - runs[0].linear_period) / (2 * h)
    return r[1], T_lin, T_lin / dT_dI, (r[2] - r[0]) / (2 * h)


def test_rule_asks_for_a_tighter_rtol_only_where_the_noise_matters():
    # noise bound T_lin rtol / (h |dT/dp|) against FACTOR_GAIN_NOISE: the cylinder's Ixx 11.8 (asks for
    # 1e-8 x 0.01 / 11.8), a boat-like component 2.7e-3 (nothing)
    assert factor_step_rtol(1e-8, 8.55, 8.55 / 1.65e6, 1.4e-3) == pytest.approx(1e-8 * FACTOR_GAIN_NOISE / 11.8,
                                                                                  rel=0.01)
    assert factor_step_rtol(1e-8, 2.0, 2.0 / 3.7e2, 1.4e-3 * 1.0) is None
    assert factor_step_rtol(1e-8, 8.55, 8.55 / 1.65e9, 1.4e-3) == 1e-12  # the floor
    assert factor_step_rtol(1e-8, 8.55, 0.0, 1.4e-3) is None


def test_cylinder_ixx_gain_and_sigma_agree_between_sweep_invert_and_converged(converged):
    r_conv, T_lin, TdI_dT, dr = converged
    g_conv = r_conv + TdI_dT * dr  # 1.0004
    cfg = read_yaml(CYL)
    st = sw.resolve_settings(cfg, components=["Ixx"], amplitude=A)
    e = sw.evaluate_point(cfg, str(CYL), {}, st)["components"]["Ixx"]
    assert e["mode"] == "swing-y"
    ab = e["amplitude_budget"]
    # the gain's stated accuracy is FACTOR_GAIN_NOISE (measured 1.2e-3 at the floor's rtol); was 0.713
    assert ab["factor_gain"] == pytest.approx(g_conv, abs=FACTOR_GAIN_NOISE)

    # invert (10 cycles, rtol 1e-10, DOP853) of the period the body shows at 0.05, the same rule
    T = T_lin * r_conv
    ms = MeasurementSet([Hanging("reference", load_scene(CYL), np.eye(3))],
                        [Measurement("swing-y", T, st.unc["timing"], "period", "--period", amplitude=A)])
    ms.uncertainty = dict(st.unc)
    res = invert(ms, solve_for=["Ixx"], ladder=False, unc=dict(st.unc))
    g_inv = res.amplitude_laws[0].factor(A) + TdI_dT * float(res.amplitude_laws[0].dr_dp[0])
    assert g_inv == pytest.approx(g_conv, abs=FACTOR_GAIN_NOISE)
    # the sigma goes as 1/g in its timing share (75 %): both within ~1 % of each other (0.1 % measured;
    # was 313.7 against 223.7, +40 %), and of the small-amplitude sigma at g = 1.0004
    assert e["sigma"] == pytest.approx(res.sigma("Ixx"), rel=0.02)
    assert e["sigma"] == pytest.approx(ab["sigma_small_amplitude"], rel=0.02)


def test_invert_law_takes_dr_dp_from_the_tighter_pair_only_where_the_rule_asks(monkeypatch):
    # stated_amplitude_law with the runs replaced: unknown 0's period hardly moves (dT/dp 1e-6 s per unit:
    # bound 2 rtol / (1e-4 x 1e-6) = 2e2 at rtol 1e-10), unknown 1's does (1 s per unit: 2e-6); only
    # unknown 0's dr/dp comes from the pair rerun at factor_step_rtol's rtol
    from types import SimpleNamespace as NS

    import bifilar.estimation.solve as so

    calls = iter([1.00162, 1.0021, 1.0019])  # the 0.9 A run, then one per unknown stepped
    monkeypatch.setattr(so, "measured_factor", lambda pb, k, p, rtol=1e-10, amplitude=None: (next(calls), None, 0.0))
    tight = []

    def unchecked(pb, k, p, rtol):
        tight.append(rtol)
        return 1.002 + 3e-9 * float(p[0] - 1.0) / so.FACTOR_STEP  # r at p, and at p[0] + h: +3e-9

    monkeypatch.setattr(so, "_unchecked_factor", unchecked)
    pb = NS(measurements=[NS(amplitude=0.3)], scales=lambda: np.ones(2), linear_periods=lambda p: np.array([2.0]),
            jacobian=lambda p: np.array([[1e-6, 1.0]]))
    law = so.stated_amplitude_law(pb, np.array([1.0, 2.0]), 0, 1.002)
    assert law.dr_dp == pytest.approx([3e-9 / so.FACTOR_STEP, (1.0019 - 1.002) / so.FACTOR_STEP], rel=1e-6)
    assert tight == [pytest.approx(so.factor_step_rtol(1e-10, 2.0, 1e-6, so.FACTOR_STEP))] * 2


# ---- gainnoise, session 13: where even the floor's rtol cannot bound the noise, a wider step does ----

def _window_cylinder(tmp_path):
    """The 6.4 cylinder with Ixx = 3 kg m^2 (its admissible range 2.0 .. 26.1) and the short wire 18.5 m
    (was 17.658): swing-y's T_lin dI/dT = 1.68e7 kg m^2, so d ln T / d ln(Ixx / Imax) = 8.3e-7 -- under
    the sweep's identifiability (1e-6) but invert accepts Ixx (its period changes by more than 1e-6 over
    the range, whose far end is 1.6 Imax away) -- and the bound at the floor's rtol over FACTOR_STEP is
    1.2e-2, above FACTOR_GAIN_NOISE."""
    text = CYL.read_text().replace("lengths:     [19.62, 17.658]", "lengths:     [19.62, 18.5]").replace(
        "principal: [14.03443125, 14.03443125, 12.0295125]", "principal: [3.0, 14.03443125, 12.0295125]")
    assert "18.5]" in text and "[3.0," in text
    path = tmp_path / "cylinder_window.yaml"
    path.write_text(text)
    return path


def test_the_floor_widens_the_step_where_rtol_alone_cannot_bound_the_noise():
    from bifilar.estimation.solve import (FACTOR_FLOOR_MARGIN, FACTOR_RTOL_FLOOR, FACTOR_STEP, FACTOR_STEP_MAX,
                                          factor_step)

    h = FACTOR_STEP * 14.03  # the cylinder's step, kg m^2
    # reachable by rtol alone (the cylinder's own Ixx, T_lin dI/dT 1.65e6): the step stays
    assert factor_step(1e-8, 8.55, 8.55 / 1.65e6, h) == (factor_step_rtol(1e-8, 8.55, 8.55 / 1.65e6, h), h)
    assert factor_step(1e-8, 2.0, 2.0 / 3.7e2, h) is None
    # the window case (T_lin dI/dT 1.68e7): at the floor over h the bound is 1.2e-2; the wider step brings
    # it FACTOR_FLOOR_MARGIN under FACTOR_GAIN_NOISE
    rtol, step = factor_step(1e-10, 8.77, 8.77 / 1.68e7, h)
    assert rtol == FACTOR_RTOL_FLOOR
    assert 8.77 * rtol / (step * 8.77 / 1.68e7) == pytest.approx(FACTOR_GAIN_NOISE / FACTOR_FLOOR_MARGIN, rel=1e-9)
    # a period that all but ignores the unknown: the step stops at FACTOR_STEP_MAX of the scale
    assert factor_step(1e-10, 8.77, 8.77 / 1.68e12, h)[1] == pytest.approx(h * FACTOR_STEP_MAX / FACTOR_STEP)


def test_the_sweeps_identifiable_components_never_need_the_wider_step():
    # the sweep refuses a component with |d ln T / d ln I| < IDENTIFIABLE_MIN at its scale (<= the largest
    # moment, the step's scale), so its bound at the floor is at most FLOOR / (FACTOR_STEP IDENTIFIABLE_MIN):
    # no wider than FACTOR_GAIN_NOISE while these constants keep this relation (they meet exactly now)
    from bifilar.estimation.solve import FACTOR_RTOL_FLOOR, FACTOR_STEP
    from bifilar.studies.point import IDENTIFIABLE_MIN

    assert FACTOR_RTOL_FLOOR / (FACTOR_STEP * IDENTIFIABLE_MIN) <= FACTOR_GAIN_NOISE * (1 + 1e-9)


def test_invert_law_takes_the_floor_pair_over_the_wider_step(monkeypatch):
    # as test_invert_law_takes_dr_dp_from_the_tighter_pair_only_where_the_rule_asks, but unknown 0's period
    # moves so little (dT/dp 1e-7 s per unit: bound 0.2 at the floor over FACTOR_STEP) that the pair is run
    # at the floor over the step factor_step widens it to (main took it over FACTOR_STEP: bound 0.2)
    from types import SimpleNamespace as NS

    import bifilar.estimation.solve as so

    calls = iter([1.00162, 1.0021, 1.0019])
    monkeypatch.setattr(so, "measured_factor", lambda pb, k, p, rtol=1e-10, amplitude=None: (next(calls), None, 0.0))
    pairs = []

    def unchecked(pb, k, p, rtol):
        pairs.append((rtol, float(p[0])))
        return 1.002 + 3e-5 * float(p[0] - 1.0)  # dr/dp0 = 3e-5 exactly, whatever the step

    monkeypatch.setattr(so, "_unchecked_factor", unchecked)
    pb = NS(measurements=[NS(amplitude=0.3)], scales=lambda: np.ones(2), linear_periods=lambda p: np.array([2.0]),
            jacobian=lambda p: np.array([[1e-7, 1.0]]))
    law = so.stated_amplitude_law(pb, np.array([1.0, 2.0]), 0, 1.002)
    rtol, step = so.factor_step(1e-10, 2.0, 1e-7, so.FACTOR_STEP)
    assert step > 10 * so.FACTOR_STEP
    assert pairs == [(rtol, pytest.approx(1.0 + step, rel=1e-12)), (rtol, 1.0)]
    assert 2.0 * rtol / (step * 1e-7) <= FACTOR_GAIN_NOISE
    assert law.dr_dp[0] == pytest.approx(3e-5, rel=1e-6)


def test_wider_step_gain_agrees_with_the_converged_one(tmp_path):
    # the window cylinder: the forward difference at factor_step's (rtol, step) against central differences
    # at rtol 1e-12 over 3e-3 of the largest moment (converged: 1.00112, 1.00101 .. 1.00115 over steps 1e-3 ..
    # 1e-2 and 3 or 10 periods); measured 1.00170 (step 1.2e-3 of the moment), within the stated 1e-2
    from bifilar.estimation.solve import FACTOR_STEP, factor_step

    scene = load_scene(_window_cylinder(tmp_path))
    Imax = float(np.max(np.linalg.eigvalsh(scene.inertia)))

    def stepped(d):
        inertia = np.array(scene.inertia, float)
        inertia[0, 0] += d
        return replace(scene, inertia=inertia)

    hc = 3e-3 * Imax
    ref = simulate_batch([stepped(-hc), scene, stepped(hc)], mode="swing-y", amplitude=A, periods=3, rtol=1e-12,
                         health=False)
    r = [x.period / x.linear_period for x in ref]
    T_lin = ref[1].linear_period
    dT_dI = (ref[2].linear_period - ref[0].linear_period) / (2 * hc)
    g_conv = r[1] + T_lin / dT_dI * (r[2] - r[0]) / (2 * hc)
    rtol, step = factor_step(1e-10, T_lin, dT_dI, FACTOR_STEP * Imax)
    assert step > FACTOR_STEP * Imax  # the floor alone would not do
    own, up = simulate_batch([scene, stepped(step)], mode="swing-y", amplitude=A, periods=3, rtol=rtol, health=False)
    dr = (up.period / up.linear_period - own.period / own.linear_period) / step
    assert r[1] + T_lin / dT_dI * dr == pytest.approx(g_conv, abs=FACTOR_GAIN_NOISE)
