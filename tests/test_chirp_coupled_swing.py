"""A decaying record of a real rig's torsion carries the swing its release
excites: the damped trifilar of tests/test_end_to_end_audit.py (release
0.15 rad, Q 100, 40 cycles at 60 Hz), whose dominant coordinate also shows
the swings at 0.475-0.485 Hz (~2e-4 rad, 0.1 % of the release).  Left in
the amplitude law's residuals, the swing leaked into the law's frequency:
the period at ``amplitude_period`` lay 8e-6 s (1.1 of its 7.2e-6 s std)
above the true one on the noise-free record, and one std above it in every
noise draw (z mean +0.98; docs/invert.md, "Signal audit, session 9").  The
law is now fitted together with the other oscillations its residuals keep
(``signal_law._with_other_oscillations``).

The truth is independent of the code under test's law: the same rig
released without damping at two amplitudes bracketing the reference one,
each 20 cycles, its period interpolated linearly in A^2 (the law's A^4
term changes that by ~1e-8 s over the bracket, 3e-3 of the std).  The
motion is simulated once for the module (~6 s CPU).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import initial_state, relative_pose
from bifilar.config import scene_from_dict
from bifilar.estimation import measurements as mm
from bifilar.estimation.invert import invert
from bifilar.estimation.problem import build_problem
from bifilar.estimation.signal import AMPLITUDE_LAW_MODEL, fit_period
from bifilar.estimation.solve import amplitude_factor

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
sys.path.insert(0, str(ROOT / "tests"))
from bench_work_precision import atol_vector, naive_rhs_factory  # noqa: E402
from test_end_to_end_audit import TRIFILAR  # noqa: E402

FS = 60.0
A_RELEASE, Q_DAMP, CYCLES = 0.15, 100.0, 40
BRACKET = (0.09, 0.10)  # rad: undamped releases around the reference amplitude (~0.095)


def _motion(scene, rest, md, A, cycles, damping):
    """The dominant coordinate of the torsion released at ``A`` (rad),
    sampled at FS, by the naive right-hand side (viscous ``damping``, 1/s)."""
    y0 = initial_state(scene, rest, md, A)
    y0[:3] -= rest.com
    f = naive_rhs_factory(scene, rest.com, damping=damping)
    T = md.period
    sol = solve_ivp(f, (0.0, cycles * T), y0, method="DOP853", rtol=1e-9, atol=atol_vector(scene, T, A, 1e-9),
                    dense_output=True)
    assert sol.success
    t = np.arange(0.0, cycles * T, 1 / FS)
    Y = sol.sol(t).T
    Y[:, :3] += rest.com
    return t, relative_pose(Y, rest, md.dominant)


@pytest.fixture(scope="module")
def trifilar():
    scene = scene_from_dict(TRIFILAR, warn=False)
    rest = rest_pose(scene)
    modes = linear_modes(scene, rest).modes
    md = next(m for m in modes if m.label == "torsion")
    swings = [1 / m.period for m in modes if m.label.startswith("swing")]
    t, y = _motion(scene, rest, md, A_RELEASE, CYCLES, (2 * math.pi / md.period) / Q_DAMP)
    truth = []  # (fundamental amplitude, period, std) of the undamped runs
    for A in BRACKET:
        tu, yu = _motion(scene, rest, md, A, 20, 0.0)
        g = fit_period(tu, yu, model="auto")
        truth.append((g.amplitude, g.period, g.std))
    return t, y, truth, swings, scene


def _true_period(truth, a):
    (a1, T1, s1), (a2, T2, s2) = truth
    assert a1 < a < a2, (a1, a, a2)  # the bracket holds the reference amplitude
    x = (a * a - a1 * a1) / (a2 * a2 - a1 * a1)
    return T1 + x * (T2 - T1), math.hypot((1 - x) * s1, x * s2)


@pytest.fixture(scope="module")
def records(trifilar, tmp_path_factory):
    """12 noise draws (0.1 % of the release) of the one motion, written as
    ``t,angle`` files.  The first (seed 11) is byte for byte the record
    tests/test_end_to_end_audit.py wrote of the same motion (checked,
    session 26), whose closed loop now runs here on it."""
    t, y0 = trifilar[:2]
    d = tmp_path_factory.mktemp("draws")
    out = []
    for seed in range(11, 23):
        y = y0 + 1e-3 * A_RELEASE * np.random.default_rng(seed).standard_normal(t.size)
        path = d / f"torsion{seed}.csv"
        np.savetxt(path, np.c_[t, y], delimiter=",", header="t,angle", comments="", fmt="%.12g")
        out.append(path)
    return out


@pytest.fixture(scope="module")
def draws(records):
    """The 12 records, each read as ``invert --signal torsion=REC
    --signal-quantity angle`` reads it (a
    :class:`~bifilar.estimation.measurements.Measurement` holding its fit)."""
    return [mm.signal_measurement("torsion", path, "--signal", quantity="angle") for path in records]


def test_the_law_fits_the_coupled_swing_and_its_period_is_covered(trifilar, draws):
    """12 noise draws (0.1 % of the release) of the one motion.  z = (T -
    T_true(amplitude_period)) / std, T the record's undamped period as
    ``invert`` takes it.  Bands for 12 draws: the mean within 2/sqrt(12) =
    0.58 of 0, every |z| < 3, sd(z) < 1.6 (chi^2_11 99.5 %).  Here: mean
    -0.13, sd 0.74; before, the mean was +0.98 (sd 0.34), the swing left
    in the residuals ("unmodelled oscillation at 0.47 Hz, 435 x the noise
    level")."""
    _, _, truth, swings, _ = trifilar
    z, other = [], []
    for m in draws:
        fit = m.fit
        assert fit.model == AMPLITUDE_LAW_MODEL and fit.amplitude_law["used"]
        T_true, s_true = _true_period(truth, fit.amplitude_period)
        z.append((fit.period_undamped - T_true) / math.hypot(fit.std, s_true))
        other.append([o["frequency"] for o in fit.amplitude_law.get("other_oscillations", [])])
    z = np.asarray(z)
    assert abs(z.mean()) < 0.58, z
    assert np.all(np.abs(z) < 3.0), z
    assert z.std(ddof=1) < 1.6, z
    # the swing is part of the law's fit, at one of the rig's swing frequencies (within 2 %)
    assert all(any(abs(f / s - 1) < 0.02 for f in fs for s in swings) for fs in other), (other, swings)


def test_the_noise_free_records_period_is_within_its_std(trifilar):
    """Without noise only the model's shape is left: the period at
    ``amplitude_period`` within its std of the truth (before: 8.1e-6 s
    above, 1.12 std; now 6.1e-7 s above, 0.4 std)."""
    t, y, truth, _, _ = trifilar
    fit = fit_period(t, y, model="auto")
    assert fit.model == AMPLITUDE_LAW_MODEL and fit.amplitude_law["used"]
    T_true, s_true = _true_period(truth, fit.amplitude_period)
    assert abs(fit.period_undamped - T_true) < math.hypot(fit.std, s_true), (fit.period_undamped, T_true, fit.std)


# --------------------------------------------------------------------------- invert on the record (session 10)

EXACT = {"length": 0.0, "position": 0.0, "mass": 0.0, "com": 0.0, "amplitude": 0.0}
RECORD_STD = 3.6e-6  # s: the record's period std over the 12 draws below (3.5-3.9e-6)


def test_the_nonlinear_models_period_at_a_records_amplitude_is_the_true_one(trifilar):
    """``invert``'s model of a fitted record at the true inertia: ``T_lin
    r(A)`` with the amplitude factor of a record (``fundamental``: the
    fundamental's period at the fundamental's amplitude ``A``) against the
    undamped truth at ``A``.  Its error must be small against the record's
    std, or ``invert`` carries it into Izz as a bias: within 0.1 of it and
    twice the truth's own std (5.4e-7 s): 1.1e-6 s.  Here 4e-7 s; before
    (the mean period between the first and last crossings of a run
    released at ``A``) -2.7e-6 s: the swing the release excites at the run's
    two ends (-3.6e-6 s) and the release's fundamental 1.0003 A (+9e-7 s)."""
    _, _, truth, _, scene = trifilar
    A = 0.5 * (truth[0][0] + truth[1][0])
    m = mm.Measurement("torsion", 1.644, RECORD_STD, "signal", "--signal", amplitude=A, cycles=20)
    assert m.fundamental
    pb = build_problem(mm.MeasurementSet([mm.Hanging("reference", scene, np.eye(3))], [m]), ["Izz"])
    p = np.array([float(np.asarray(scene.inertia)[2, 2])])
    r, _ = amplitude_factor(pb.models[0], pb.values(p), pb.mode_index[0], A, m.cycles, 1e-10, fundamental=m.fundamental)
    T_model = float(pb.linear_periods(p)[0]) * r
    T_true, s_true = _true_period(truth, A)
    assert abs(T_model - T_true) < math.hypot(0.1 * RECORD_STD, 2 * s_true), (T_model, T_true, s_true)


def test_invert_on_the_record_is_as_unbiased_as_the_records_period(trifilar, draws):
    """``invert --signal torsion=REC --signal-quantity angle --solve-for
    Izz`` with every other input exact, on the first 2 of the noise draws
    above.  In period units the record's error ``e_rec = T - T_true(A)``
    and Izz's ``e_izz = (Izz - I_true) dT/dIzz`` (the linear model's slope,
    0.47 s / kg m^2; the amplitude factor's own slope moves it by ~1e-3 of
    itself) differ by the model's error at the true inertia alone, the same
    in every draw: measured +3.69e-7 s in each of the 12 draws (spread
    +-5e-10 s).  Bands: that difference within 1.1e-6 s (twice the truth's
    own std and 0.1 of the record's, as the model's error is held to in the
    test above) and the same in every draw within 1e-8 s.  Before ("found,
    not fixed" in session 9: the amplitude factor's period was the run's
    crossings', docs/invert.md, "Signal audit, session 10") it was -2.7e-6
    s, 0.75 of the record's std, in every draw.

    Test economy, session 16: this was Izz's z against the record's z over
    all 12 draws (20 s of CPU, 12 nonlinear inverts), on the ground that
    the two z differ by a constant (sd 0.01-0.03).  Since Izz's std carries
    the hidden second mode's term (``hidden_second_mode[torsion]``, 1.05e-5
    kg m^2 beside the timing's 7.6e-6) they do not: Izz's z is ~0.58 of
    the record's, their differences had sd 0.41 (-0.38 .. +0.61) and only
    their mean over 12 draws separated the bug (+0.73) from the band (0.3).
    In seconds the difference is deterministic, so each draw checks it
    alone; the record's own bias over the 12 draws is the first test's
    (mean z within 0.58), and Izz's bias in its std is that one's plus
    3.7e-7 s over Izz's std in seconds (6.1e-6 s): 0.06.

    Test economy, session 23: 2 draws (was 3; each a nonlinear invert).
    The bias band is checked by each draw alone (the bug's -2.7e-6 s in
    every draw, the band 1.1e-6 s), and two draws still test that the
    difference is the same in each (1e-8 s; the 12 draws spread by +-5e-10
    s).  The amplitude factor from the run's crossings again
    (amplitude_runs.amplitude_factor with fundamental=False) fails
    (checked, session 23)."""
    _, _, truth, _, scene = trifilar
    I_true = float(np.asarray(scene.inertia)[2, 2])
    pb = build_problem(mm.MeasurementSet([mm.Hanging("reference", scene, np.eye(3))], [draws[0]]), ["Izz"])
    h = 1e-6 * I_true
    dT_dI = float(pb.linear_periods(np.array([I_true + h]))[0] - pb.linear_periods(np.array([I_true - h]))[0]) / (2 * h)
    diff = []
    for m in draws[:2]:
        T_true, _ = _true_period(truth, m.amplitude)
        ms = mm.MeasurementSet([mm.Hanging("reference", scene, np.eye(3))], [m])
        ms.uncertainty = {**ms.uncertainty, **EXACT}
        r = invert(ms, solve_for=["Izz"])
        diff.append((m.period - T_true) - (r.value("Izz") - I_true) * dT_dI)
        # Izz's std holds at least the record's timing: in seconds not below the record's std
        assert r.sigma("Izz") * dT_dI >= m.std, (r.sigma("Izz"), m.std)
    diff = np.asarray(diff)
    assert np.all(np.abs(diff) < 1.1e-6), diff
    assert np.ptp(diff) < 1e-8, diff


# --------------------------------------------------------------------------- the closed loop of session 8


def test_a_damped_trifilars_izz_from_its_release_amplitude_is_within_its_std(trifilar, records):
    """``invert --signal torsion=REC --amplitude 0.15 --solve-for Izz`` with
    the inputs exact and stated so (the std is the record's and the
    amplitude's alone), on the first noise draw (the end-to-end audit's
    record, session 8; moved here from tests/test_end_to_end_audit.py in
    session 26, which integrated the same motion a second time, ~3 s of
    CPU).  That std (0.0024 kg m^2) is nearly all the
    record's split-half term, which here measures the period's own fall
    with the decaying amplitude, the effect the model now accounts for:
    the noise (0.1 % of the release) and the amplitude rule (1 % in A^2,
    tests/test_end_to_end_audit.py) leave errors of a few 1e-2 of it, so the
    estimate must lie well inside it, |z| < 0.5.  Before the fix the stated
    release amplitude gave z = -1.67 (its nonlinear lengthening removed from
    a period that had decayed past it); after it, and with the fitted
    amplitude (``--signal-quantity angle``, z = -0.43 with the
    energy-weighted amplitude), |z| ~ 1e-3."""
    scene, path, A = trifilar[4], records[0], A_RELEASE
    truth = float(np.asarray(scene.inertia)[2, 2])
    exact = {"length": 0.0, "position": 0.0, "mass": 0.0, "com": 0.0}
    for kw in ({"amplitude": A}, {"quantity": "angle"}):
        m = mm.signal_measurement("torsion", path, "--signal", **kw)
        ms = mm.MeasurementSet([mm.Hanging("reference", scene, np.eye(3))], [m])
        ms.uncertainty = {**ms.uncertainty, **exact}
        r = invert(ms, solve_for=["Izz"])
        z = (r.value("Izz") - truth) / r.sigma("Izz")
        assert abs(z) < 0.5, (kw, z, r.value("Izz"), truth, r.sigma("Izz"))
