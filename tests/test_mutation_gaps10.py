"""Tests written to kill surviving mutants of round 10 (docs/mutation.md,
"Round 10"): session 9's code -- the decaying record's amplitude law
(``bifilar/estimation/signal_law.py``), the period's error bound and the
irregular-motion check (``bifilar/analysis/run_accuracy.py``), a sweep
point's stated-amplitude budget (``bifilar/studies/point_amplitude.py``),
the Monte Carlo factor following dr/dp (``bifilar/estimation/montecarlo.py``),
the barely determined unknowns (``bifilar/estimation/roots.py``) and the
config's uncertainty block (``bifilar/estimation/measurements.py``).

Truths: closed forms worked out in the comments (a least-squares std from a
diagonal Jacobian, the documented bounds and rules of the module
docstrings), records written here from their own laws -- never output of
the code under test pasted in.  Each test runs in well under 2 s.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bifilar.estimation.roots import loosely_determined

# ---------------------------------------------------------------------------
# roots.py: the unknowns the periods barely determine
# ---------------------------------------------------------------------------


class _LinearProblem:
    """A stand-in for :class:`~bifilar.estimation.problem.Problem` with a
    diagonal Jacobian: unknown ``j`` moves only period ``j``, by ``slopes[j]``
    s per unit, timed to ``sigmas[j]`` s, so its timing-only least-squares std
    is ``sigmas[j] / |slopes[j]|`` (J^T J diagonal)."""

    def __init__(self, names, slopes, sigmas, scales):
        self.unknowns = list(names)
        self.measurements = [SimpleNamespace(std=s) for s in sigmas]
        self._J = np.diag(np.asarray(slopes, float))
        self._scales = np.asarray(scales, float)

    def jacobian(self, p):
        return self._J.copy()

    def scales(self):
        return self._scales.copy()


def test_an_unknown_is_loose_above_a_tenth_of_its_scale():
    # stds 1e-3 / slope: 0.09 and 0.11 of the unit scale (the documented tenth, LOOSE_UNKNOWN);
    # only the second is named, with its std
    pb = _LinearProblem(["Izz", "Ixx"], [1e-3 / 0.09, 1e-3 / 0.11], [1e-3, 1e-3], [1.0, 1.0])
    loose = loosely_determined(pb, [0.0, 0.0])
    assert [n for n, _ in loose] == ["Ixx"]
    assert loose[0][1] == pytest.approx(0.11, rel=1e-9)
    # the same stds against a scale of 0.5: 0.18 and 0.22 of it, both named
    pb = _LinearProblem(["Izz", "Ixx"], [1e-3 / 0.09, 1e-3 / 0.11], [1e-3, 1e-3], [0.5, 0.5])
    assert {n for n, _ in loosely_determined(pb, [0.0, 0.0])} == {"Izz", "Ixx"}


def test_loose_unknowns_come_largest_relative_std_first():
    # com.x: std 0.5 m on a scale of 1 m (0.5 of it); com.y: std 0.3 m on 0.1 m (3 of it).  By the
    # std relative to the scale com.y comes first, though its std is the smaller (by std alone, or by
    # std times scale -- 0.5 against 0.03 -- com.x would)
    pb = _LinearProblem(["com.x", "com.y"], [1e-3 / 0.5, 1e-3 / 0.3], [1e-3, 1e-3], [1.0, 0.1])
    loose = loosely_determined(pb, [0.0, 0.0])
    assert [n for n, _ in loose] == ["com.y", "com.x"]
    assert [s for _, s in loose] == pytest.approx([0.3, 0.5], rel=1e-9)


# ---------------------------------------------------------------------------
# measurements.py / cmd_invert: the config's uncertainty block under invert
# ---------------------------------------------------------------------------


def _boat_config(tmp_path, name, unc):
    import yaml

    from conftest import CONFIGS

    cfg = yaml.safe_load((CONFIGS / "solar_boat.yaml").read_text())
    cfg.pop("uncertainty", None)
    if unc is not None:
        cfg["uncertainty"] = unc
    p = tmp_path / name
    p.write_text(yaml.safe_dump(cfg))
    return p


def _invert_cli(*args):
    from click.testing import CliRunner

    from bifilar.cli import main

    return CliRunner().invoke(main, ["invert", *map(str, args)])


INVERT_IZZ = ["--amplitude", "0", "--solve-for", "Izz", "--json"]


@pytest.mark.parametrize("block", [0.001, [0.001, 0.002], "timing=0.001"])
def test_an_uncertainty_block_that_is_no_mapping_exits_2_naming_it(tmp_path, block):
    # docs/errors.md: one line naming the field, exit 2 (without the check: exit 1, "internal error
    # (TypeError ...)" for a number, another field's wording for a list)
    res = _invert_cli(_boat_config(tmp_path, "c.yaml", block), "--period", "torsion=2.0+-0.001", *INVERT_IZZ)
    assert res.exit_code == 2, res.output
    assert "error: uncertainty: must be a mapping" in res.output and "Traceback" not in res.output


def test_the_timing_flag_overrides_the_blocks_for_a_period_without_its_std(tmp_path):
    # the block states timing 5 ms, --uncertainty timing=0.001: a --period without +- takes the flag's
    # 1 ms (README: invert budgets the block *below* its --uncertainty flags), so Izz's std is the one of
    # the period given with +-0.001 on a config without a block
    import json

    stated = _boat_config(tmp_path, "stated.yaml", {"timing": 0.005})
    plain = _boat_config(tmp_path, "plain.yaml", None)
    a = _invert_cli(stated, "--period", "torsion=2.0", "--uncertainty", "timing=0.001", *INVERT_IZZ)
    b = _invert_cli(plain, "--period", "torsion=2.0+-0.001", *INVERT_IZZ)
    c = _invert_cli(stated, "--period", "torsion=2.0", *INVERT_IZZ)
    assert a.exit_code == b.exit_code == c.exit_code == 0, (a.output, b.output, c.output)
    sa, sb, sc = (json.loads(r.stdout)["inertia"]["Izz"]["std"] for r in (a, b, c))
    assert sa == pytest.approx(sb, rel=1e-9)
    assert sc > 3 * sb  # the block's 5 ms itself is used without the flag (the test can tell)


# ---------------------------------------------------------------------------
# signal_law.py: which amplitude law is a pendulum's, which other oscillations go with it
# ---------------------------------------------------------------------------

CH_T0, CH_C, CH_A0, CH_Q, CH_CYCLES = 1.3, 1 / 16, 0.5, 100.0, 40
CH_F0 = 1 / CH_T0
CH_BIN = 1 / (CH_CYCLES * CH_T0)  # periodogram bin of the record, Hz


def _chirp(d_over_c2=0.0, others=(), t_start=0.0, noise=1e-4, seed=1):
    """A decaying record (rad) whose frequency is ``w0 (1 - c A^2 + (c^2 - d) A^4)``, the series of
    ``T = T0 (1 + c A^2 + d A^4)`` to A^4, with A = A0 exp(-sigma tau), Q = 100, 40 cycles at 30 Hz: with
    ``u = (A / A0)^2`` the law's ``beta = -w0 c A0^2``, ``beta2 = w0 (c^2 - d) A0^4``, so ``beta2 w0 / beta^2 =
    1 - d / c^2`` exactly.  The phase is integrated in closed form (int_0^tau exp(-k s) ds = (1 - exp(-k
    tau)) / k); ``others``: (Hz, amplitude / A0) undamped cosines; white noise of ``noise`` A0; time from
    ``t_start``.  Returns t, y and the law's period (s) at an amplitude."""
    rng = np.random.default_rng(seed)
    w0 = 2 * math.pi / CH_T0
    sg = w0 / (2 * CH_Q)
    d = d_over_c2 * CH_C**2
    tau = np.arange(0.0, CH_CYCLES * CH_T0, 1 / 30.0)

    def E(k):
        return (1 - np.exp(-k * tau)) / k

    ph = w0 * tau - w0 * CH_C * CH_A0**2 * E(2 * sg) + w0 * (CH_C**2 - d) * CH_A0**4 * E(4 * sg) + 0.3
    y = CH_A0 * np.exp(-sg * tau) * np.cos(ph)
    for f, a in others:
        y = y + a * CH_A0 * np.cos(2 * math.pi * f * tau + 1.1)
    y = y + noise * CH_A0 * rng.standard_normal(tau.size)

    def T_of(A):
        return 2 * math.pi / (w0 * (1 - CH_C * A**2 + (CH_C**2 - d) * A**4))

    return tau + t_start, y, T_of


@pytest.mark.parametrize("d_over_c2", [0.0, -0.5, 1.5, -1.5, 3.0])
def test_the_amplitude_law_is_used_only_for_a_pendulums_a4_term(d_over_c2):
    # AMPLITUDE_LAW_D_RANGE: T = T0 (1 + c A^2 + d A^4) is a pendulum's for d / c^2 in -1 .. 2 (the
    # fit's beta2 w / beta^2 = 1 - d / c^2 within -1 .. 2, noise here leaving its std ~1e-3 of that
    # unit).  Inside (0: a period linear in A^2; -0.5; 1.5) the law is used and the period at
    # amplitude_period is the generator's there; outside (-1.5, 3) it is refused for its A^4 term
    from bifilar.estimation.signal import AMPLITUDE_LAW_MODEL, fit_period

    t, y, T_of = _chirp(d_over_c2)
    fit = fit_period(t, y, model="auto")
    law = fit.amplitude_law
    assert law["curvature_ratio"] == pytest.approx(1 - d_over_c2, abs=0.05)  # the fit sees the generator's law
    inside = -1.0 <= d_over_c2 <= 2.0
    assert law["used"] is inside, law["reason"]
    if inside:
        assert fit.model == AMPLITUDE_LAW_MODEL
        assert abs(fit.period - T_of(fit.amplitude_period)) < 4 * fit.std
    else:
        assert "A^4 term" in law["reason"] and fit.model != AMPLITUDE_LAW_MODEL


@pytest.mark.parametrize("t_start", [0.0, 1000.0])
@pytest.mark.parametrize("name, others, fitted", [
    # OTHER_BINS: another oscillation 4.5 bins from the fundamental (or from zero) is the rig's and is
    # fitted with the law; 2 bins from either is the law's own misfit and is not
    ("4.5 bins above f0", [(CH_F0 + 4.5 * CH_BIN, 0.01)], [CH_F0 + 4.5 * CH_BIN]),
    ("2 bins above f0", [(CH_F0 + 2 * CH_BIN, 0.01)], []),
    ("4.5 bins above zero", [(4.5 * CH_BIN, 0.01)], [4.5 * CH_BIN]),
    ("2 bins above zero", [(2 * CH_BIN, 0.01)], []),
    # OTHER_MAX_RATIO: below 4 f0 (3.5 f0) fitted, above (4.5 f0: a hum) not
    ("3.5 f0", [(3.5 * CH_F0, 0.01)], [3.5 * CH_F0]),
    ("4.5 f0", [(4.5 * CH_F0, 0.01)], []),
    # OTHER_MAX: of four, the three strongest
    ("four", [(0.3 * CH_F0, 0.02), (1.7 * CH_F0, 0.015), (2.5 * CH_F0, 0.01), (3.3 * CH_F0, 0.005)],
     [0.3 * CH_F0, 1.7 * CH_F0, 2.5 * CH_F0]),
])
def test_the_law_fits_the_other_oscillations_of_the_documented_band(name, others, fitted, t_start):
    # each oscillation 100x the noise; the record's time origin (t_start) changes nothing: the bands are
    # in bins of the record's length.  The period at amplitude_period stays the generator's
    from bifilar.estimation.signal import fit_period

    t, y, T_of = _chirp(0.0, others, t_start)
    fit = fit_period(t, y, model="auto")
    law = fit.amplitude_law
    assert law["used"], law["reason"]
    got = sorted(o["frequency"] for o in law["other_oscillations"])
    assert len(got) == len(fitted), (name, got)
    for g, f in zip(got, sorted(fitted)):
        assert abs(g - f) < 0.1 * CH_BIN
    # the fit names its own free parameters: the law's c0 (c1 with a drift), a, b, omega, sigma, beta,
    # beta2, then a, b, omega, sigma of each other oscillation (the viscous fit's five were reported)
    drift = ["c1"] if fit.selection["drift"] else []
    others = [f"{nm}{k}" for k in range(2, 2 + len(fitted)) for nm in ("a", "b", "omega", "sigma")]
    assert fit.selection["free_parameters"] == ["c0", *drift, "a", "b", "omega", "sigma", "beta", "beta2", *others]
    assert abs(fit.period - T_of(fit.amplitude_period)) < 4 * fit.std


# ---------------------------------------------------------------------------
# run_accuracy.py: the period's error bound, the drift term, the irregular-motion check
# ---------------------------------------------------------------------------


def test_below_resolution_is_none_where_either_figure_is_undefined():
    # "no larger than its resolution"; None where either is undefined (docstring)
    from bifilar.analysis.run_accuracy import below_resolution

    assert below_resolution(1e-7, 1e-6) is True
    assert below_resolution(1e-6, 1e-6) is True  # equal: no larger (both given, not computed)
    assert below_resolution(1e-5, 1e-6) is False
    for d, r in ((math.nan, 1e-6), (1e-7, math.nan), (math.inf, 1e-6), (math.nan, math.nan)):
        assert below_resolution(d, r) is None, (d, r)


def test_the_tightest_rtol_is_a_hundred_times_the_double_precision():
    # MIN_RTOL: 100 eps = 2.2e-14, itself accepted, 99 eps refused naming --rtol
    from bifilar.analysis.run_accuracy import check_rtol
    from bifilar.errors import InputError

    eps = float(np.finfo(float).eps)
    check_rtol(100 * eps)
    check_rtol(1e-10)
    with pytest.raises(InputError) as e:
        check_rtol(99 * eps)
    assert e.value.field == "--rtol"


def test_too_small_to_time_is_a_microradian_of_wire_angle():
    # MIN_TIMED_ANGLE: 1e-6 rad for a rotation (dominant index 3, 4, 5: rx ry rz), 1e-6 of the longest
    # wire (m) for a translation (0, 1, 2).  On 2 m wires: a rotation of 1.5e-6 rad is timed, a
    # translation of 1.5e-6 m (0.75e-6 rad of wire angle) is not
    from bifilar.analysis.run_accuracy import small_amplitude_period, untimed

    for dominant in (3, 4, 5):
        assert not untimed(1.5e-6, dominant, 2.0)
        assert untimed(0.5e-6, dominant, 2.0)
        T, why = small_amplitude_period(-0.5e-6, dominant, 2.0, 1.9)
        assert T == 1.9 and "below 1e-06 rad the simulated crossings" in why
    for dominant in (0, 1, 2):
        assert untimed(1.5e-6, dominant, 2.0) and not untimed(2.5e-6, dominant, 2.0)
        T, why = small_amplitude_period(1.5e-6, dominant, 2.0, 1.9)
        assert "below 2e-06 m the simulated crossings" in why and "|amplitude| >= 2e-06 m" in why
    assert untimed(0.0) and not untimed(None)
    assert small_amplitude_period(2.5e-6, 0, 2.0, 1.9) is None and small_amplitude_period(0.5e-6, 3, 2.0, None) is None


# ---------------------------------------------------------------------------
# point_amplitude.py: the sigma invert prints with the amplitude stated
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("dTlin_dI, dr_dI, slope", [(0.02, -0.002, 0.025), (-0.02, 0.003, 0.04),
                                                    (0.02, 0.0, None)])
def test_stated_amplitude_budget_is_the_implicit_function_theorem_on_t_lin_times_r(dTlin_dI, dr_dI, slope):
    # invert solves T_lin(I) r(A; I) = T for I: dI = (dT - T_lin (dr/dA) dA) / (dT/dI) with the full
    # derivative dT/dI = r dT_lin/dI + T_lin dr/dI.  So the timing's contribution is s_T / |dT/dI|,
    # the stated amplitude's (s_A = rel A, slope = A dr/dA) T_lin slope rel / |dT/dI|, the inputs' and
    # the second-order excess q^2 of the small-amplitude budget unchanged; shares over the linear terms.
    # slope None: the quadratic rule's A dr/dA = 2 (r - 1)
    from bifilar.estimation.sensitivity import Budget
    from bifilar.studies.point_amplitude import stated_amplitude_budget

    s_T, c_len, q, T_lin, r, rel = 1e-3, 0.03, 0.01, 2.0, 1.01, 0.1
    c_t0 = s_T / abs(dTlin_dI)  # the small-amplitude timing contribution
    b = Budget("Izz", "torsion", math.sqrt(c_t0**2 + c_len**2 + q**2), {"timing": c_t0, "length.0": c_len},
               {}, 1 / dTlin_dI, 0.5)
    sd, c_t, c_a, shares = stated_amplitude_budget(b, T_lin, r, rel, slope, dr_dI)
    dT_dI = r * dTlin_dI + T_lin * dr_dI
    A_dr_dA = 2 * (r - 1) if slope is None else slope
    t_exp, a_exp = s_T / abs(dT_dI), T_lin * A_dr_dA * rel / abs(dT_dI)
    assert c_t == pytest.approx(t_exp, rel=1e-12) and c_a == pytest.approx(a_exp, rel=1e-12)
    assert sd == pytest.approx(math.sqrt(c_len**2 + q**2 + t_exp**2 + a_exp**2), rel=1e-12)
    tot = t_exp**2 + a_exp**2 + c_len**2
    assert shares == pytest.approx({"timing": t_exp**2 / tot, "length.0": c_len**2 / tot, "amplitude": a_exp**2 / tot},
                                   rel=1e-12)
    if dr_dI == 0.0 and slope is None:  # the defaults: no derivative in I, the quadratic rule
        assert stated_amplitude_budget(b, T_lin, r, rel)[:3] == pytest.approx((sd, c_t, c_a), rel=1e-12)


# ---------------------------------------------------------------------------
# montecarlo.py: the draws
# ---------------------------------------------------------------------------


def test_a_solved_com_coordinate_is_not_drawn():
    # draw_monte_carlo: a CoM coordinate solved for is re-estimated by every draw, so it is not drawn;
    # the others shift every attachment together by -R dcom, dcom ~ N(0, unc.com) (2 mm).  Only the CoM
    # is uncertain here, so each draw's attachments differ from the config's by one common vector whose
    # x is exactly zero (com.x solved) and whose y, z spread by 2 mm (200 draws: the sample std within
    # 25 %, 5 of its own sd)
    from bifilar.config import read_yaml, scene_from_dict
    from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
    from bifilar.estimation.montecarlo import draw_monte_carlo
    from bifilar.estimation.problem import build_problem

    from conftest import CONFIGS

    scene = scene_from_dict(read_yaml(CONFIGS / "trifilar_kth.yaml"), warn=False)
    ms = MeasurementSet([Hanging("reference", scene, np.eye(3))],
                        [Measurement(lb, 2.0, 1e-3, "period", "--period", amplitude=0.0) for lb in ("torsion", "swing-x")])
    unc = {"length": 0.0, "position": 0.0, "mass": 0.0, "com": 2e-3, "gravity": 0.0, "timing": 1e-3}
    pb = build_problem(ms, ["Izz", "com.x"], unc)
    res = SimpleNamespace(problem=pb, factors=[1.0, 1.0], method="linear", amplitude_laws=[None, None],
                          values=np.asarray(pb.prior, float))
    draws = draw_monte_carlo(res, 200, np.random.default_rng(0))
    shift = np.array([d.hangings[0].scene.attachments - scene.attachments for d in draws])  # (200, 3 wires, 3)
    assert np.max(np.abs(shift - shift[:, :1, :])) < 1e-15  # one vector per draw
    assert np.max(np.abs(shift[:, :, 0])) == 0.0
    assert shift[:, 0, 1:].std(axis=0) == pytest.approx([2e-3, 2e-3], rel=0.25)


def test_period_warn_threshold_is_a_tenth_of_a_stated_timing_else_1e_8_of_the_period():
    from bifilar.analysis.run_accuracy import period_warn_threshold

    assert period_warn_threshold(2.0, 1e-3) == pytest.approx(1e-4, rel=1e-12)
    for timing in (None, 0.0, -1e-3, math.nan, math.inf):
        assert period_warn_threshold(2.0, timing) == pytest.approx(2e-8, rel=1e-12), timing


def test_drift_period_error_is_the_drift_times_the_periods_distance_from_the_linear_one():
    from bifilar.analysis.run_accuracy import drift_period_error

    assert drift_period_error(2.0, 1.9, 0.01) == pytest.approx(1e-3, rel=1e-9)
    assert drift_period_error(1.9, 2.0, 0.01) == pytest.approx(1e-3, rel=1e-9)
    assert drift_period_error(2.0, None, 0.01) == 0.0 and drift_period_error(None, 2.0, 0.01) == 0.0
    assert drift_period_error(2.0, 1.9, math.nan) == 0.0


@pytest.mark.parametrize("method, model, rtol, per_rtol", [
    ("auto", "maximal", 1e-10, 15.0), ("LSODA", "maximal", 1e-10, 8.0), ("DOP853", "maximal", 1e-10, 4.0),
    ("RK45", "maximal", 1e-10, 5.0), ("RK23", "maximal", 1e-9, 7.0), ("Radau", "maximal", 1e-8, 0.05),
    ("BDF", "maximal", 1e-10, 10.0),
    ("DOP853", "kane", 1e-10, 8.0), ("RK45", "kane", 1e-10, 30.0), ("LSODA", "kane", 1e-10, 40.0),
    ("no-such", "maximal", 1e-10, 15.0), ("no-such", "kane", 1e-10, 40.0),  # unmeasured: the largest
    ("auto", "maximal", 1e-15, None),  # below the floor: 1e-12 of the period
])
def test_period_error_is_the_methods_constant_times_rtol_of_the_period(method, model, rtol, per_rtol):
    # PERIOD_ERROR_PER_RTOL(_KANE) and PERIOD_ERROR_FLOOR as documented; T = 2 s, no drift: no warning
    # below 1e-8 of the period (2e-8 s)
    from bifilar.analysis.run_accuracy import period_accuracy

    err, warn = period_accuracy(2.0, method, rtol, model=model)
    rel = 1e-12 if per_rtol is None else per_rtol * rtol
    assert err == pytest.approx(rel * 2.0, rel=1e-12)
    assert warn is None


def test_period_error_adds_the_drifts_part_and_says_where_the_error_comes_from():
    from bifilar.analysis.run_accuracy import period_accuracy

    # 15 x 1e-10 x 2 s = 3e-9 s of integration, plus 1e-6 x |2.0 - 1.9| = 1e-7 s of drift: above 2e-8
    err, warn = period_accuracy(2.0, "auto", 1e-10, linear_period=1.9, drift=1e-6)
    assert err == pytest.approx(3e-9 + 1e-7, rel=1e-12)
    assert "most of it from the energy drift" in warn and "+1.0e-01 s from the linear one" in warn
    # the drift's part alone below the limit: no warning
    err, warn = period_accuracy(2.0, "auto", 1e-10, linear_period=1.9, drift=1e-8)
    assert err == pytest.approx(3e-9 + 1e-9, rel=1e-12) and warn is None


@pytest.mark.parametrize("rtol, timing, cure", [
    # err 15 rtol 2 s = 3e-5 s against 2e-8 s (no timing): rtol x limit / err = 6.7e-10 -> 1e-10, where
    # the error is 3e-9 s, below
    (1e-6, None, "--rtol 1e-10 brings it below"),
    # against a tenth of a 1 ms timing (1e-4 s): 3e-4 s at 1e-5; 1e-5 x 1e-4 / 3e-4 = 3.3e-6 -> 1e-6
    (1e-5, 1e-3, "--rtol 1e-06 brings it below"),
    # a tenth of 1e-12 s: below the floor (1e-12 of the period, 2e-12 s) whatever the rtol
    (1e-10, 1e-12, "no --rtol brings it below"),
])
def test_a_period_error_above_the_limit_names_the_rtol_that_cures_it(rtol, timing, cure):
    from bifilar.analysis.run_accuracy import period_accuracy

    err, warn = period_accuracy(2.0, "auto", rtol, timing=timing)
    assert err == pytest.approx(max(15 * rtol, 1e-12) * 2.0, rel=1e-12)
    assert warn is not None and cure in warn
    assert ("uncertainty.timing" in warn) is (timing is not None)


def test_needs_check_above_a_millionth_of_the_period():
    from bifilar.analysis.run_accuracy import needs_check

    def run(period, std):
        return SimpleNamespace(period=period, period_std=std)

    assert needs_check(run(2.0, 2.2e-6)) and not needs_check(run(2.0, 1.8e-6))
    assert not needs_check(run(None, 1.0)) and not needs_check(run(2.0, None)) and not needs_check(run(2.0, math.nan))


def _checked(diff, *, rtol=1e-10, method="LSODA", atol=None, timing=None, fail=None, period=2.0, model=4e-9):
    """check_period on a fake run (period 2 s, model bound ``model`` s) whose check run differs by ``diff``
    s (None: times no period); returns the run and the check's arguments."""
    from bifilar.analysis.run_accuracy import check_period

    r = SimpleNamespace(period=period, period_std=1e-5, period_error=model, rtol=rtol, method=method, warnings=[],
                        period_check=None)
    calls = []

    def again(m, rt, at):
        calls.append((m, rt, at))
        if fail is not None:
            raise fail
        return SimpleNamespace(period=None if diff is None else period + diff, method=m, rtol=rt)

    check_period(r, again, "auto", atol, timing=timing)
    return r, calls


def test_the_check_runs_at_a_hundredth_of_the_rtol_or_with_the_other_engine():
    r, calls = _checked(1e-9)
    assert calls == [("auto", pytest.approx(1e-12, rel=1e-12), None)]
    r, calls = _checked(1e-9, atol=np.array([1e-8, 2e-8]))
    assert calls[0][2] == pytest.approx([1e-10, 2e-10], rel=1e-12)
    # a hundredth of 1e-12 is below MIN_RTOL (2.2e-14): the other engine at the same rtol and atol
    for method, other in (("LSODA", "DOP853"), ("DOP853", "LSODA")):
        r, calls = _checked(1e-9, rtol=1e-12, method=method, atol=np.array([1e-8]))
        assert calls[0][0] == other and calls[0][1] == 1e-12 and calls[0][2] == pytest.approx([1e-8], rel=1e-12)


@pytest.mark.parametrize("diff, timing, error, warns", [
    (1e-9, None, 4e-9, False),   # within the model's bound: it stands
    (6e-9, None, 6e-9, False),   # 1.5 x the bound, below 2 x and below 1e-8 of the period (2e-8 s)
    (9e-9, None, 9e-9, True),    # 2.25 x the bound: IRREGULAR_FACTOR = 2
    (-9e-9, None, 9e-9, True),   # either side
    (6e-9, 1e-8, 6e-9, True),    # 1.5 x the bound and above a tenth of the stated 1e-8 s timing
    (3e-9, 1e-8, 4e-9, False),   # above a tenth of the timing but within the bound
])
def test_the_check_widens_the_error_to_the_runs_difference_and_warns_beyond_the_documented_factor(
        diff, timing, error, warns):
    r, _ = _checked(diff, timing=timing)
    assert r.period_error == pytest.approx(error, rel=1e-6)
    assert r.period_check["difference"] == pytest.approx(abs(diff), rel=1e-6)
    assert r.period_check["model_bound"] == 4e-9 and r.period_check["period"] == pytest.approx(2.0 + diff)
    got = [w for w in r.warnings if "not regular" in w]
    assert bool(got) is warns
    if warns:
        assert f"{abs(diff) / 4e-9:.3g} x the integration error bound" in got[0]


def test_a_failed_or_periodless_check_keeps_the_models_bound_and_says_so():
    from bifilar.errors import IntegrationError

    r, _ = _checked(1e-9, fail=IntegrationError("step size too small"))
    assert r.period_error == 4e-9 and r.period_check is None
    assert len(r.warnings) == 1 and "failed (step size too small)" in r.warnings[0]
    r, _ = _checked(None)
    assert r.period_error == 4e-9 and r.period_check is None
    assert len(r.warnings) == 1 and "timed no period" in r.warnings[0]


def test_a_factor_draws_slope_is_the_laws_dr_dp_carried_to_the_drawn_amplitude():
    # FactorDraw.slope[k] = w dr/dp / r(A), w = (r(A) - 1) / (r(A0) - 1) (the law's release weight,
    # its docstring), r(A) the factor at the drawn amplitude.  With the period drawn to 1e-12 s, the
    # draw's period is T / r(A), so r(A) is read off each draw -- whatever amplitude it drew -- and the
    # slope follows from the law's factor at A0 and its dr/dp.  A hand-made law with a quartic term
    # (r(0.6) = 1 + 0.3 0.36 + 0.1 0.1296 = 1.121), an inversion's result stubbed around it
    from bifilar.config import read_yaml, scene_from_dict
    from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
    from bifilar.estimation.montecarlo import FactorDraw, draw_monte_carlo
    from bifilar.estimation.problem import build_problem
    from bifilar.estimation.solve import AmplitudeLaw

    from conftest import CONFIGS

    scene = scene_from_dict(read_yaml(CONFIGS / "solar_boat.yaml"), warn=False)
    T, A0 = 2.1, 0.6
    ms = MeasurementSet([Hanging("reference", scene, np.eye(3))],
                        [Measurement("torsion", T, 1e-12, "period", "--period", amplitude=A0)])
    unc = {"length": 0.0, "position": 0.0, "mass": 1e-3, "com": 0.0, "gravity": 0.0, "timing": 1e-12,
           "amplitude": 0.1}
    pb = build_problem(ms, ["Izz"], unc)
    law = AmplitudeLaw(amplitude=A0, a=0.3, b=0.1, dr_dp=np.array([-0.004]))
    r0 = 1 + 0.3 * A0**2 + 0.1 * A0**4
    res = SimpleNamespace(problem=pb, factors=[r0], method="nonlinear", amplitude_laws=[law],
                          values=np.array([scene.inertia[2, 2]]))
    draws = draw_monte_carlo(res, 30, np.random.default_rng(4))
    assert all(isinstance(d, FactorDraw) for d in draws)
    rs = np.array([T / d.measurements[0].period for d in draws])
    assert np.std(rs) > 0.01  # the amplitudes really differ (10 % of 0.6 rad)
    for d, r in zip(draws, rs):
        expected = (r - 1) / (r0 - 1) * -0.004 / r
        assert d.slope[0, 0] == pytest.approx(expected, rel=1e-8)
        # an inertia's unit is m_hat / m_draw (the motion depends on I / m)
        assert d.unit[0] == pytest.approx(scene.mass / d.hangings[0].scene.mass, rel=1e-12)
        assert d.p_ref[0] == res.values[0]
    assert np.std([d.unit[0] for d in draws]) > 5e-4  # the mass really drawn (0.1 %)
    # the linear method, or no stated amplitude: plain draws, the factor held
    for method, amplitude in (("linear", A0), ("nonlinear", 0.0)):
        ms.measurements[0].amplitude = amplitude
        res.method = method
        assert not any(isinstance(d, FactorDraw) for d in draw_monte_carlo(res, 3, np.random.default_rng(4)))


def test_the_drift_resolution_does_not_depend_on_where_the_rig_hangs():
    # drift_resolution: 20 eps m g D over the oscillation energy, D the farthest anchor from the rest
    # CoM.  The whole rig moved 5 m sideways and 3 m up hangs and swings the same (D, the energy), so
    # the resolution is the same; D measured from the origin instead of the CoM would grow ~5x
    from dataclasses import replace

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.analysis.run_accuracy import drift_resolution
    from bifilar.analysis.simulate import initial_state
    from bifilar.config import load_scene

    from conftest import CONFIGS

    out = []
    for shift in ((0.0, 0.0, 0.0), (5.0, 0.0, 3.0)):
        sc = load_scene(CONFIGS / "thesis_plate_rest.yaml")
        sc = replace(sc, anchors=sc.anchors + np.array(shift))
        rest = rest_pose(sc)
        md = linear_modes(sc, rest).get("torsion")
        out.append(drift_resolution(sc, rest, initial_state(sc, rest, md, 0.05)))
    assert np.isfinite(out[0]) and out[0] > 0
    assert out[1] == pytest.approx(out[0], rel=1e-6)


def test_a_com_unknowns_factor_unit_does_not_follow_the_mass():
    # FactorDraw.unit: m_hat / m_draw for an inertia (the motion depends on I / m), 1 for a CoM shift
    # (metres do not scale with the mass).  Izz and com.x from a stated-amplitude torsion and a swing
    from bifilar.config import read_yaml, scene_from_dict
    from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
    from bifilar.estimation.montecarlo import FactorDraw, draw_monte_carlo
    from bifilar.estimation.problem import build_problem
    from bifilar.estimation.solve import AmplitudeLaw

    from conftest import CONFIGS

    scene = scene_from_dict(read_yaml(CONFIGS / "solar_boat.yaml"), warn=False)
    ms = MeasurementSet([Hanging("reference", scene, np.eye(3))],
                        [Measurement("torsion", 2.1, 1e-3, "period", "--period", amplitude=0.3),
                         Measurement("swing-x", 3.0, 1e-3, "period", "--period", amplitude=0.0)])
    unc = {"length": 0.0, "position": 0.0, "mass": 1e-3, "com": 0.0, "gravity": 0.0, "timing": 1e-3,
           "amplitude": 0.1}
    pb = build_problem(ms, ["Izz", "com.x"], unc)
    law = AmplitudeLaw(amplitude=0.3, a=0.3, b=0.0, dr_dp=np.array([-0.004, 0.02]))
    res = SimpleNamespace(problem=pb, factors=[float(law.factor(0.3)), 1.0], method="nonlinear",
                          amplitude_laws=[law, None], values=np.array([scene.inertia[2, 2], 0.0]))
    draws = draw_monte_carlo(res, 10, np.random.default_rng(6))
    assert all(isinstance(d, FactorDraw) for d in draws)
    for d in draws:
        np.testing.assert_allclose(d.unit, [scene.mass / d.hangings[0].scene.mass, 1.0], rtol=1e-12)
        assert np.all(d.slope[1] == 0.0) and np.all(d.slope[0] != 0.0)  # only the stated amplitude's row


def test_a_release_too_small_to_time_claims_the_floor_of_the_period():
    # period_accuracy for a release below MIN_TIMED_ANGLE: its period is the linear one, to within the
    # wire angle squared -- below 1e-12 there, so the bound is PERIOD_ERROR_FLOOR x the period, s.  A
    # translation's angle is metres over the longest wire: 4e-6 m on 5 m wires is 8e-7 rad (4e-6 x 5 =
    # 2e-5 would claim 4e-10)
    from bifilar.analysis.run_accuracy import period_accuracy

    for amplitude, dominant, Lmax in ((5e-7, 3, 1.0), (-9e-7, 5, 5.0), (4e-6, 0, 5.0), (4e-6, 2, 5.0)):
        err, warn = period_accuracy(2.0, "auto", 1e-4, amplitude=amplitude, dominant=dominant, Lmax=Lmax)
        assert err == pytest.approx(2e-12, rel=1e-12) and warn is None, (amplitude, dominant)


def test_the_batched_monte_carlo_takes_one_hanging_one_period_one_inertia_unknown():
    from bifilar.config import read_yaml, scene_from_dict
    from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
    from bifilar.estimation.montecarlo import batched_applies
    from bifilar.estimation.problem import build_problem

    from conftest import CONFIGS

    scene = scene_from_dict(read_yaml(CONFIGS / "solar_boat.yaml"), warn=False)

    def pb(labels, unknowns):
        ms = MeasurementSet([Hanging("reference", scene, np.eye(3))],
                            [Measurement(lb, 2.0, 1e-3, "period", "--period", amplitude=0.0) for lb in labels])
        return build_problem(ms, unknowns, {})

    assert batched_applies(pb(["torsion"], ["Izz"]))
    assert not batched_applies(pb(["torsion", "roll"], ["Izz"]))  # two periods
    assert not batched_applies(pb(["torsion", "roll"], ["Izz", "Ixx"]))  # two unknowns
    assert not batched_applies(pb(["torsion"], ["com.x"]))  # not an inertia component


def test_the_loop_reports_its_progress_draw_by_draw():
    # solve_draws_loop's progress(done, total) after each draw, failed ones (None) too
    from bifilar.estimation.montecarlo import solve_draws_loop

    res = SimpleNamespace(problem=SimpleNamespace(unknowns=["Izz"]))
    calls = []
    out = solve_draws_loop(res, [None, None, None], progress=lambda i, n: calls.append((i, n)))
    assert calls == [(1, 3), (2, 3), (3, 3)] and out.shape == (3, 1) and np.all(np.isnan(out))


def test_the_cure_counts_the_drifts_part_shrinking_with_the_rtol():
    # 3e-9 s of integration (15 x 1e-10 x 2 s) and 7e-9 s of drift (7e-8 x 0.1 s) against a tenth of a
    # 2.5e-11 s timing (2.5e-12 s): the rtol that would scale the error below it, 2.5e-12 / 1e-8 x 1e-10
    # = 2.5e-14 -> 1e-14, is below MIN_RTOL (2.2e-14), where the integration claims its floor 2e-12 s
    # and the drift's part is 7e-9 x 2.2e-14 / 1e-10 = 1.5e-12 s: 3.5e-12 s together, above the limit
    # (either part alone, 2e-12 or 1.5e-12, is not)
    from bifilar.analysis.run_accuracy import period_accuracy

    err, warn = period_accuracy(2.0, "auto", 1e-10, timing=2.5e-11, linear_period=1.9, drift=7e-8)
    assert err == pytest.approx(1e-8, rel=1e-9)
    assert "most of it from the energy drift" in warn and "no --rtol brings it below" in warn


def test_a_sweep_points_amplitude_budget_reports_its_own_figures_consistently():
    # the Solar Boat at spacing 2.5, 0.3 rad, Izz from torsion: amplitude_budget's quadratic_slope is the
    # quadratic rule 2 (r - 1) of its period_factor r; rel_sigma is sigma / |Izz| (component_scale of a
    # moment), before and after the amplitude; factor_gain g is the one the amplitude's contribution
    # was divided by: contribution = |slope rel T_lin dI/dT| / g with dI/dT = (rel. sensitivity) I / T_lin
    from test_planner_amplitude import SOLAR, _point

    st, scene, p = _point(SOLAR, {"spacing": 2.5, "length": 2.0}, components=["Izz"], amplitude=0.3)
    e = p["components"]["Izz"]
    ab = e["amplitude_budget"]
    I = abs(float(scene.inertia[2, 2]))
    assert ab["budgeted"] and ab["period_factor"] > 1.01
    assert ab["quadratic_slope"] == pytest.approx(2 * (ab["period_factor"] - 1), rel=1e-12)
    assert e["rel_sigma"] == pytest.approx(e["sigma"] / I, rel=1e-12)
    assert ab["rel_sigma_small_amplitude"] == pytest.approx(ab["sigma_small_amplitude"] / I, rel=1e-12)
    g = abs(ab["slope"] * ab["relative_std"] * e["rel_sensitivity_period"] * I) / ab["contribution"]
    assert ab["factor_gain"] == pytest.approx(g, rel=1e-9)
    assert abs(ab["factor_gain"] - ab["period_factor"]) > 0.05  # dr/dI moves the gain off r (the test can tell)
