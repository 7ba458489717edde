"""Mutation round 11 (docs/mutation.md, "Round 11"): tests that fail on a
mutant of session 10's code, or of round 10's three gaps, that the suite
let through.  Each states the truth it checks (an analytic result, an
independent formulation or the documented rule on a record built for it);
none reads its expected value off the code under test.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from test_amplitude_law import boat  # noqa: F401  (the Solar Boat at spacing 1, length 2: a module fixture)

# ---------------------------------------------------------------------------
# signal_law.py: the law's own split check
# ---------------------------------------------------------------------------

ST_T0, ST_C, ST_A0, ST_Q, ST_CYCLES, ST_FS = 1.3, 1 / 16, 0.5, 40.0, 40, 30.0


def _chirp_with_step(step: float, noise: float = 1e-5, seed: int = 1):
    """A decaying record (rad) of ``T = T0 (1 + c A^2)`` to A^4 (the frequency ``w0 (1 - c A^2 + c^2 A^4)``,
    A = A0 exp(-sigma t), Q = 40, 40 cycles at 30 Hz, phase integrated in closed form) whose frequency
    also steps up by ``step`` w0 at mid-record, phase continuous (a rig that changes once, in time: no
    amplitude explains it); white noise of ``noise`` A0."""
    rng = np.random.default_rng(seed)
    w0 = 2 * math.pi / ST_T0
    sg = w0 / (2 * ST_Q)
    t = np.arange(0.0, ST_CYCLES * ST_T0, 1 / ST_FS)
    L = t[-1]

    def E(k):
        return (1 - np.exp(-k * t)) / k

    ph = w0 * t - w0 * ST_C * ST_A0**2 * E(2 * sg) + w0 * ST_C**2 * ST_A0**4 * E(4 * sg) + 0.3
    ph = ph + step * w0 * np.maximum(t - L / 2, 0.0)
    return t, ST_A0 * np.exp(-sg * t) * np.cos(ph) + noise * ST_A0 * rng.standard_normal(t.size)


@pytest.mark.parametrize("seed", [1, 2])
def test_a_law_whose_own_halves_still_disagree_is_not_used(seed):
    # _amplitude_law's rule: the law replaces the viscous fit only when its own split check (each half
    # with the law held at the whole record's beta, referred to one amplitude) finds no disagreement
    # beyond noise; "a drift the law cannot explain (a period that changes with time, not with the
    # amplitude) keeps the viscous fit and its between-half std".  The record: a pendulum's law (d/c^2 =
    # 0, inside the A^4 band) plus a frequency step of 3e-6 at mid-record, ~50x the halves' std (4e-8 of
    # the period each at 1e-5 noise).  The whole record's law absorbs most of a step (at Q = 100 all but
    # ~3 %, so the halves agreed), at Q = 40 not: it still passes every earlier check (BIC lower, beta
    # resolved, the A^4 ratio ~1), and its halves disagree, so the law is refused for that reason alone.
    # Without the step the same record's law is used (the refusal is the step's)
    from bifilar.estimation.signal import AMPLITUDE_LAW_MODEL, fit_period

    t, y = _chirp_with_step(0.0, seed=seed)
    clean = fit_period(t, y, model="auto")
    assert clean.amplitude_law["used"] and clean.model == AMPLITUDE_LAW_MODEL, clean.amplitude_law["reason"]

    t, y = _chirp_with_step(3e-6, seed=seed)
    fit = fit_period(t, y, model="auto")
    law = fit.amplitude_law
    # the earlier checks pass
    assert law["criterion_delta"] < 0 and abs(law["beta"]) >= 3 * law["beta_std"]
    assert law["curvature_ratio"] == pytest.approx(1.0, abs=0.2)
    # its halves, referred to one amplitude, differ by more than their noise: chi^2 with one dof
    (T1, s1), (T2, s2) = law["halves"]
    assert abs(T1 - T2) > 5 * math.hypot(s1, s2)
    assert law["Q"] > law["critical_Q"]
    assert not law["used"] and "halves still disagree" in law["reason"]
    assert fit.model != AMPLITUDE_LAW_MODEL and fit.std_nonstationary > 0


# ---------------------------------------------------------------------------
# point_amplitude.py: a failed law run, a point without a sigma
# ---------------------------------------------------------------------------

def _law_point(monkeypatch, law_runs=None, budget=None):
    """The Solar Boat at spacing 2.5, length 2, Izz from torsion at 0.3 rad (tests/test_planner_amplitude.py),
    its amplitude law's runs (the half-amplitude run, then the stepped scene's) passed through
    ``law_runs`` and its small-amplitude budgets through ``budget``."""
    import bifilar.studies.point as point
    import bifilar.studies.point_amplitude as pa
    from test_planner_amplitude import SOLAR, _point

    real_runs, real_stated = point._runs_at, point._stated_amplitude

    def runs_at(law, st, own=None):
        runs = real_runs(law, st, own)
        n = len(runs) - len(law.scenes)
        return runs[:n] + (law_runs(runs[n:]) if law_runs else runs[n:])

    def stated(res, pre, sims, st, *args, **kw):
        if budget:
            pre.budgets = {c: budget(b) for c, b in pre.budgets.items()}
        return real_stated(res, pre, sims, st, *args, **kw)

    monkeypatch.setattr(point, "_runs_at", runs_at)
    monkeypatch.setattr(pa, "_runs_at", runs_at)
    monkeypatch.setattr(point, "_stated_amplitude", stated)
    return _point(SOLAR, {"spacing": 2.5, "length": 2.0}, components=["Izz"], amplitude=0.3)


def _broken(which: int, error: bool):
    """The law run ``which`` (0 the half-amplitude run, 1 the stepped scene's) failed: with an error
    (its period kept: a run that errs is failed whatever it timed) or without a period (no error)."""
    def f(runs):
        assert len(runs) == 2
        runs = list(runs)
        runs[which] = replace(runs[which], error="broken on purpose") if error else replace(runs[which], period=None)
        return runs
    return f


@pytest.mark.parametrize("which, error", [(0, True), (1, True), (0, False), (1, False)])
def test_a_failed_law_run_leaves_the_small_amplitude_sigma_and_says_so(monkeypatch, which, error):
    # _amplitude_laws: "a component whose runs fail is left out (its sigma then says so)": a run with an
    # error, or without a period, is failed (each of the guard's four terms on its own).  The sigma is then
    # invert's at --amplitude 0 (an independent call), amplitude_budget says budgeted false and why
    from test_planner_amplitude import _invert

    st, scene, p = _law_point(monkeypatch, law_runs=_broken(which, error))
    e = p["components"]["Izz"]
    ab = e["amplitude_budget"]
    assert ab["budgeted"] is False and ab["contribution"] is None
    assert "amplitude law's runs failed" in ab["note"] and "--amplitude 0" in ab["note"]
    assert ab["period_factor"] > 1.01  # the point's own run did run: only the law's failed
    small = _invert(scene, e["mode"], e["period"], "Izz", st.unc, 0.0)
    assert e["sigma"] == pytest.approx(small.sigma("Izz"), rel=1e-6)
    assert ab["sigma_small_amplitude"] == e["sigma"]


def test_a_point_with_a_law_but_no_sigma_says_no_sigma(monkeypatch):
    # _stated_amplitude: a component whose small-amplitude std is undefined gets no amplitude budget even
    # when its law ran (the budget of an undefined std is undefined): note "no sigma", budgeted false
    st, scene, p = _law_point(monkeypatch, budget=lambda b: replace(b, value_sigma=float("nan")))
    ab = p["components"]["Izz"]["amplitude_budget"]
    assert ab["period_factor"] > 1.01
    assert ab["budgeted"] is False and ab["note"] == "no sigma" and ab["sigma_small_amplitude"] is None
    # the same point with its sigma is budgeted: the law did run
    monkeypatch.undo()
    st, scene, p = _law_point(monkeypatch)
    assert p["components"]["Izz"]["amplitude_budget"]["budgeted"] is True


# ---------------------------------------------------------------------------
# fundamental.py: the frequency of the nearest periodic function
# ---------------------------------------------------------------------------

FW = 2 * math.pi / 1.7
FT = np.arange(0.0, 20 * 1.7, 1 / 60.0)


def _periodic(tone: float) -> np.ndarray:
    """A constant and three harmonics of FW at arbitrary phases (a release not at a turning point: the
    sines matter), plus ``tone`` times a cosine at 0.43 FW (another mode's swing)."""
    return (0.01 + 0.3 * np.cos(FW * FT + 0.7) + 0.02 * np.cos(2 * FW * FT - 1.1) + 0.005 * np.cos(3 * FW * FT + 2.0)
            + tone * np.cos(0.43 * FW * FT + 0.4))


def _profile(omega: float, y: np.ndarray) -> float:
    """min over the coefficients of |y - periodic(omega)|^2, a constant and three harmonics (numpy's lstsq)."""
    cols = [np.ones_like(FT)] + [f(k * omega * FT) for k in (1, 2, 3) for f in (np.cos, np.sin)]
    X = np.stack(cols, axis=1)
    r = y - X @ np.linalg.lstsq(X, y, rcond=None)[0]
    return float(r @ r)


@pytest.mark.parametrize("start", [1e-3, -5e-3])
def test_the_fundamentals_frequency_of_a_periodic_record_is_its_own(start):
    # exactly periodic with phases: the least-squares frequency is the generator's (to rounding), from a
    # start 0.1-0.5 % off (the harmonics' sines and the Gauss-Newton iteration's residual matter here;
    # the torsion run of tests/test_mode_fundamental.py starts at a turning point, its sines ~0)
    from bifilar.analysis.fundamental import _fit_frequency

    assert _fit_frequency(FT, _periodic(0.0), FW * (1 + start)) == pytest.approx(FW, rel=1e-11)


@pytest.mark.parametrize("start", [1e-3, -5e-3])
def test_the_fundamentals_frequency_is_the_least_squares_one_beside_another_oscillation(start):
    # _fit_frequency: "the angular frequency of the periodic function (constant and three harmonics)
    # nearest y(t) in least squares": with another oscillation (5 % of the record) the residual is not
    # zero and the minimum moves off the generator's frequency (3e-5 here); the returned frequency is the
    # minimum of the profile sum of squares, found independently (numpy's lstsq per frequency, central
    # differences: Newton's step from it measured 4e-13 of the frequency; band 1e-9).  A Gauss-Newton
    # step with a wrong derivative column stops where the residual is orthogonal to the wrong column
    from bifilar.analysis.fundamental import _fit_frequency

    y = _periodic(0.05)
    w = _fit_frequency(FT, y, FW * (1 + start))
    h = 1e-6 * w
    sp, s0, sm = _profile(w + h, y), _profile(w, y), _profile(w - h, y)
    newton = -((sp - sm) / (2 * h)) / ((sp - 2 * s0 + sm) / h**2)
    assert abs(newton) < 1e-9 * w
    assert abs(w / FW - 1) > 1e-6  # the other oscillation did move the minimum (the test can tell)


@pytest.mark.parametrize("off", [0.1, -0.2, 0.3])
def test_a_start_far_off_gives_the_frequency_or_says_it_did_not_converge(off):
    # a start 10-30 % off the fundamental (several bins of the 20-cycle record): the answer is the
    # periodic record's own frequency or a ConvergenceError, never another frequency (an alias or a
    # harmonic's) presented as the fundamental's
    from bifilar.analysis.fundamental import _fit_frequency
    from bifilar.errors import ConvergenceError

    try:
        w = _fit_frequency(FT, _periodic(0.0), FW * (1 + off))
    except ConvergenceError as exc:
        assert "did not converge" in str(exc)
        return
    assert w == pytest.approx(FW, rel=1e-11)


def test_mode_fundamental_takes_the_other_modes_out_through_the_mass_matrix(monkeypatch):
    # mode_fundamental's rule on a motion written from its modes: d(t) = q_a(t) phi_a + q_b(t) phi_b with
    # phi_a^T M phi_b = 0 (M diagonal), q_a a constant and three harmonics of FW at arbitrary phases,
    # q_b another mode at 0.43 FW that also moves a's dominant coordinate (8.6 x q_b there).  The modal
    # projection gives q_a exactly, so the period is 2 pi / FW; the amplitude is the fundamental's in the
    # dominant coordinate with b's part taken out: 0.3 x phi_a[dom] = 0.3 (the 1st harmonic's amplitude).
    # The pose is the test's d (relative_pose replaced by the identity: the rest is the origin)
    from types import SimpleNamespace as NS

    import bifilar.analysis.fundamental as fu

    M = np.diag([2.0, 2.0, 2.0, 0.05, 0.03, 0.07])
    phi_a = np.array([0.3, 0.0, 0.0, 0.0, 0.0, 1.0])
    phi_b = np.array([1.0, 0.0, 0.0, 0.0, 0.0, -2.0 * 0.3 / 0.07])
    assert abs(phi_a @ M @ phi_b) < 1e-12
    q_a = _periodic(0.0)
    q_b = 0.1 * np.cos(0.43 * FW * FT + 0.4)
    d = np.outer(q_a, phi_a) + np.outer(q_b, phi_b)
    modes = NS(modes=[NS(shape=phi_b, dominant=0), NS(shape=phi_a, dominant=5)], mass_matrix=M)
    monkeypatch.setattr(fu, "relative_pose", lambda Y, rest: Y)
    T, a = fu.mode_fundamental(FT, d, None, modes, 1, 2 * math.pi / FW * (1 + 2e-3))
    assert T == pytest.approx(2 * math.pi / FW, rel=1e-11)
    assert a == pytest.approx(0.3, rel=1e-9)


# ---------------------------------------------------------------------------
# factor_inputs.py: which inputs' dr/dx are derived without a run
# ---------------------------------------------------------------------------

def _routes_problem(names, nw=4):
    from types import SimpleNamespace as NS

    return NS(models=[NS(hanging=NS(name=n, scene=NS(n_wires=nw))) for n in names])


def _all_keys(pre="", nw=4):
    return (["gravity", "mass", "com.x", "com.y", "com.z"] + [f"{pre}length.{i}" for i in range(1, nw + 1)]
            + [f"{pre}{p}.{i}.{a}" for p in ("anchor", "attachment") for i in range(1, nw + 1) for a in "xyz"])


@pytest.mark.parametrize("names", [["only"], ["a", "b"]])
def test_the_exact_routes_of_dr_dx_follow_the_documented_rule(names):
    # _factor_routes' docstring: gravity (0, time scaling), the last wire's anchor coordinates (translation
    # invariance: all the other anchors' same coordinate needed), com.* (all the attachments needed) and
    # the mass (the scaling identity: every length, anchor and attachment needed) are derived, the rest
    # run.  Keys carry the hanging's name as prefix only with several hangings
    from bifilar.estimation.factor_inputs import _factor_routes

    pb = _routes_problem(names)
    pre = f"{names[0]}:" if len(names) > 1 else ""
    keys = _all_keys(pre)
    run, derived = _factor_routes(pb, 0, keys)
    want = {"gravity": "gravity", "mass": "scaling", "com.x": "com", "com.y": "com", "com.z": "com",
            f"{pre}anchor.4.x": "translation", f"{pre}anchor.4.y": "translation", f"{pre}anchor.4.z": "translation"}
    assert derived == want
    assert sorted(run) == sorted(k for k in keys if k not in want)
    # one input missing takes its route away: anchor.2.y (the last anchor's y, and the mass), an
    # attachment (com and the mass), a length (the mass)
    for gone, lost in ((f"{pre}anchor.2.y", {f"{pre}anchor.4.y", "mass"}),
                       (f"{pre}attachment.3.z", {"com.x", "com.y", "com.z", "mass"}),
                       (f"{pre}length.1", {"mass"})):
        _, d = _factor_routes(pb, 0, [k for k in keys if k != gone])
        assert set(d) == set(want) - lost, gone


# ---------------------------------------------------------------------------
# rig.py: the same measurement within SAME_TOL of the longest wire
# ---------------------------------------------------------------------------

def _rig_scene(dz: float, L: float = 2.0):
    from types import SimpleNamespace as NS

    anchors = np.array([[0.3, 0.0, L], [-0.3, 0.0, L]])
    anchors[1, 2] += dz
    return NS(anchors=anchors, lengths=np.array([L, 1.5]), attachments=np.array([[0.3, 0.0, 0.0], [-0.3, 0.0, 0.0]]),
              n_wires=2)


@pytest.mark.parametrize("frac, same", [(0.5e-9, True), (1.5e-9, False)])
def test_two_hangings_share_a_rig_within_a_billionth_of_the_longest_wire(frac, same):
    # SAME_TOL: anchors and lengths equal within 1e-9 of the longest wire (2 m here) are one measurement:
    # an anchor 0.5e-9 x 2 m off is the same rig (one key per length and anchor, both hangings'), 1.5e-9 x
    # 2 m off two rigs (each hanging its own keys)
    from bifilar.estimation.rig import rig_links

    links = rig_links(["a", "b"], [_rig_scene(0.0), _rig_scene(frac * 2.0)], [np.eye(3), np.eye(3)])
    length_keys = [k for k in links.keys if "length.1" in k]
    if same:
        assert length_keys == ["a+b:length.1"] and links.hangings("a+b:anchor.2.z") == [0, 1]
    else:
        assert sorted(length_keys) == ["a:length.1", "b:length.1"]


@pytest.mark.parametrize("case", ["no law", "law without dr_dp", "no amplitude"])
def test_dr_dx_is_measured_only_for_a_stated_amplitudes_law(monkeypatch, case):
    # factor_input_derivatives: dr/dx "for each measurement k with a stated amplitude's law (dr_dp set)":
    # a measurement without a law, with an unstated release's law (no dr_dp) or without an amplitude runs
    # nothing and its law is left untouched
    from types import SimpleNamespace as NS

    import bifilar.analysis.batch as batch
    from bifilar.estimation.factor_inputs import factor_input_derivatives

    def no_runs(*a, **k):
        raise AssertionError("ran a simulation")

    monkeypatch.setattr(batch, "simulate_batch", no_runs)
    law = None if case == "no law" else NS(dr_dp=None if case == "law without dr_dp" else np.ones(1), amplitude=0.3)
    m = NS(amplitude=0.0 if case == "no amplitude" else 0.3, hanging=0, cycles=10)
    pb = NS(measurements=[m], models=[NS(hanging=NS(name="only", scene=NS(n_wires=2)))], mode_index=[0])
    factor_input_derivatives(pb, [law], ["gravity"], {"gravity": 1e-4}, [None], [None], [None], [[0]])
    if law is not None:
        assert not hasattr(law, "dr_dx") and not hasattr(law, "dr_dx_failed")


# ---------------------------------------------------------------------------
# kane_run.py: the kane model's runs checked as the maximal model's
# ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def pitch_rig():
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.config import load_scene

    from conftest import CONFIGS

    sc = load_scene(CONFIGS / "thesis_lin2_pitch.yaml")
    rest = rest_pose(sc)
    return sc, rest, linear_modes(sc, rest)


def test_kane_checks_only_a_run_whose_cycles_spread_and_only_when_asked(pitch_rig):
    # simulate_kane's check: "where the single-cycle periods spread by more than IRREGULAR_SPREAD of the
    # period the same start is run again at rtol / 100"; check=False: the error model alone.  The pitch rig's
    # pitch at 0.05 rad spreads (7e-6 of its period over 5 cycles), its swing-y does not (1e-10)
    from bifilar.analysis.kane_run import simulate_kane
    from bifilar.analysis.run_accuracy import IRREGULAR_SPREAD

    sc, rest, ms = pitch_rig
    calm = simulate_kane(sc, rest, ms, mode="swing-y", amplitude=0.05, periods=3, rtol=1e-9)
    assert calm.period_std < IRREGULAR_SPREAD * calm.period and calm.period_check is None
    spread = simulate_kane(sc, rest, ms, mode="pitch", amplitude=0.05, periods=5, rtol=1e-8)
    assert spread.period_std > IRREGULAR_SPREAD * spread.period
    assert spread.period_check is not None and spread.period_check["rtol"] == pytest.approx(1e-10, rel=1e-12)
    unchecked = simulate_kane(sc, rest, ms, mode="pitch", amplitude=0.05, periods=5, rtol=1e-8, check=False)
    assert unchecked.period_check is None



# ---------------------------------------------------------------------------
# solve.py: a stated amplitude's law carries the largest irregularity of its runs
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("given, diffs, largest", [(9e-7, [2e-7, 5e-7, 1e-7], 9e-7), (3e-7, [2e-7, 5e-7, 1e-7], 5e-7),
                                                   (0.0, [0.0, 0.0, 0.0], 0.0)])
def test_a_laws_irregularity_is_the_largest_of_its_runs(monkeypatch, given, diffs, largest):
    # stated_amplitude_law: "law.irregular: the largest difference" of the factor's own run (given) and the
    # law's runs (one at 0.9 A, one per unknown stepped); the runs replaced by factors of a quadratic law
    # with their check differences
    from types import SimpleNamespace as NS

    import bifilar.estimation.solve as so

    calls = iter(zip([1.0 + 0.002 * 0.81, 1.0021, 1.0019], diffs))

    def measured(pb, k, p, rtol=1e-10, amplitude=None):
        r, d = next(calls)
        return r, None, d

    monkeypatch.setattr(so, "measured_factor", measured)
    # a period of 2 s moving 1 s per unit of each unknown: factor_step_rtol's bound 2e-6, no rerun
    pb = NS(measurements=[NS(amplitude=0.3)], scales=lambda: np.ones(2), linear_periods=lambda p: np.array([2.0]),
            jacobian=lambda p: np.ones((1, 2)))
    law = so.stated_amplitude_law(pb, np.array([1.0, 2.0]), 0, 1.002, irregular=given)
    assert law.irregular == largest
    assert law.dr_dp == pytest.approx([(1.0021 - 1.002) / so.FACTOR_STEP, (1.0019 - 1.002) / so.FACTOR_STEP], rel=1e-6)


# ---------------------------------------------------------------------------
# factor_inputs.py: dr/dx of a factor linear in the inputs, through every route
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("dominant, own_fails, pre", [(0, False, ""), (3, False, ""), (0, True, ""), (0, False, "a:")])
def test_dr_dx_of_a_factor_linear_in_the_inputs(monkeypatch, dominant, own_fails, pre):
    # factor_input_derivatives with the engine replaced by a factor linear in the inputs, r = r0 + sum g_x
    # dx (a run's period r T_lin): a forward difference returns g_x exactly; the exact routes are the
    # docstring's identities on those g: gravity 0; the last anchor's coordinate minus the sum over the
    # other anchors'; com.a = -sum_i sum_b R[b, a] g(attachment i, b); the mass (sum_x x g_x + A dr/dA for a
    # translation mode only) / 2m.  One stepped run fails (attachment.1.y): its input is listed in
    # dr_dx_failed and left at 0 (and, there, the com and mass routes read that 0).  When the estimate's own
    # run fails, every input is failed and 0 (no difference can be taken).  pre "a:": hanging "a" of two, its
    # rig and attachment keys prefixed, each stepped as its own input (the name without the prefix)
    from types import SimpleNamespace as NS

    import bifilar.analysis.batch as batch
    import bifilar.estimation.factor_inputs as fi
    import bifilar.estimation.uncertainty as un

    nw, A, T_lin, r0, m_body, slope_A = 2, 0.3, 1.7, 1.01, 3.0, 0.02
    rng = np.random.default_rng(3)
    keys = (["gravity", "mass", "com.x", "com.y", "com.z"] + [f"{pre}length.{i}" for i in (1, 2)]
            + [f"{pre}{p}.{i}.{a}" for p in ("anchor", "attachment") for i in (1, 2) for a in "xyz"])
    g = {k: float(rng.normal()) for k in keys if k not in ("gravity", "mass") and not k.startswith("com.")}
    value = {k.split(":")[-1]: float(rng.uniform(0.2, 1.5)) for k in g}
    step = {k.split(":")[-1]: 1e-4 * (1 + 0.1 * n) for n, k in enumerate(keys)}
    failed = f"{pre}attachment.1.y"
    th = 0.4
    R = np.array([[math.cos(th), -math.sin(th), 0.0], [math.sin(th), math.cos(th), 0.0], [0.0, 0.0, 1.0]])
    base = NS(mass=m_body, n_wires=nw)

    monkeypatch.setattr(un, "_step", lambda scene, name, rel: step[name])
    monkeypatch.setattr(fi, "_perturbed_scene", lambda pb, h, scene, moves: NS(moved=moves[0]))
    monkeypatch.setattr(fi, "input_value", lambda scene, name: value[name])
    monkeypatch.setattr(fi, "n_modes", lambda ms: 1)
    monkeypatch.setattr(fi, "mac_matches", lambda base_ms, mss: [[0] for _ in mss])
    monkeypatch.setattr(batch, "rest_poses", lambda scenes, rest, errors=None: [None] * len(scenes))
    monkeypatch.setattr(batch, "modes_batch", lambda scenes, rests: ["modes"] * len(scenes))

    def runs(scenes, **kw):
        out = []
        for s in scenes:
            if s is base:
                out.append(NS(error="broken" if own_fails else None, period=None if own_fails else r0 * T_lin,
                              linear_period=T_lin))
            else:
                key, d = s.moved
                bad = key == failed
                out.append(NS(error="broken" if bad else None, period=None if bad else (r0 + g[key] * d) * T_lin,
                              linear_period=T_lin))
        return out

    monkeypatch.setattr(batch, "simulate_batch", runs)
    law = NS(dr_dp=np.ones(1), amplitude=A, slope=lambda: slope_A)
    models = [NS(hanging=NS(name=n, scene=NS(n_wires=nw)), R=R) for n in (["a", "b"] if pre else ["a"])]
    pb = NS(measurements=[NS(amplitude=A, hanging=0, cycles=10)], mode_index=[0], links=NS(hangings=lambda k: [0]),
            models=models)
    sig = {k: 1e-3 for k in keys}
    H = len(models)
    fi.factor_input_derivatives(pb, [law], keys, sig, [base] * H, [None] * H, [NS(modes=[NS(dominant=dominant)])] * H,
                                [[0]] * H)

    if own_fails:
        assert sorted(law.dr_dx_failed) == sorted(keys) and law.dr_dx == {k: 0.0 for k in keys}
        return
    gm = dict(g, **{failed: 0.0})
    want = {k: gm[k] for k in g if not k.startswith(f"{pre}anchor.2.")}
    want["gravity"] = 0.0
    for a in "xyz":
        want[f"{pre}anchor.2.{a}"] = -gm[f"{pre}anchor.1.{a}"]
        want[f"com.{a}"] = -sum(R[b, "xyz".index(a)] * gm[f"{pre}attachment.{i}.{'xyz'[b]}"] for i in (1, 2)
                                for b in range(3))
    geo = sum(value[k.split(":")[-1]] * want[k] for k in g)
    want["mass"] = (geo + (A * slope_A if dominant < 3 else 0.0)) / (2 * m_body)
    assert law.dr_dx_failed == [failed]
    assert set(law.dr_dx) == set(keys)
    for k in keys:
        assert law.dr_dx[k] == pytest.approx(want[k], rel=1e-6, abs=1e-9), k


# ---------------------------------------------------------------------------
# montecarlo.py: a draw's factor offset from its mass, CoM and gravity errors
# ---------------------------------------------------------------------------

def test_each_draw_moves_the_factor_by_its_own_mass_com_and_gravity_errors(boat):  # noqa: F811
    # as tests/test_factor_inputs.py's test for the rig inputs: a FactorDraw's offset is sum_j dr/dx_j e_j / r
    # (the amplitude exact: w = 1), here for the mass, the CoM and gravity, each e_j read back from the drawn
    # scene against the measured one (the mass and gravity their differences, the CoM from the attachments'
    # common shift -R dcom, the positions exact).  The drawn mass m (1 - dm) against an offset for +m dm
    # (s.mass * -> /) passed every test
    from bifilar.estimation.montecarlo import draw_monte_carlo

    from test_amplitude_law import A0, _invert, _periods
    from test_factor_inputs import EXACT

    T = float(_periods(boat, [A0])[0])
    res = _invert(boat, T, {**EXACT, "mass": 1e-2, "com": 2e-3, "gravity": 1e-3, "timing": 1e-9})
    law = res.amplitude_laws[0]
    assert law.dr_dx_failed == [] and law.dr_dx["gravity"] == 0.0
    r = float(law.factor(A0))
    R = res.problem.models[0].R
    for d in draw_monte_carlo(res, 4, np.random.default_rng(5)):
        s = d.hangings[0].scene
        shift = s.attachments - boat.attachments
        assert np.ptp(shift, axis=0) == pytest.approx(np.zeros(3), abs=1e-15)  # one common shift
        dcom = -R.T @ shift[0]
        e = {"mass": s.mass - boat.mass, "gravity": s.gravity - boat.gravity,
             **{f"com.{a}": dcom[q] for q, a in enumerate("xyz")}}
        expect = sum(v * e[k] for k, v in law.dr_dx.items()) / r
        assert abs(law.dr_dx["mass"] * e["mass"] / r) > 1e-7  # the mass's part is there to see
        assert float(d.offset[0]) == pytest.approx(expect, rel=1e-6, abs=1e-15)
    # unit: ones where the law has dr_dx; without it (a law the budget did not reach) m_hat / m_draw for an
    # inertia unknown (the motion depends on the mass only through I / m)
    assert all(np.all(d.unit == 1.0) for d in draw_monte_carlo(res, 2, np.random.default_rng(6)))
    law.dr_dx = None
    for d in draw_monte_carlo(res, 3, np.random.default_rng(6)):
        m_draw = d.hangings[0].scene.mass
        assert abs(m_draw / boat.mass - 1) > 1e-4
        assert d.unit == pytest.approx([boat.mass / m_draw], rel=1e-12)


def test_a_period_without_an_amplitude_beside_a_stated_ones_law_draws_unit_ones(boat):  # noqa: F811
    # the boat's torsion at 0.3 rad (a law with dr_dx) and its pitch at --amplitude 0 (no law): FactorDraws
    # whose unit is 1 (the law has dr_dx; the pitch has no factor to follow the mass); the law-less
    # measurement is skipped, not read (measured's first or -> and read None.dr_dp)
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.estimation.invert import invert
    from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
    from bifilar.estimation.montecarlo import FactorDraw, draw_monte_carlo

    from test_amplitude_law import A0, _periods

    T = float(_periods(boat, [A0])[0])
    Tp = next(m.period for m in linear_modes(boat, rest_pose(boat)).modes if m.label == "pitch")
    unc = {"length": 0.0, "position": 0.0, "mass": 1e-2, "com": 0.0, "gravity": 0.0, "amplitude": 0.0, "timing": 1e-9}
    ms = MeasurementSet([Hanging("reference", boat, np.eye(3))],
                        [Measurement("torsion", T, 1e-9, "period", "--period", amplitude=A0),
                         Measurement("pitch", Tp, 1e-9, "period", "--period", amplitude=0.0)])
    ms.uncertainty = dict(unc)
    res = invert(ms, solve_for=["Izz"], ladder=False, unc=dict(unc))
    assert res.method == "nonlinear" and res.amplitude_laws[1] is None and res.amplitude_laws[0].dr_dx is not None
    draws = draw_monte_carlo(res, 2, np.random.default_rng(1))
    assert all(isinstance(d, FactorDraw) and np.all(d.unit == 1.0) for d in draws)
