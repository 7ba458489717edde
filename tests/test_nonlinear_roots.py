"""Several nonlinear roots in one unknown (docs/invert.md, "The nonlinear
model's period in the unknown: monotonic?").

``invert``'s nonlinear rung solves ``T_lin(p) r(A; p) = T_meas`` by the fixed
point ``p = T_lin^-1(T_meas / r(p))``, which contracts only while the gain
``g = d(T_lin r)/dp / (r dT_lin/dp)`` lies in (0, 2).  Near the Solar Boat's
internal resonance (swing-y with roll, Ixx ~ 100-120) the amplitude factor
moves faster: six runs left the estimate off and the fit check, made with the
factor of the last simulated iterate, could not see it.  The references are
independent runs of the maximal model (``simulate``) at a known tensor,
never the output of the code under test."""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis.simulate import simulate
from bifilar.config import load_scene
from bifilar.estimation import measurements as mm
from bifilar.estimation.invert import invert
from bifilar.estimation.problem import admissible_interval, build_problem
from bifilar.estimation.roots import relabel
from bifilar.estimation.solve import amplitude_factor

GAIN_HIGH = 2.0  # solve.GAIN_RANGE[1]: the fixed point stops contracting there
from conftest import CONFIGS

BOAT = CONFIGS / "solar_boat.yaml"
PLATE = CONFIGS / "thesis_plate_rest.yaml"
STD = 1e-3  # s


def _problem(cfg, label, comp, A):
    sc = load_scene(cfg, unknown=(comp,))
    m = mm.Measurement(label, 1.0, STD, "period", "--period", cycles=10, amplitude=A, std_given=True)
    return build_problem(mm.MeasurementSet([mm.Hanging("ref", sc, np.eye(3), str(cfg))], [m]), [comp])


def _true_period(cfg, label, comp, A, value):
    """The maximal model's crossing period (``simulate``, as the amplitude
    factor runs it: DOP853 at rtol 1e-10, 10 linear periods) of the body
    with ``comp`` = ``value``."""
    pb = _problem(cfg, label, comp, A)
    scene = pb.models[0].scene(pb.values([value]))
    return simulate(scene, label, A, 10, method="DOP853", rtol=1e-10, check=False).period


def _invert(cfg, label, comp, A, T):
    meas = mm.MeasurementSet([mm.Hanging("reference", load_scene(cfg, unknown=(comp,)), np.eye(3), str(cfg))],
                             [mm.Measurement(label, T, STD, "period", "--period", cycles=10, amplitude=A,
                                             std_given=True)])
    return invert(meas, solve_for=[comp], ladder=False)


def _monotonic_warnings(res):
    return [w for w in res.warnings if "need not be monotonic" in w or "also at" in w]


def test_the_nonlinear_estimate_is_a_root_where_the_fixed_point_does_not_contract():
    """The Solar Boat's swing-y released at 1.0 m, Ixx = 100.  Before:
    100.38 +- 2.28 (g = 1.7: six runs of the oscillating fixed point; the
    model's period there 4 timing std from the measured one), exit 0 with
    the fit check passed at chi2 0 (made with the factor of the last
    simulated iterate).  g = 1.7 lies in the range: no warning."""
    truth = 100.0
    res = _invert(BOAT, "swing-y", "Ixx", 1.0, _true_period(BOAT, "swing-y", "Ixx", 1.0, truth))
    Ixx, sd = res.values[0], res.std[0]
    assert abs(Ixx - truth) < 0.01 * sd, (Ixx, sd)
    assert not _monotonic_warnings(res), res.warnings


def test_near_the_resonance_the_root_is_found_and_the_gain_warned():
    """1.3 m at Ixx 95, the resonance.  Before: 117.85 +- 1.32 (g = 5.8:
    the fixed point's iterates ran off; the model's period there 360 timing
    std from the measured one), exit 0, no warning.  Now the root, and the
    warning quotes the gain (from the law's ``dr/dp``, no extra run) that
    central differences of the simulated period ``T(Ixx +- h)`` over the
    linear one's give (h = 0.05, 1.5e-4 of the scale, where the map is
    smooth)."""
    A, truth, h = 1.3, 95.0, 0.05
    res = _invert(BOAT, "swing-y", "Ixx", A, _true_period(BOAT, "swing-y", "Ixx", A, truth))
    assert abs(res.values[0] - truth) < 0.01 * res.std[0], (res.values, res.std)
    (w,) = [w for w in res.warnings if "need not be monotonic" in w]
    g_warned = float(w.split("d(T_lin r)/dIxx = ")[1].split(" ")[0])
    Tp, Tm = (_true_period(BOAT, "swing-y", "Ixx", A, truth + s * h) for s in (1, -1))
    pb = _problem(BOAT, "swing-y", "Ixx", A)
    relabel(pb, [truth])
    T_lin = [float(pb.linear_periods([truth + s * h])[0]) for s in (1, -1)]
    r = _true_period(BOAT, "swing-y", "Ixx", A, truth) / float(pb.linear_periods([truth])[0])
    g = (Tp - Tm) / (r * (T_lin[0] - T_lin[1]))
    assert g > GAIN_HIGH
    assert abs(g_warned - g) < 0.05 * g, (g_warned, g)  # two significant digits in the warning


def _scan(cfg, label, comp, A, xs):
    pb = _problem(cfg, label, comp, A)
    out = []
    for x in xs:
        assert relabel(pb, [x])
        r, _ = amplitude_factor(pb.models[0], pb.values([x]), pb.mode_index[0], A, 10, 1e-10)
        out.append(float(pb.linear_periods([x])[0]) * r)
    return np.array(out)


@pytest.mark.parametrize("cfg, label, comp, A, span", [
    (BOAT, "swing-y", "Ixx", 1.0, (5.0, 120.0)),  # the label's lower branch (it passes to the roll's at ~121)
    (PLATE, "torsion", "Izz", 0.6, None),  # the whole physical interval
    (PLATE, "torsion", "Izz", 1.2, None),  # near the torsion's reach (1.5 rad: no pose on the wires)
])
def test_realistic_releases_give_a_monotonic_period(cfg, label, comp, A, span):
    """The claim of docs/invert.md: at the realistic releases of the shipped
    configs the full model's period ``T_lin r`` rises with the unknown (one
    root), though the factor falls (the plate: ``r`` 1.37 -> 1.23 at 0.6 rad,
    g down to 0.2 at 1.2 rad).  Non-monotonic only at 1.3 m and beyond on
    the boat, at its resonance (Ixx ~ 100-106)."""
    if span is None:
        pb = _problem(cfg, label, comp, A)
        lo, hi = admissible_interval(pb.I_ref0, comp)
        span = (lo + 1e-3 * (hi - lo), hi - 1e-3 * (hi - lo))
    T = _scan(cfg, label, comp, A, np.linspace(*span, 10))
    assert np.all(np.diff(T) > 0), T


def test_a_realistic_estimate_gives_no_warning():
    """The boat's own Ixx (83.14) from swing-y at 1.0 m: g = 1.2, inside
    the range: no monotonicity warning, the estimate its own."""
    truth = 83.14158854
    res = _invert(BOAT, "swing-y", "Ixx", 1.0, _true_period(BOAT, "swing-y", "Ixx", 1.0, truth))
    assert not _monotonic_warnings(res), res.warnings
    assert abs(res.values[0] - truth) < 0.01 * res.std[0]


def test_one_unknown_from_two_periods_settles_by_secant():
    """The same release timed twice (two periods, one unknown: least
    squares, not the full model's root), 1.0 m at Ixx 100.  Before: 100.38
    +- 1.34, exit 0, chi2 4e-25 (the factor of the last simulated iterate);
    now the secant on the fixed point's map settles it."""
    truth = 100.0
    T = _true_period(BOAT, "swing-y", "Ixx", 1.0, truth)
    m = [mm.Measurement("swing-y", T, STD, "period", "--period", cycles=10, amplitude=1.0, std_given=True)
         for _ in range(2)]
    meas = mm.MeasurementSet([mm.Hanging("reference", load_scene(BOAT, unknown=("Ixx",)), np.eye(3), str(BOAT))], m)
    res = invert(meas, solve_for=["Ixx"], ladder=False)
    assert abs(res.values[0] - truth) < 0.01 * res.std[0], (res.values, res.std)
