"""Mutation round 15 (docs/mutation.md, "Round 15"): session 15's new code.

Each test kills mutants that survived the session's own tests, from a
truth computed another way: the quantiles of a known mixture by quadrature,
the moments of ``a z + b z^2`` by hand, the neutral pitch's ``Izz -
Iyz^2/Iyy`` on the knife edge, the elastic equilibrium by a general
minimiser, white noise's periodogram level.  Every test is cheap (no
model run beyond a rest pose and its modes)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, stats

from bifilar.estimation.budget import BudgetContext, interval_95
from bifilar.estimation.prior_inertia import (PLAUSIBLE_PRIOR_ERROR, WARN_SHIFT, PriorInertia, prior_warning,
                                              with_prior_curvature)
from bifilar.estimation.uncertainty import LinearBudget


# --- the stated priors' second-order term: budget and 95 % interval ------------------------------------------

def _budget(terms: dict) -> LinearBudget:
    """A one-unknown (``Izz``) budget of the given signed contributions (kg m^2)."""
    contrib = {k: np.array([float(v)]) for k, v in terms.items()}
    cov = sum(np.outer(c, c) for c in contrib.values())
    return LinearBudget(["Izz"], cov, contrib)


def _prior(names: list, quadratic=None, sens=None, stated=True, plausible=None, scales=None) -> PriorInertia:
    """A :class:`PriorInertia` of one unknown (``Izz``) with components
    ``names``, their second-order terms as given (kg m^2: ``quadratic``
    stated, ``plausible`` at the plausible error) and first-order
    sensitivities ``sens``."""
    Q = len(names)
    scales = np.ones(Q) if scales is None else np.asarray(scales, float)
    S = np.zeros((1, Q)) if sens is None else np.asarray(sens, float).reshape(1, Q)
    return PriorInertia(names, np.zeros(Q), scales, 0.1 * scales, 0.1, stated, ["Izz"], S, np.zeros((1, Q)),
                        quadratic={c: np.array([float(b)]) for c, b in (quadratic or {}).items()},
                        plausible_quadratic={c: np.array([float(b)]) for c, b in (plausible or {}).items()})


def _ctx(pri) -> BudgetContext:
    return BudgetContext(inputs=[], sigmas={}, G=np.zeros((1, 1)), T_hat=np.zeros(1), degenerate=[], scenes=[],
                         rests=[], modes=[], match=[], prior=pri)


def _mixture_quantiles(st: float, a: float, b: float, n: int, D: float = 0.0, mirror: bool = False):
    """2.5 and 97.5 % quantiles of ``st z1 + a z2 + b z2^2 + D U^2`` (z
    independent standard normal, U uniform on (0, 1): an unstated release
    amplitude's quadratic law), or of ``s (st z1 + a z2 + b z2^2)`` with a
    random sign s (``mirror``: a sigma-point surrogate's reading): the CDF
    ``E[Phi((x - a z2 - b z2^2 - D U^2) / st)]`` by Gauss-Hermite quadrature
    over z2 (160 nodes) and Gauss-Legendre over U (40 nodes: smooth
    integrands, errors far below 1e-6), and root finding; and each
    quantile's sampling std from ``n`` draws, ``sqrt(p (1 - p) / n) /
    pdf(q)`` (the pdf the same way)."""
    z, wz = np.polynomial.hermite_e.hermegauss(160)
    u, wu = np.polynomial.legendre.leggauss(40)
    u, wu = 0.5 * (u + 1), 0.5 * wu
    W = np.outer(wz / math.sqrt(2 * math.pi), wu).ravel()
    m = (a * z[:, None] + b * z[:, None] ** 2 + D * u[None, :] ** 2).ravel()
    F = lambda x: float(W @ stats.norm.cdf((x - m) / st))
    f = lambda x: float(W @ stats.norm.pdf((x - m) / st)) / st
    cdf, pdf = ((lambda x: 0.5 * (F(x) + 1 - F(-x))), (lambda x: 0.5 * (f(x) + f(-x)))) if mirror else (F, f)
    span = 10 * (st + abs(a) + abs(b) + abs(D))
    q = tuple(optimize.brentq(lambda x: cdf(x) - p, -span, span, xtol=1e-10) for p in (0.025, 0.975))
    return q, tuple(math.sqrt(0.025 * 0.975 / n) / pdf(x) for x in q)


@pytest.mark.parametrize("a, b, D", [(0.0, 1.5, 0.0), (0.0, -1.5, 0.0), (2.0, 0.6, 0.0), (-1.0, -0.8, 0.0),
                                     (0.0, 1.5, 2.0), (0.5, -1.0, -1.5)])
def test_the_interval_of_a_quadratic_prior_is_the_mixtures_with_each_side_at_least_the_others(a, b, D):
    """``interval_95`` of a timing term ``st`` (normal), a stated prior's
    ``a z + b z^2`` and an unstated release amplitude's ``D U^2`` (``u^2``
    law): the 2.5-97.5 % quantiles of the mixture (quadrature, above),
    each side at least the other terms' own quantile (where the prior is
    right, z = 0: the timing's 1.96 st, the amplitude's skew with it).
    b = +-1.5 st: the side away from the b z^2 tail is the others', the
    other the mixture's; a = 2, b = 0.6 and a = -1, b = -0.8: both sides
    the mixture's.  Tolerance: 4 of the 20 000 draws' quantile std (0.02
    st at a normal side, up to ~0.06 st in a b z^2 tail)."""
    st, p = 1.0, 10.0
    budget = _budget({"period[torsion]": st, "prior_inertia[Ixz]": a, "prior_inertia[Ixz] (2nd order)":
                      math.sqrt(2) * b, "offset": b, "amplitude[torsion]": D / 3})
    pri = _prior(["Ixz"], {"Ixz": b})
    pri.budgeted = True
    ctx = _ctx(pri)
    if D:
        ctx.amplitude = {"torsion": np.array([D])}
    lo, hi = interval_95(np.array([p]), budget, ctx)[0] - p
    (qlo, qhi), (slo, shi) = _mixture_quantiles(st, a, b, 20_000, D)
    (olo, ohi), (s0lo, s0hi) = _mixture_quantiles(st, 0.0, 0.0, 20_000, D)
    (want_lo, tol_lo), (want_hi, tol_hi) = min((qlo, slo), (olo, s0lo)), max((qhi, shi), (ohi, s0hi))
    assert lo == pytest.approx(want_lo, abs=4 * tol_lo) and hi == pytest.approx(want_hi, abs=4 * tol_hi), \
        (lo, hi, want_lo, want_hi, tol_lo, tol_hi)
    if D:
        return
    # not budgeted (below the sigma points' rule), no priors computed (a planner's std), no context: the
    # linear interval, value +- 1.96 std
    pri.budgeted = False
    z95 = stats.norm.ppf(0.975)
    for ctx in (_ctx(pri), _ctx(None), None):
        lo, hi = interval_95(np.array([p]), budget, ctx)[0] - p
        assert -lo == pytest.approx(hi) and hi == pytest.approx(z95 * budget.std[0], rel=1e-9)


def test_a_surrogate_alone_gives_the_hull_of_the_mirrored_and_the_plain_mixtures_intervals():
    """A sigma-point surrogate ``a z + b z^2`` of an input with a timing
    term and nothing else skewed: the interval is the hull of the
    quantiles of the mixture read with a random sign (the model and its
    mirror image: symmetric about the value) and of the mixture as built
    (its equal tails; session 28, docs/invert.md "Both readings"), by
    quadrature as above.  Here the low side is the mirrored reading's
    (-6.09 st) and the high side the plain mixture's b z^2 tail (+7.90 st
    against the mirrored +6.09; the session-27 rule fails it: ran)."""
    st, a, b, p = 1.0, 0.5, 1.5, 10.0
    budget = _budget({"period[torsion]": st, "length": a})
    ctx = _ctx(None)
    ctx.surrogate = {"length": (np.array([a]), np.array([b]))}
    lo, hi = interval_95(np.array([p]), budget, ctx)[0] - p
    (mlo, mhi), (smlo, smhi) = _mixture_quantiles(st, a, b, 20_000, mirror=True)
    (qlo, qhi), (slo, shi) = _mixture_quantiles(st, a, b, 20_000)
    (want_lo, tol_lo), (want_hi, tol_hi) = min((mlo, smlo), (qlo, slo)), max((mhi, smhi), (qhi, shi))
    assert lo == pytest.approx(want_lo, abs=4 * tol_lo) and hi == pytest.approx(want_hi, abs=4 * tol_hi), \
        (lo, hi, want_lo, want_hi)


def test_the_budgeted_curvature_makes_the_std_the_rms_distance_of_the_truth():
    """``with_prior_curvature``: the std is the RMS distance of ``st z0 + sum_c
    (a_c z_c + b_c z_c^2)`` from the value, ``st^2 + sum a^2 + 2 sum b^2 +
    (sum b)^2`` (E z^4 = 3; the cross terms b_c b_d of independent z), and
    the offset group is ``sum b``; below the rule (the std changed by less
    than LINEAR_ENOUGH = 2 % and the offset below OFFSET_ENOUGH = 10 % of
    it) the budget is returned unchanged, not budgeted."""
    st, a1, b1, b2 = 0.3, 0.2, 0.25, -0.1
    base = _budget({"period[torsion]": st, "prior_inertia[Ixz]": a1, "offset": 0.0})
    pri = _prior(["Ixz", "Ixy"], {"Ixz": b1, "Ixy": b2})
    # computed but not (yet) in a budget (invert skips the curvature where no std can be given): nothing drawn,
    # nothing added, the JSON says so
    assert pri.quadratic_terms(base) == {} and pri.quadratic_contributions()[0] == {}
    assert pri.to_json(np.array([1.0]))["second_order_budgeted"] is False
    out = with_prior_curvature(base, pri)
    assert pri.budgeted
    want = math.sqrt(st ** 2 + a1 ** 2 + 2 * (b1 ** 2 + b2 ** 2) + (b1 + b2) ** 2)
    assert out.std[0] == pytest.approx(want, rel=1e-12)
    assert out.contributions["offset"][0] == pytest.approx(b1 + b2, rel=1e-12)
    assert out.contributions["prior_inertia[Ixz] (2nd order)"][0] == pytest.approx(math.sqrt(2) * b1, rel=1e-12)
    # a Monte Carlo of the error model agrees (independent: 4e5 draws, 1 % on the RMS)
    rng = np.random.default_rng(15)
    z = rng.standard_normal((3, 400_000))
    e = st * z[0] + a1 * z[1] + b1 * z[1] ** 2 + b2 * z[2] ** 2
    assert out.std[0] == pytest.approx(math.sqrt(np.mean(e ** 2)), rel=0.01)
    # too small to matter: std + 1 %, offset 5 % of it (both under the rule) -> unchanged
    small = math.sqrt(((1.01 * 0.5) ** 2 - 0.5 ** 2) / 3)  # 2 b^2 + b^2 = the variance the 1 % adds
    base2 = _budget({"period[torsion]": 0.5})
    pri2 = _prior(["Ixz"], {"Ixz": small})
    assert small / 0.5 < 0.1 and with_prior_curvature(base2, pri2) is base2 and not pri2.budgeted
    # a budget that already holds an offset (the inputs' sigma points): the prior's mean adds to it, and the
    # rule judges the whole: 0.45 timing, 0.2 offset, b = 0.025 -> std 0.4924 -> 0.5044 (+2.4 %), budgeted
    base4 = _budget({"period[torsion]": 0.45, "offset": 0.2})
    pri4 = _prior(["Ixz"], {"Ixz": 0.025})
    out4 = with_prior_curvature(base4, pri4)
    assert pri4.budgeted and out4.contributions["offset"][0] == pytest.approx(0.225, rel=1e-12)
    assert out4.std[0] == pytest.approx(math.sqrt(0.45 ** 2 + 2 * 0.025 ** 2 + 0.225 ** 2), rel=1e-12)
    # the offset alone over the rule (a one-sided term that moves the std by < 2 %): budgeted
    pri3 = _prior(["Ixz", "Ixy"], {"Ixz": 0.03, "Ixy": 0.025})  # std +1.2 %, offset 11 % of it
    out3 = with_prior_curvature(base2, pri3)
    assert pri3.budgeted and out3.contributions["offset"][0] == pytest.approx(0.055, rel=1e-9)


# --- the unstated priors' warning to second order ------------------------------------------------------------

def test_the_plausible_shift_is_the_rms_of_a_z_plus_b_z_squared_over_the_components():
    """``plausible_shift`` (the warning's figure) and ``plausible_parts``
    (who moves it) against a Monte Carlo of independent 10 % errors of two
    components: first-order ``a_c = s_c 0.1 scale_c``, second-order ``b_c``
    (4e5 draws: 1 % on an RMS).  Each part is ``sqrt(a^2 + 3 b^2)`` of its
    component alone."""
    scales = np.array([2.0, 0.5])
    sens = np.array([0.3, 0.0])
    b = {"Iyy": 0.02, "Iyz": 0.09}
    pri = _prior(list(b), sens=sens, stated=False, plausible=b, scales=scales)
    a = sens * PLAUSIBLE_PRIOR_ERROR * scales
    rng = np.random.default_rng(151)
    z = rng.standard_normal((2, 400_000))
    parts = [a[q] * z[q] + b[c] * z[q] ** 2 for q, c in enumerate(pri.names)]
    assert pri.plausible_shift()[0] == pytest.approx(math.sqrt(np.mean((parts[0] + parts[1]) ** 2)), rel=0.01)
    for q in range(2):
        assert pri.plausible_parts()[0, q] == pytest.approx(math.sqrt(np.mean(parts[q] ** 2)), rel=0.01)
    # the JSON's ratio to the answer's std, none where there is no std (NaN: not computable; 0: an exact answer)
    sh = pri.plausible_shift()[0]
    for std, ratio in ((2.0, sh / 2.0), (float("nan"), None), (0.0, None)):
        assert pri.to_json(np.array([std]))["plausible_shift"]["Izz"]["in_std"] == ratio
    # the first-order figure alone where no second-order term was computed
    pri0 = _prior(list(b), sens=sens, stated=False, plausible={}, scales=scales)
    assert pri0.plausible_shift()[0] == pytest.approx(abs(a[0]), rel=1e-12)


def test_the_prior_warning_fires_past_a_third_of_the_std_and_names_the_components_that_move_it():
    """The unstated warning: the shift (above: ``sqrt(a^2 + 2 b^2 + b^2)``,
    one component) over ``WARN_SHIFT`` = 1/3 of the std, the movers by
    their part (largest first, above a tenth of the shift), the figure
    ``shift / std`` written; none for a stated prior."""
    b = {"Iyz": 0.3, "Ixy": 0.05, "Ixz": 0.001}
    pri = _prior(list(b), stated=False, plausible=b)
    sh = math.sqrt(2 * sum(v * v for v in b.values()) + sum(b.values()) ** 2)
    assert pri.plausible_shift()[0] == pytest.approx(sh, rel=1e-12)
    w = prior_warning(pri, np.array([sh / (1.05 * WARN_SHIFT)]))
    assert w is not None and "the config's Iyz, Ixy (not solved for) are taken as exact" in w, w
    assert f"Izz by {1.05 * WARN_SHIFT:.2g} of its std" in w, w
    assert prior_warning(pri, np.array([sh / (0.95 * WARN_SHIFT)])) is None
    # one mover: the verb agrees
    w1 = prior_warning(_prior(["Iyz"], stated=False, plausible={"Iyz": 0.3}), np.array([0.1]))
    assert "the config's Iyz (not solved for) is taken as exact" in w1, w1
    pri.stated = True
    assert prior_warning(pri, np.array([0.01])) is None


# --- a residual tone's own inflation (neartone) --------------------------------------------------------------

def test_a_tones_inflation_on_white_residuals_is_one_even_where_the_fits_is_below_two():
    """``tone_inflation`` on white residuals: the periodogram level of white
    noise of variance s2 is s2 at every frequency (I = |F|^2 / n), so the
    factor is 1 (its floor; the median of ~100 bins scatters by < 15 %),
    whatever the fit's own factor ``infl`` > 1, 1.5 as well as 5.  Where
    there is no level to read (no variance ``s2``, residuals identically
    0: a record the fit reproduced exactly) the fit's factor is kept."""
    from bifilar.estimation.signal_swing import tone_inflation

    rng = np.random.default_rng(1515)
    t = np.arange(0.0, 66.5, 1.0 / 60.0)
    r = 1e-4 * rng.standard_normal(t.size)
    s2 = float(np.mean(r ** 2))
    for infl in (1.5, 5.0):
        assert 1.0 <= tone_inflation(t, r, 0.30, s2, infl) < 1.15
    assert tone_inflation(t, r, 0.30, 0.0, 3.0) == 3.0
    assert tone_inflation(t, np.zeros_like(t), 0.30, s2, 3.0) == 3.0



def test_the_local_noise_level_of_white_noise_is_its_variance():
    """The level ``tone_inflation`` reads (``signal_checks._local_level``:
    the median of the neighbouring periodogram bins over ln 2, the median
    of an exponential being ln 2 times its mean) is the variance of white
    noise at every frequency (I = |F|^2 / n has mean s2).  Against a
    least-squares variance stated as s2 / 4 the factor is 2 (not floored,
    not capped); the mean over 25 frequencies 1 Hz apart (independent
    windows of ~100 bins, each ~10 % scatter in the level) is within 5 %."""
    from bifilar.estimation.signal_swing import tone_inflation

    rng = np.random.default_rng(1516)
    t = np.arange(0.0, 66.5, 1.0 / 60.0)
    r = 1e-4 * rng.standard_normal(t.size)
    s2 = float(np.mean((r - r.mean()) ** 2))
    k = [tone_inflation(t, r, f, s2 / 4, 50.0) for f in np.arange(1.0, 26.0)]
    assert np.mean(k) == pytest.approx(2.0, rel=0.05)

# --- the tone's other reading (tonewiden): its two shifts and the std -----------------------------------------

@pytest.mark.parametrize("scale", [0.8, 1.2])
def test_the_other_readings_shifts_follow_the_square_law_and_its_std_is_the_larger_gap(scale):
    """``joint_reading_std`` by hand from the law it documents: a mode's
    period shift goes as its amplitude squared (the found swing-y's 4e-4 s
    at 2 cm is 1e-4 s at its 1 cm bound), the modes' shifts add (the hidden
    swing-x and pitch at their bounds), the whole decays with the record
    as the found mode does (x decay^2, 0.9 here: a damped record) and
    scales as the joint release's ``scale`` squared (0.8 and 1.2) and at 1;
    the std is the larger distance of those two shifts from the answer's
    (the found mode's 4e-4 s)."""
    from types import SimpleNamespace

    from bifilar.estimation.signal_swing import JointReading, joint_reading_std

    jr = JointReading(["swing-x", "swing-y", "pitch"], scale, 0.01, 0.01)
    sec = SimpleNamespace(joint=jr, shift=4e-4, amplitude=0.02, decay=0.9, label="swing-y", tone_period=1.64)
    hidden = [SimpleNamespace(label="swing-x", shift=-1e-5), SimpleNamespace(label="pitch", shift=-2e-5)]
    m = SimpleNamespace(secondary=sec, hidden=hidden, label="torsion", field="--signal")
    at_bound = 4e-4 * (0.01 / 0.02) ** 2 - 1e-5 - 2e-5  # 7e-5 s
    want = (0.81 * scale ** 2 * at_bound, 0.81 * at_bound)
    std = joint_reading_std(m)
    assert jr.shifts == pytest.approx(want, rel=1e-12)
    assert std == pytest.approx(max(4e-4 - w for w in want), rel=1e-12) and jr.shift_std == std
    # a negative answer's shift (a mode that shortens the period): the gap is taken on the other side
    sec.shift, hidden[:] = -4e-4, []
    std = joint_reading_std(m)
    want = (-0.81 * scale ** 2 * 1e-4, -0.81 * 1e-4)
    assert jr.shifts == pytest.approx(want, rel=1e-12)
    assert std == pytest.approx(max(w + 4e-4 for w in want), rel=1e-12)
    # the found mode's own shift unknown (its run failed): no std covers both readings, refused naming --signal
    from bifilar.errors import InputError

    sec.shift = None
    with pytest.raises(InputError) as e:
        joint_reading_std(m)
    assert e.value.field == "--signal" and "--uncertainty release" in str(e.value)
    # no other reading: no group
    sec.joint = None
    assert joint_reading_std(m) == 0.0


def test_the_joint_reading_takes_the_worst_signs_and_the_part_beyond_the_timed_modes_own_tone(monkeypatch):
    """``infer_secondary``'s joint check where the timed mode's release
    alone makes part of the record's tone (``c0`` = 4e-4 of the torsion,
    the tones adding in amplitude as the code documents) and the joint
    release's tone depends on the velocity signs (the first combination
    the largest, the others 0.7 of it): the scale is the square law's
    ``sqrt((ratio - c0) / (c_joint_max - c0))`` with the WORST signs'
    tone, and the found swing-y ``0.01 sqrt((ratio - c0) / c_1cm)`` (its
    trial runs at 3 and 1.5 cm minus ``c0``: exponent 2).  The stand-in
    laws are test_tonepair's (the drone's measured ones)."""
    from types import SimpleNamespace

    from tests.test_tonepair import JOINT_AT_BOUND, SINGLE_1CM, T1, _fit, _problem

    from bifilar.estimation import signal_swing

    C0 = 4e-4

    def tones(hm, values, k, j, amplitude, a_j, cycles, rtol):
        if isinstance(j, tuple):
            worst = all(a > 0 for a in a_j)  # the first sign combination (every velocity +)
            return [(1.0 / T1, C0 + JOINT_AT_BOUND * (1.0 if worst else 0.7) * (abs(a_j[0]) / 0.01) ** 2)]
        if j == k:  # the timed mode's release alone
            return [(1.0 / T1, C0)]
        return [(1.0 / T1, C0 + SINGLE_1CM * (a_j / 0.01) ** 2)] if j == 2 else []

    monkeypatch.setattr(signal_swing, "_run_tones", tones)
    fit = _fit(2.36e-3)
    ratio = signal_swing.record_tones(SimpleNamespace(fit=fit, details={"quantity": "angle"}))[0]["ratio"]
    sec = signal_swing.infer_secondary(_problem(fit), 0, np.zeros(1))
    assert sec is not None and sec.label == "swing-y" and sec.exponent == pytest.approx(2.0, rel=1e-12)
    assert sec.amplitude == pytest.approx(0.01 * math.sqrt((ratio - C0) / SINGLE_1CM), rel=1e-9)
    assert sec.joint is not None
    assert sec.joint.scale == pytest.approx(math.sqrt((ratio - C0) / JOINT_AT_BOUND), rel=1e-9)


@pytest.mark.parametrize("scale", [1.1, 1.3])
def test_a_joint_release_beyond_its_uncertainty_of_the_bound_is_no_second_reading(scale, monkeypatch):
    """The joint release explains the record's tone only at a scale of the
    bound within its uncertainty of 1: ``scale <= 1 + 2 sigma``, sigma the
    found amplitude's relative std (the tone's noise over the law's
    exponent 2, hypot the 10 % calibration share: ~0.11, the limit ~1.22).
    Records whose tone the joint release makes at 1.1 and 1.3 times the
    bound (the stand-in's square law: tone = 1.21 and 1.69 x its tone at
    the bound): the first has the second reading, the second none (a
    single mode beyond the bound, read as before)."""
    from types import SimpleNamespace

    from tests.test_tonepair import JOINT_AT_BOUND, _fit, _problem, _tone_laws

    from bifilar.estimation import signal_swing

    monkeypatch.setattr(signal_swing, "_run_tones", _tone_laws([]))
    fit = _fit(scale ** 2 * JOINT_AT_BOUND)
    tone = signal_swing.record_tones(SimpleNamespace(fit=fit, details={"quantity": "angle"}))[0]
    limit = 1 + 2 * math.hypot(tone["ratio_std"] / tone["ratio"] / 2, signal_swing.CALIBRATION_SHARE)
    assert 1.15 < limit < 1.25  # the rule's figure here: both cases lie clear of it
    sec = signal_swing.infer_secondary(_problem(fit), 0, np.zeros(1))
    assert sec is not None and sec.label == "swing-y"
    if scale < limit:
        assert sec.joint is not None and sec.joint.scale == pytest.approx(scale, rel=0.03)
    else:
        assert sec.joint is None


# --- nearly dependent wires at rest (elastic): the strain that sets the rigid split ----------------------------

@pytest.mark.parametrize("eps, out", [(0.002, 0.01), (0.0, 0.3)])
def test_the_strain_scale_is_the_split_change_of_a_changed_length(eps, out):
    """``length_strain_scale`` (its first-order KKT solve) against finite
    differences of the equilibrium itself: each wire's length changed by
    +-1 % of ``e*`` (relative), the split found by ``elastic_rest`` on very
    stiff wires (EA 1e6 and 1e7 N, Richardson-extrapolated to rigid wires:
    the elastic split differs from the rigid one by O(T / (EA s^2)),
    measured linear in 1/EA), ``e* = (W / n) / max |dT_j / de_i|``.  The
    table with every anchor 1 cm out and a diagonal splayed 2 mm more
    (nearly dependent, e* 1.6e-4) and the one leaning 0.3 m out (e* 0.074,
    where the multipliers' own ``lam dL`` term is 7 % of it).  Measured
    agreement 3e-6; tolerance 1e-4 (the extrapolation's O(1/EA^2) and the
    differences' O(h^2)).  By symmetry (a half turn about z maps wire 1 to
    3 and 2 to 4) wires 1 and 2 are enough."""
    from test_restrank import _splayed

    from bifilar.analysis.elastic_rest import elastic_rest, length_strain_scale
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.scene import scene_with

    sc = _splayed(eps, out)
    rest = rest_pose(sc)
    lam = rest.tensions / np.linalg.norm(rest.wire_vectors, axis=1)
    es = length_strain_scale(sc, rest.com, rest.R, lam)
    L = np.asarray(sc.lengths, float)

    def fd(ea):
        worst, h = 0.0, 0.01 * es
        for i in (0, 1):
            T = []
            for s in (1, -1):
                Li = L.copy()
                Li[i] *= 1 + s * h
                T.append(elastic_rest(scene_with(sc, lengths=Li), ea, rest.com, rest.R)[2])
            worst = max(worst, float(np.max(np.abs(T[0] - T[1]))) / (2 * h))
        return (sc.mass * sc.gravity / 4) / worst

    rigid = (10 * fd(1e7) - fd(1e6)) / 9
    assert es == pytest.approx(rigid, rel=1e-4)


def _table_2m(eps: float):
    """The table on four 2 m vertical wires (test_dependent_wires_messages'
    ``vertical``, 10 kg) with anchors 1 and 3 splayed out along x by eps (m)."""
    import yaml
    from test_dependent_wires_messages import CORNERS, vertical

    from bifilar.config import scene_from_dict

    dct = yaml.safe_load(vertical(CORNERS, [2.0] * 4))
    dct["rig"]["anchors"][0][0] += eps
    dct["rig"]["anchors"][2][0] -= eps
    return scene_from_dict(dct, "test", warn=False)


def test_on_2m_wires_a_slack_verdict_within_the_strain_scale_is_the_stiffness_refusal():
    """The table on 2 m wires, anchors 1 and 3 splayed out by 1 cm: the
    rigid model leaves wires 2 and 4 slack by 0.0086 mm, less than the
    length change ``e* L`` (7.7e-6 of 2 m, 0.0154 mm) that moves the rigid
    split by a wire's mean load: the stiffness refusal, quoting that gap
    and ``e* L`` in mm (``e*`` checked against finite differences of the
    equilibrium above).  On 1 m wires the rule cannot tell ``e* L`` from
    ``e* / L``."""
    import re

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.errors import StiffnessNeededError

    with pytest.raises(StiffnessNeededError) as e:
        rest_pose(_table_2m(1e-2))
    msg = str(e.value)
    gap = float(re.search(r"slack by (\S+) mm", msg).group(1))
    es, esl = (float(v) for v in re.search(r"length by (\S+) of it \((\S+) mm\)", msg).groups())
    assert e.value.wires == [2, 4] and esl == pytest.approx(es * 2000, rel=0.07)  # each quoted to 2 digits
    assert es / 2 * 1000 < gap < esl  # slack by less than e* L, though more than e* / L


def test_the_stiffness_refusal_quotes_the_rigid_all_taut_split_and_a_wires_mean_load():
    """The table on 2 m wires, anchors 1 and 3 splayed out by 1 mm: refused
    naming rig.stiffness, wires 2 and 4 pushing.  The figures against the
    rigid all-taut statics solved another way: the pose that minimises the
    CoM's height with every wire at its length (SLSQP over the CoM and a
    rotation vector), its tensions the least squares of the six
    equilibrium equations there (residual below 1e-6 W); the pushing
    wires' tensions (3 digits quoted: 5e-3), a wire's mean load m g / n
    (24.5 N)."""
    import re

    from scipy.spatial.transform import Rotation

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.errors import StiffnessNeededError

    sc = _table_2m(1e-3)
    a, p, L = np.asarray(sc.anchors), np.asarray(sc.attachments), np.asarray(sc.lengths)
    W = sc.mass * sc.gravity

    def wires(x):
        R = Rotation.from_rotvec(x[3:]).as_matrix()
        return x[:3] + p @ R.T - a, p @ R.T

    cons = {"type": "eq", "fun": lambda x: np.sum(wires(x)[0] ** 2, axis=1) - L ** 2}
    x0 = np.r_[np.mean(a - p, axis=0) - [0.0, 0.0, 2.0], np.zeros(3)]
    sol = optimize.minimize(lambda x: x[2], x0, constraints=[cons], method="SLSQP",
                            options={"ftol": 1e-15, "maxiter": 200})
    d, w = wires(sol.x)
    u = -d / np.linalg.norm(d, axis=1)[:, None]  # each wire's pull on the body, per newton of tension
    A = np.vstack([u.T, np.cross(w, u).T])
    T, *_ = np.linalg.lstsq(A, np.r_[0.0, 0.0, W, 0.0, 0.0, 0.0], rcond=None)
    assert np.max(np.abs(A @ T - np.r_[0.0, 0.0, W, 0.0, 0.0, 0.0])) < 1e-6 * W
    with pytest.raises(StiffnessNeededError) as e:
        rest_pose(sc)
    msg = str(e.value)
    assert e.value.wires == [2, 4] and "wires 2, 4 would be pushing" in msg, msg
    quoted = [float(v) for v in re.search(r"pushing \(([-\d.]+) N, ([-\d.]+) N\)", msg).groups()]
    np.testing.assert_allclose(quoted, T[[1, 3]], rtol=5e-3)
    assert T[1] < 0 and f"a wire's mean load ({W / 4:.3g} N)" in msg


# --- starts on nearly dependent wires (nearfix): the refusal's figure off 1 m wires ---------------------------

def test_a_kite_on_2m_wires_is_refused_with_its_length_error_in_metres():
    """test_nearfix's kite table (one corner 5 cm in: its twist changes
    the squared lengths at second order by r_i^2 theta^2, whose self-stress
    share no rigid motion takes up) on 2 m wires at 0.05 rad: the length
    error is that share over 2 L (``|d|^2 - L^2 = 2 L dL``), 5.5e-6 m,
    above FREE_TOL x 2 m, refused with the new wording quoting it in
    metres (2 % for the closed form's O(theta^2) terms, as there)."""
    import re

    from test_dependent_wires_messages import scene_of, vertical

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.analysis.simulate import initial_state
    from bifilar.analysis.start_pose import FREE_TOL
    from bifilar.errors import InputError

    kite = [(0.35, 0.25), (-0.35, 0.25), (-0.30, -0.25), (0.35, -0.25)]
    sc = scene_of(vertical(kite, [2.0] * 4))
    rest = rest_pose(sc)
    tor = linear_modes(sc, rest).get("torsion")
    theta, L = 0.05, 2.0
    x, y = np.array(kite).T
    s = np.linalg.svd(np.vstack([np.ones(4), x, y]))[2][-1]  # the self-stress of vertical wires
    q = (x ** 2 + y ** 2) * theta ** 2 / 2  # (|d|^2 - L^2) / 2's second-order change
    closed = float(np.max(np.abs(s * (s @ q)))) / L
    assert closed > 2 * FREE_TOL * L
    with pytest.raises(InputError) as err:
        initial_state(sc, rest, tor, theta)
    msg = str(err.value)
    assert "along the self-stress of wires nearly dependent" in msg, msg
    found = float(re.search(r"closest start found is (\S+) m off", msg).group(1))
    assert found == pytest.approx(closed, rel=0.02)


def test_a_one_item_stiffness_list_is_every_wires_and_an_empty_one_is_refused():
    """``rig.stiffness`` as a list: one item is every wire's EA (as the
    scalar), an empty list names the field (the wires' count check alone
    would say "0 items"; either way one line on rig.stiffness)."""
    import yaml
    from test_dependent_wires_messages import CORNERS, vertical

    from bifilar.config import scene_from_dict
    from bifilar.errors import InputError

    dct = yaml.safe_load(vertical(CORNERS, [1.0] * 4))
    dct["rig"]["stiffness"] = [2.0e5]
    np.testing.assert_array_equal(scene_from_dict(dct, "test", warn=False).stiffness, np.full(4, 2.0e5))
    dct["rig"]["stiffness"] = []
    with pytest.raises(InputError) as e:
        scene_from_dict(dct, "test", warn=False)
    assert str(e.value).startswith("rig.stiffness:") and "\n" not in str(e.value)
