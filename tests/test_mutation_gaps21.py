"""Mutation round 21 (docs/mutation.md, "Round 21"): tests that kill the
surviving mutants of session 21's new code -- birge.py, parts_prior.py,
close_modes.py, local_fits.py, the soft clipping of signal_clip.py,
phase_lean, fit_window and kernel_values.py.  Every expected value comes
from a definition worked by hand, a closed form or an independent
formulation, never from the code's own output."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bifilar.estimation.birge import birge_factor, widen_timing
from bifilar.estimation.parts_prior import described_moments, parts_prior_warnings
from bifilar.estimation.uncertainty import LinearBudget

# ---------------------------------------------------------------- birge


def _fit(chi2, dof, passed=True, with_inputs=None):
    return {"passed": passed, "chi2": chi2, "dof": dof, "chi2_with_inputs": with_inputs}


def test_birge_factor_divides_chi2_by_its_degrees_of_freedom():
    """``B = sqrt(chi2 / dof)``: chi2 8 on 2 dof is 2 (chi2 x dof would give 4), 27 on 3 is 3; a fit
    check without a dof count has none (the documented ``dof > 0``): 1."""
    assert birge_factor(_fit(8.0, 2)) == pytest.approx(2.0, rel=1e-15)
    assert birge_factor(_fit(27.0, 3)) == pytest.approx(3.0, rel=1e-15)
    assert birge_factor({"passed": True, "chi2": 9.0, "chi2_with_inputs": None}) == 1.0
    assert birge_factor(_fit(9.0, 1, passed=False)) == 1.0
    assert birge_factor(_fit(math.nan, 1)) == 1.0


def _budget():
    """Izz (kg m^2) with two timing terms and one length term: contributions c_j, sigmas s_j written out."""
    contrib = {"timing[torsion]": np.array([3e-3]), "timing[roll]": np.array([-1e-3]), "length.1": np.array([2e-3])}
    cov = sum(np.outer(c, c) for c in contrib.values())
    return LinearBudget(["Izz"], cov, contrib, {"timing[torsion]": 1e-3, "timing[roll]": 2e-3, "length.1": 5e-4})


def test_widening_by_a_factor_between_one_and_two_scales_the_timing_sigmas_only():
    """A factor 1.5 (above 1: widened) multiplies each timing term's contribution and its stated sigma by
    1.5 and leaves the length's; the variance is the length's plus 1.5^2 the timing's (9 + 1 + 4 in
    1e-6 units -> 2.25 x 10 + 4)."""
    w = widen_timing(_budget(), 1.5)
    assert w.covariance[0, 0] == pytest.approx((2.25 * 10 + 4) * 1e-6, rel=1e-12)
    assert w.sigmas == pytest.approx({"timing[torsion]": 1.5e-3, "timing[roll]": 3e-3, "length.1": 5e-4}, rel=1e-12)
    assert w.contributions["length.1"][0] == 2e-3
    b = _budget()
    assert widen_timing(b, 1.0) is b and widen_timing(b, 0.5) is b


# ---------------------------------------------------------------- parts_prior


def _rot(axis, angle):
    """Rotation matrix about a unit ``axis`` by ``angle`` rad (Rodrigues)."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _ms(I_h, R, inertia_spec=None):
    """A stand-in measurement set: one hanging whose scene carries ``I_h`` (its own body axes) and the
    config's ``body.inertia`` spec; ``R`` maps reference body axes to the hanging's (``v_h = R v_ref``)."""
    cfg = {"body": {"inertia": inertia_spec}} if inertia_spec is not None else {}
    scene = SimpleNamespace(inertia=np.asarray(I_h, float), config=cfg)
    return SimpleNamespace(hangings=[SimpleNamespace(scene=scene, rotation=R)])


def test_described_moments_are_the_quadratic_form_along_the_reference_axes():
    """The moment about reference axis ``e_k`` is ``(R e_k) . I_h (R e_k)`` (the hanging's axes carry
    ``R e_k``): computed here one axis at a time, for a general rotation and a full tensor."""
    I_h = np.array([[5.0, 0.4, -0.3], [0.4, 7.0, 0.2], [-0.3, 0.2, 9.0]])
    R = _rot([1.0, 2.0, -0.5], 0.7)
    got = described_moments(_ms(I_h, R))
    for k, n in enumerate(("Ixx", "Iyy", "Izz")):
        u = R[:, k]
        assert got[n] == pytest.approx(float(u @ I_h @ u), rel=1e-12)
    assert set(got) == {"Ixx", "Iyy", "Izz"}


def test_described_moments_leave_out_the_null_and_the_unknown():
    """A component the config marks null is left out although the scene carries a start value for it."""
    got = described_moments(_ms(np.diag([1.0, 2.0, 3.0]), np.eye(3), {"principal": [1.0, 2.0, None]}))
    assert got == {"Ixx": 1.0, "Iyy": 2.0}
    got = described_moments(_ms(np.diag([1.0, 2.0, 3.0]), np.eye(3), {"tensor": [[1, 0, 0], [0, None, 0], [0, 0, 3]]}))
    assert got == {"Ixx": 1.0, "Izz": 3.0}


def test_parts_prior_compares_small_bodies_and_the_exact_third():
    """A body under 1 kg m^2 is compared like any other (0.02 described, 0.07 solved: 3.5 times); exactly a
    third (1.0 of 3.0, the float 1/3 itself) is "at most 1 / FACTOR": warned, 'half'."""
    assert len(parts_prior_warnings({"Izz": 0.02}, ["Izz"], [0.07])) == 1
    assert len(parts_prior_warnings({"Izz": 0.5}, ["Izz"], [0.1])) == 1
    w = parts_prior_warnings({"Iyy": 3.0}, ["Iyy"], [1.0])
    assert len(w) == 1 and "half" in w[0]


@pytest.mark.parametrize("described, value", [({"Izz": 0.0}, 5.0), ({"Izz": -1.0}, 5.0), ({}, 5.0),
                                              ({"Izz": 2.0}, 0.0), ({"Izz": 2.0}, -7.0),
                                              ({"Izz": 2.0}, math.nan), ({"Izz": 2.0}, math.inf)])
def test_parts_prior_skips_what_it_cannot_compare(described, value):
    """No ratio exists for a described moment that is zero, negative or absent, nor for a solved moment
    that is not a positive finite number (unphysical answers are another check's): no warning, no error."""
    assert parts_prior_warnings(described, ["Izz"], [value]) == []


# ---------------------------------------------------------------- close_modes


def test_periods_exactly_rel_apart_are_a_close_pair():
    """"differ by at most ``rel`` of the longer" includes the tie: 1 s and 1 - 2^-10 s with rel = 2^-10
    (every number exact in binary) are a pair; 1 - 2^-9 s is not."""
    from bifilar.analysis.close_modes import close_pairs

    M = SimpleNamespace
    assert close_pairs([M(period=1.0), M(period=1.0 - 2.0 ** -10)], rel=2.0 ** -10) == [(0, 1)]
    assert close_pairs([M(period=1.0), M(period=1.0 - 2.0 ** -9)], rel=2.0 ** -10) == []


def test_close_mode_warning_states_the_difference_in_percent_of_the_longer():
    """2 s and 2.0018 s differ by 0.0018 / 2.0018 = 0.0899 % of the longer: the warning states
    "0.09 %" (two digits; 0.0909 % would print 0.091, the difference times the period 0.36), whatever
    the sentence around it (trust22 rewords it)."""
    from bifilar.analysis.close_modes import close_mode_warnings

    M = SimpleNamespace
    w = close_mode_warnings([M(label="a", period=2.0), M(label="b", period=2.0018)])
    assert len(w) == 1 and "0.09 %" in w[0], w


# ---------------------------------------------------------------- local_fits


def test_local_fits_on_even_times_are_savitzky_golay_filters():
    """On evenly spaced times the local quartic fits over 9 samples are scipy's Savitzky-Golay filters
    (an independent implementation), ``mode="interp"`` at the record's ends (the window shifted inwards,
    as documented): value, first and second derivative of a random record agree to rounding."""
    from scipy.signal import savgol_filter

    from bifilar.estimation.local_fits import apply, local_weights

    h = 0.01
    t = 3.0 + h * np.arange(40)
    x = np.random.default_rng(21).normal(size=40)
    start, W = local_weights(t)
    assert W.shape == (40, 3, 9)
    for d in range(3):
        ref = savgol_filter(x, 9, 4, deriv=d, delta=h, mode="interp")
        assert np.allclose(apply(start, W, x, d), ref, rtol=0, atol=1e-9 * np.max(np.abs(ref))), d


def test_second_derivative_error_is_the_fits_response_to_a_complex_sinusoid():
    """``H_i(w)`` is what the second-derivative weights make of ``exp(i w t)`` at ``t_i``: applying them to
    ``cos`` and ``sin`` sampled at jittered times (``D cos + i D sin = H_i exp(i w t_i)``) gives the
    relative error ``|H_i / (-w^2) - 1|`` independently of the function's own sum."""
    from bifilar.estimation.local_fits import apply, local_weights, second_derivative_error

    rng = np.random.default_rng(7)
    h = 0.02
    t = h * (np.arange(60) + rng.uniform(-0.3, 0.3, 60))
    w = 2 * np.pi * 2.5  # 20 samples a period
    start, W = local_weights(t)
    D = apply(start, W, np.cos(w * t), 2) + 1j * apply(start, W, np.sin(w * t), 2)
    expect = np.abs(D * np.exp(-1j * w * t) / -w ** 2 - 1.0)
    got = second_derivative_error(t, start, W, w)
    assert np.allclose(got, expect, rtol=1e-9, atol=1e-12)
    assert 1e-4 < np.median(got) < 0.1  # a real, small error at 20 samples a period: the check has teeth


# ---------------------------------------------------------------- kernel_values

_SYM = {"xx": (0, 0), "yy": (1, 1), "zz": (2, 2), "xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}


def _rig(seed, n=3):
    """RigParams of an arbitrary (non-physical is fine) rig: a full symmetric positive definite inertia,
    general anchors and attachments, distinct Baumgarte alpha and beta."""
    from bifilar.models.maximal import RigParams

    rng = np.random.default_rng(seed)
    A = rng.normal(size=(3, 3))
    I = A @ A.T + 3 * np.eye(3)
    return RigParams(mass=np.array(2.5 + seed), gravity=np.array(9.81), inertia=I, inertia_inv=np.linalg.inv(I),
                     anchors=rng.normal(size=(n, 3)), attachments=rng.normal(size=(n, 3)),
                     lengths=1.0 + rng.uniform(size=n), baumgarte=np.array([1.3, 2.7 + seed]))


def _expected_values(P) -> dict:
    """Each kernel parameter from its documented definition, one at a time."""
    al, be = (float(x) for x in P.baumgarte)
    I, N = np.asarray(P.inertia), np.asarray(P.inertia_inv)
    m = float(P.mass)
    out = {"mass": m, "g": float(P.gravity), "bga": 2 * al, "hb": be ** 2 / 2}
    for k, (i, j) in _SYM.items():
        out["I" + k], out["N" + k], out["M" + k] = I[i, j], N[i, j], m * N[i, j]
    Ix, Iy, Iz = np.diag(I)
    out.update(Ex=(Iy - Iz) / Ix, Ey=(Iz - Ix) / Iy, Ez=(Ix - Iy) / Iz)
    for i, L in enumerate(P.lengths):
        out[f"L2{i}"], out[f"hbL{i}"] = L ** 2, be ** 2 * L ** 2 / 2
        for k, a in enumerate("xyz"):
            out[f"a{a}{i}"], out[f"p{a}{i}"] = P.anchors[i, k], P.attachments[i, k]
            if i:
                out[f"Da{a}{i}"] = P.anchors[0, k] - P.anchors[i, k]
                out[f"Dp{a}{i}"] = P.attachments[i, k] - P.attachments[0, k]
    return out


def test_kernel_values_follow_their_definitions_for_one_scene_and_a_batch():
    """The kernel's named values (mass, g, 2 alpha, beta^2 / 2, the inertia, its inverse and mass x
    inverse, Euler's coefficients, anchors, attachments, L^2, beta^2 L^2 / 2, wire i less wire 0) written
    out from the docstring for a general three-wire rig, alone and as scene 1 of a batch of two."""
    from bifilar.models.kernel_values import param_values
    from bifilar.models.maximal import RigParams

    P0, P1 = _rig(1), _rig(2)
    exp = _expected_values(P1)
    one = param_values(P1)
    batch = param_values(RigParams(**{k: np.stack([getattr(P0, k), getattr(P1, k)])
                                      for k in P1.__dataclass_fields__}))
    assert set(one) == set(exp) == set(batch)
    for name, v in exp.items():
        assert one[name] == pytest.approx(v, rel=1e-13, abs=1e-15), name
        assert batch[name].shape == (2,) and batch[name][1] == pytest.approx(v, rel=1e-13, abs=1e-15), name
        assert batch[name][0] == pytest.approx(_expected_values(P0)[name], rel=1e-13, abs=1e-15), name


def test_kernel_values_keep_a_two_dimensional_batch_shape():
    """A (2, 2) batch of four rigs (the batch shape is any leading shape): each value an array of shape
    (2, 2) whose entry [i, j] is that rig's own, by definition."""
    from bifilar.models.kernel_values import param_values
    from bifilar.models.maximal import RigParams

    rigs = [_rig(s) for s in range(4)]
    P = RigParams(**{k: np.stack([getattr(r, k) for r in rigs]).reshape((2, 2) + np.shape(getattr(rigs[0], k)))
                     for k in rigs[0].__dataclass_fields__})
    vals = param_values(P)
    for s, r in enumerate(rigs):
        for name, v in _expected_values(r).items():
            assert vals[name].shape == (2, 2), name
            assert vals[name][s // 2, s % 2] == pytest.approx(v, rel=1e-13, abs=1e-15), (name, s)


def _noisy_rig(scale):
    """A two-wire rig of size ``scale`` with a product of inertia 8 eps of its largest moment and one 32
    eps of it, an attachment coordinate 8 eps of its largest coordinate or length (its 3 * scale m wire)
    and one 32 eps of it."""
    from bifilar.models.maximal import RigParams

    eps = np.finfo(float).eps
    I = np.diag([1.0, 2.0, 10.0]) * scale ** 3
    I[0, 1] = I[1, 0] = 8 * eps * 10.0 * scale ** 3
    I[0, 2] = I[2, 0] = 32 * eps * 10.0 * scale ** 3
    anchors = np.array([[0.5, 0.0, 0.0], [-0.5, 0.0, 0.0]]) * scale
    att = np.array([[0.2, 8 * eps * 3.0, 32 * eps * 3.0], [-0.2, 0.0, 0.0]]) * scale
    return RigParams(mass=np.array(scale), gravity=np.array(9.81), inertia=I, inertia_inv=np.linalg.inv(I),
                     anchors=anchors, attachments=att, lengths=np.array([3.0, 2.0]) * scale,
                     baumgarte=np.array([1.0, 1.0]))


@pytest.mark.parametrize("shape", [(), (1,), (2, 2)])
def test_rounding_level_entries_are_zeroed_relative_to_their_own_scenes_scale(shape):
    """A product of inertia 8 eps of the largest moment and a coordinate 8 eps of the rig's largest
    coordinate or length are rounding noise (under 16 eps): exact zeros; 32 eps of them is kept.  The
    scale is each scene's own (a batch of rigs 1, 10, 100 and 1000 times as large: the same decisions in
    each) and its largest entry (8 eps of the largest moment is 80 eps of the smallest: still dropped)."""
    from bifilar.models.kernel_values import param_values
    from bifilar.models.maximal import RigParams

    eps = np.finfo(float).eps
    scales = [10.0 ** k for k in range(int(np.prod(shape)))]
    rigs = [_noisy_rig(sc) for sc in scales]
    if shape == ():
        P = rigs[0]
    else:
        P = RigParams(**{k: np.stack([getattr(r, k) for r in rigs]).reshape(shape + np.shape(getattr(rigs[0], k)))
                         for k in rigs[0].__dataclass_fields__})
    vals = {k: np.ravel(v) for k, v in param_values(P).items()}
    for n, sc in enumerate(scales):
        v = {k: float(x[n]) for k, x in vals.items()}
        assert v["Ixy"] == 0.0 and v["Ixz"] == 32 * eps * 10.0 * sc ** 3, sc
        assert v["py0"] == 0.0 and v["pz0"] == 32 * eps * 3.0 * sc, sc
        assert v["Dpy1"] == 0.0 and v["Dpz1"] == -32 * eps * 3.0 * sc, sc
        assert v["Nxz"] != 0.0 and v["Mxz"] != 0.0 and v["Izz"] == 10.0 * sc ** 3


# ---------------------------------------------------------------- phase_lean (signal_phasewander)


def _stepped_cosine(K, W, jumps, fs=30.0, offset=0.0):
    """``K`` cycles of exactly ``W`` samples at ``fs`` Hz whose phase steps by ``jumps[k]`` rad at the
    start of cycle ``k`` (the frequency fs / W): each cycle is a pure cosine of its own phase."""
    f = fs / W
    t = np.arange(K * W) / fs
    phi = np.repeat(np.cumsum(jumps), W)
    return t, offset + np.cos(2 * np.pi * f * t + phi), SimpleNamespace(t0=float(t[0]), t1=float(t[-1]), frequency=f)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_phase_lean_is_the_skew_of_the_cycles_phase_advances(sign):
    """Phase steps of 0.2 rad at every 4th of 40 cycle boundaries: the advances are 0.2 with probability
    exactly 1/4, else 0, whose skew is a Bernoulli's ``(1 - 2p) / sqrt(p (1 - p))`` = 2 / sqrt(3); steps
    back, ``-2 / sqrt(3)``.  Each cycle holds a whole period, so its demodulated phase is its own
    exactly."""
    from bifilar.estimation.signal_phasewander import phase_lean

    jumps = np.zeros(41)
    jumps[4::4] = 0.2 * sign
    t, y, fit = _stepped_cosine(41, 10, jumps)
    assert phase_lean(t, y, fit) == pytest.approx(sign * 2 / math.sqrt(3), rel=1e-9)


def test_phase_lean_is_blind_to_an_offset():
    """Each cycle's mean is taken out before demodulating: an offset 1000 times the amplitude leaves the
    lean as it is, here where a cycle is not a whole number of samples (1 / (f dt) = 10.4, W = 10, so the
    demodulator does not sum to zero over a row and an offset left in would leak into the phases)."""
    from bifilar.estimation.signal_phasewander import phase_lean

    rng = np.random.default_rng(5)
    fs, f = 30.0, 30.0 / 10.4
    t = np.arange(400) / fs
    y = np.cos(2 * np.pi * f * t) + 0.05 * rng.normal(size=t.size)
    fit = SimpleNamespace(t0=float(t[0]), t1=float(t[-1]), frequency=f)
    a, b = phase_lean(t, y, fit), phase_lean(t, y + 1000.0, fit)
    assert a is not None and b == pytest.approx(a, abs=1e-6)


def test_phase_lean_reads_records_of_six_cycles_of_eight_samples_and_not_fewer():
    """The documented minimum: 6 cycles of 8 samples (48 samples, W = 8 exactly) are read; 5 cycles, or
    7 samples a cycle (however many cycles), are not; nor a frequency that is zero, NaN or negative."""
    from bifilar.estimation.signal_phasewander import phase_lean

    rng = np.random.default_rng(3)
    jumps = rng.normal(0.0, 0.05, 60)
    t, y, fit = _stepped_cosine(6, 8, jumps[:6])
    assert phase_lean(t, y, fit) is not None
    assert phase_lean(*_stepped_cosine(5, 8, jumps[:5])) is None
    assert phase_lean(*_stepped_cosine(40, 7, jumps[:40])) is None
    assert phase_lean(*_stepped_cosine(5, 20, jumps[:5])) is None
    t, y, fit = _stepped_cosine(40, 10, jumps[:40])
    for f in (0.0, math.nan, -3.0):
        assert phase_lean(t, y, SimpleNamespace(t0=fit.t0, t1=fit.t1, frequency=f)) is None


def test_phase_lean_reads_up_to_max_samples():
    """``MAX_SAMPLES`` (12 000) samples are read, one more is not (a record over it is another check's)."""
    from bifilar.estimation.signal_phasewander import MAX_SAMPLES, phase_lean

    jumps = np.random.default_rng(4).normal(0.0, 0.05, 1201)
    t, y, fit = _stepped_cosine(1200, 10, jumps[:1200])
    assert t.size == MAX_SAMPLES == 12_000 and phase_lean(t, y, fit) is not None
    t = np.append(t, t[-1] + 1 / 30.0)
    y = np.append(y, y[-1])
    assert phase_lean(t, y, fit) is None


def test_a_skew_of_advances_that_do_not_vary_is_none():
    """Every cycle at the same phase: the advances are all exactly 0 and have no skew (None, not 0 / 0)."""
    from bifilar.estimation.signal_phasewander import _advance_skew

    assert _advance_skew(np.full(12, 0.3 + 0.4j)) is None


def test_leans_back_threshold_is_the_larger_of_the_fixed_bound_and_its_chance_scatter():
    """11 cycles: 10 advances, white noise's skew scatter sqrt(6 / 10) = 0.7746, 2.5 of it 1.936 (beyond
    LEAN_BACK's 0.3): -1.95 leans back, -1.90 does not (sqrt(6 / 11) or 12 / 10 in place of 6 / 10 would
    move the bound to 1.846 or 2.74).  1000 cycles: the bound is LEAN_BACK, strictly below it."""
    from bifilar.estimation.signal_phasewander import LEAN_BACK, leans_back

    assert 2.5 * math.sqrt(0.6) == pytest.approx(1.9365, abs=1e-4)
    assert leans_back(-1.95, 11) and not leans_back(-1.90, 11)
    assert leans_back(LEAN_BACK - 1e-9, 1000) and not leans_back(LEAN_BACK, 1000)
    assert not leans_back(None, 50)


def test_lean_direction_names_only_leans_strictly_beyond_its_bounds():
    """"above LEAN_FORWARD" and "below LEAN_BACK": the bounds themselves name no direction."""
    from bifilar.estimation.signal_phasewander import LEAN_BACK, LEAN_FORWARD, lean_direction

    assert lean_direction(LEAN_FORWARD) is None and lean_direction(LEAN_BACK) is None
    assert lean_direction(LEAN_FORWARD + 1e-9) == "forward" and lean_direction(LEAN_BACK - 1e-9) == "back"
    assert lean_direction(None) is None


# ---------------------------------------------------------------- fit_window (signal_timebase)


def test_fit_window_is_the_slice_of_the_samples_inside_the_closed_window():
    """Samples every 0.5 s from 0 to 4.5 s; the window [1, 3] s holds samples 2..6 (its ends are sample
    times, included: closed), the slice 2:7; [1.2, 2.9] holds 3..5; a window holding no sample, or a fit
    without a window (or half of one), reads the whole record 0:10."""
    from bifilar.estimation.signal_timebase import fit_window

    t = 0.5 * np.arange(10)
    W = SimpleNamespace
    assert fit_window(t, W(t0=1.0, t1=3.0)) == slice(2, 7)
    assert fit_window(t, W(t0=1.2, t1=2.9)) == slice(3, 6)
    assert fit_window(t, W(t0=0.0, t1=4.5)) == slice(0, 10)
    assert fit_window(t, W(t0=1.1, t1=1.3)) == slice(0, 10)
    assert fit_window(t, W(t0=1.0, t1=None)) == slice(0, 10)
    assert fit_window(t, W(t0=None, t1=3.0)) == slice(0, 10)
    assert fit_window(t, W(frequency=1.0)) == slice(0, 10)


# ---------------------------------------------------------------- find_soft_clipping (signal_clip)


def _knee(x, A):
    """A sensor law linear up to 0.6 of the amplitude ``A`` and of slope 1/2 beyond (a compressing knee):
    every sample within 0.6 A of the level is the truth, so the central fit (within 0.5 of its amplitude)
    recovers the true sinusoid exactly."""
    k = 0.6 * A
    return np.where(np.abs(x) <= k, x, np.sign(x) * (k + 0.5 * (np.abs(x) - k)))


def _knee_record(periods, t0=100.0, fs=200.0, T=1.0, A=2.0, c=5.0, phase=0.0):
    """``t`` from ``t0`` (s) over ``periods`` periods of ``T`` s at ``fs`` Hz; the true sinusoid
    ``A cos(2 pi (t - t0) / T + phase)`` and the record ``c + knee(it)``."""
    t = t0 + np.arange(int(round(periods * T * fs)) + 1) / fs
    x = A * np.cos(2 * np.pi * (t - t0) / T + phase)
    return t, x, c + _knee(x, A)


def _expected_ratios(t, x, y, c, A, T):
    """Per one-period window from ``t[0]`` (the last holding the remainder), ``r`` of each side computed
    from the TRUE sinusoid ``x`` (the documented ``r = sum((y - c) s) / sum(s^2)`` over ``|s| > 0.8 A``)."""
    n = int((t[-1] - t[0]) // T)
    edges = [int(np.searchsorted(t, t[0] + k * T)) for k in range(n)] + [t.size]
    out = []
    for a, b in zip(edges[:-1], edges[1:]):
        s, d = x[a:b], y[a:b] - c
        out.append([np.sum(d[m] * s[m]) / np.sum(s[m] ** 2) for m in (s > 0.8 * A, s < -0.8 * A)])
    return np.array(out)


@pytest.mark.parametrize("periods", [10.5, 10.0, 6.5])
def test_soft_clipping_of_a_knee_law_is_measured_from_the_true_sinusoid(periods):
    """A knee law (linear to 0.6 A, slope 1/2 beyond) on a sinusoid with an offset (5, against A = 2),
    starting at t = 100 s: one window per whole period (10 of 10.5 or of exactly 10; 6 of 6.5, the
    documented minimum),
    each side's ratio that of the TRUE sinusoid (the central fit recovers it exactly), the compression
    1 - their median mean -- near the continuous 1 - (0.5 + 0.3 * 2 sin(a) / (a + sin(a) cos(a))) =
    0.180, a = acos(0.8) -- and the samples left out exactly those beyond 0.3 A of the truth."""
    from bifilar.estimation.signal_clip import find_soft_clipping

    A, c = 2.0, 5.0
    t, x, y = _knee_record(periods, A=A, c=c)
    got = find_soft_clipping(t, y, 1.0)
    r = _expected_ratios(t, x, y, c, A, 1.0)
    assert got is not None and got["periods"] == int(periods) == len(r)
    assert got["compression"] == pytest.approx(1 - np.median(r.mean(axis=1)), abs=1e-9)
    assert got["ratios"] == pytest.approx(np.median(r, axis=0).tolist(), abs=1e-9)
    a = math.acos(0.8)
    assert got["compression"] == pytest.approx(1 - (0.5 + 0.6 * math.sin(a) / (a + math.sin(a) * math.cos(a))), abs=0.01)
    assert np.array_equal(got["mask"], np.abs(x) > 0.3 * A) and got["samples"] == int(np.sum(np.abs(x) > 0.3 * A))


def test_five_periods_are_too_few_and_a_linear_sensor_is_not_soft_clipped():
    """5.5 periods of the knee law: fewer than SOFT_MIN_PERIODS (6) windows, None; 10.5 periods of a
    linear sensor (gain 0.7, offset 5): every ratio exactly 1, no compression, None."""
    from bifilar.estimation.signal_clip import find_soft_clipping

    t, x, y = _knee_record(5.5)
    assert find_soft_clipping(t, y, 1.0) is None
    t, x, _ = _knee_record(10.5)
    assert find_soft_clipping(t, 5.0 + 0.7 * x, 1.0) is None


def test_soft_clipping_reads_periods_under_a_second_and_refuses_no_period():
    """A period of 0.4 s (a fast swing) is read like any other: the knee law over 10.5 of them is found
    with 10 windows; a period that is zero, negative, NaN or infinite reads nothing (None, no error)."""
    from bifilar.estimation.signal_clip import find_soft_clipping

    t, x, y = _knee_record(10.5, T=0.4, fs=500.0)
    got = find_soft_clipping(t, y, 0.4)
    assert got is not None and got["periods"] == 10
    for T in (0.0, -1.0, math.nan, math.inf):
        assert find_soft_clipping(t, y, T) is None


def _alternating_knee(h):
    """10 whole periods (A = 2, offset 5) whose knee slope alternates window by window so that the
    peaks' ratio is about 0.82 + h in even windows and 0.82 - h in odd ones (``r = sl + (1 - sl) g``,
    ``g`` = 0.6 A sum(s) / sum(s^2) ~ 0.641 over the peaks: linear in the slope ``sl``)."""
    A, c, g = 2.0, 5.0, 0.641
    t, x, _ = _knee_record(10.0, A=A, c=c)
    win = np.minimum(np.arange(t.size) // 200, 9)
    sl = np.where(win % 2 == 0, (0.82 + h - g) / (1 - g), (0.82 - h - g) / (1 - g))
    k = 0.6 * A
    y = c + np.where(np.abs(x) <= k, x, np.sign(x) * (k + sl * (np.abs(x) - k)))
    return t, x, y, A, c


@pytest.mark.parametrize("h, q_lo, q_hi", [(0.064, 0.7, 0.9), (0.041, 1.15, 1.4)])
def test_soft_clipping_needs_six_standard_errors_of_the_median(h, q_lo, q_hi):
    """Window means scattering by +-h about their median: the documented standard error of a median,
    1.2533 x the robust std 1.4826 MAD over sqrt(n), computed here from the TRUE sinusoid's ratios; the
    compression (~0.18) is 0.8 of 6 standard errors in the first record (not fired) and 1.25 of them in
    the second (fired).  A robust std without the 1.4826 (or 1.2533 / 1.4826) would fire both."""
    from bifilar.estimation.signal_clip import find_soft_clipping

    t, x, y, A, c = _alternating_knee(h)
    r = _expected_ratios(t, x, y, c, A, 1.0).mean(axis=1)
    med = np.median(r)
    se = 1.2533 * 1.4826 * np.median(np.abs(r - med)) / math.sqrt(r.size)
    q = (1 - med) / (6 * se)
    assert q_lo < q < q_hi and 1 - med > 0.045
    got = find_soft_clipping(t, y, 1.0)
    assert (got is not None) == (q > 1)
    if got is not None:
        assert got["compression"] == pytest.approx(1 - med, abs=1e-9) and got["periods"] == 10


def test_a_one_sided_knee_compresses_the_max_side_only():
    """The knee on the positive side only: the min side's ratio is exactly 1, the max side's that of the
    true sinusoid; the compression half the max side's shortfall (~0.09: fired)."""
    from bifilar.estimation.signal_clip import find_soft_clipping

    A, c = 2.0, 5.0
    t, x, _ = _knee_record(10.5, A=A, c=c)
    y = c + np.where(x > 0, _knee(x, A), x)
    r = _expected_ratios(t, x, y, c, A, 1.0)
    assert np.allclose(r[:, 1], 1.0, rtol=0, atol=1e-12) and np.all(r[:, 0] < 0.9)
    got = find_soft_clipping(t, y, 1.0)
    assert got is not None and got["periods"] == 10
    assert got["ratios"] == pytest.approx([float(np.median(r[:, 0])), 1.0], abs=1e-9)
    assert got["compression"] == pytest.approx(1 - np.median(r.mean(axis=1)), abs=1e-9)


def test_drop_soft_clipped_leaves_out_the_peaks_unless_too_few_samples_stay():
    """The samples kept are those within 0.3 A of the true sinusoid (counted here from it); exactly that
    many samples required still drops the peaks ("fewer than min_samples" is not met), one more leaves
    the record whole.  A hard-clipped record is left to the hard clip's rule."""
    from bifilar.estimation.signal_clip import drop_soft_clipped

    A, c = 2.0, 5.0
    t, x, y = _knee_record(10.5, A=A, c=c)
    inner = np.abs(x) <= 0.3 * A
    notes = []
    t2, y2, osc = drop_soft_clipped(t, y, {"frequency": 1.0}, notes, int(inner.sum()))
    assert np.array_equal(t2, t[inner]) and np.array_equal(y2, y[inner])
    assert osc["soft_clipped"]["samples_left_out"] == int((~inner).sum()) and notes == [osc["soft_clipped"]["line"]]
    notes = []
    t3, y3, osc = drop_soft_clipped(t, y, {"frequency": 1.0}, notes, int(inner.sum()) + 1)
    assert t3 is t and "soft_clipped" not in osc and notes == []
    t4, _, osc = drop_soft_clipped(t, y, {"frequency": 1.0, "clipped": {"line": "x"}}, [], 10)
    assert t4 is t and "soft_clipped" not in osc


def test_keeping_the_peaks_keeps_the_finding_and_says_the_peaks_stay():
    """keep_soft_clipped: the whole record back, its line the finding's (up to "; the ") followed by the
    peaks kept; none of the samples left out."""
    from bifilar.estimation.signal_clip import drop_soft_clipped, keep_soft_clipped

    t, x, y = _knee_record(10.5)
    whole = (t, y, {"frequency": 1.0}, ["earlier note"])
    _, _, osc = drop_soft_clipped(t, y, {"frequency": 1.0}, [], 10)
    first = osc["soft_clipped"]["line"]
    t2, y2, osc2, notes = keep_soft_clipped(whole, osc)
    sc = osc2["soft_clipped"]
    assert t2 is t and y2 is y and sc["kept"] and sc["samples_left_out"] == 0
    assert sc["line"].startswith(first[:first.index("; the ")] + "; the samples near the level alone")
    assert "left out of the fit" not in sc["line"] and notes == ["earlier note", sc["line"]]


def test_a_soft_fit_holds_within_a_quarter_of_the_whole_records_frequency_inclusive():
    """|f / f0 - 1| <= SOFT_MAX_SHIFT (0.25): 1.25 and 0.75 of f0 (binary-exact) hold, 1.26 does not;
    a NaN frequency does not."""
    from bifilar.estimation.signal_clip import soft_fit_holds

    osc = {"frequency": 2.0}
    assert soft_fit_holds(SimpleNamespace(frequency=2.5), osc) and soft_fit_holds(SimpleNamespace(frequency=1.5), osc)
    assert not soft_fit_holds(SimpleNamespace(frequency=2.52), osc)
    assert not soft_fit_holds(SimpleNamespace(frequency=math.nan), osc)
