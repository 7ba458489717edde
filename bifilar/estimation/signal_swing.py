"""A recording whose release also started another mode (a hand release: the
torsion with a swing), and the second mode's amplitude the nonlinear model
must then be released with.

Why: a second mode running with the timed one shifts the timed mode's
period at second order in its amplitude (docs/design.md, "Torsion released
with a swing, session 12": a quadcopter-like body's 2.026 s torsion at 0.1
rad with a 3 cm swing-y runs 1.45 ms short, 500 times a camera record's
std), and ``invert``'s nonlinear model released the timed mode alone.

What the record shows: on a two-wire rig the swings are not in the
torsion's coordinate at first order (their shapes have no yaw), so a record
of the torsion angle does not show the swing's own frequency; it shows the
nonlinear motion's other oscillations (tones at combination frequencies,
``f_pitch - f_swing``, ``2 f_swing - f_torsion``), which a multi-mode fit
(``two_mode``, ``three_mode``, ``auto``) resolves beside the dominant mode.
Their size grows with the second mode's amplitude (as its square for a
swing whose tones are combinations: measured, not assumed).  Where the chosen model
is single-mode (a damped record's chirp can make every multi-mode fit
inadmissible), the tones are looked for in its residuals
(:func:`residual_tones`).

How the amplitude is found (:func:`infer_secondary`): each other mode of the
hanging is released in the model with the timed one (the timed mode
displaced as the record's fitted amplitude says, the other one moving
through its rest with the velocity of a trial amplitude,
:func:`~bifilar.analysis.simulate.two_mode_state`), the run's timed
coordinate fitted as the record was (``three_mode``), and the record's
strongest other oscillation looked for among the run's (its frequency within
:data:`FREQ_TOL`); a second run at half the trial amplitude gives the tone's
power law ``c ~ a^n``, and the record's tone (relative to the dominant
mode's amplitude) then gives ``a``.  Its std is the tone amplitude's
(white noise: ``noise sqrt(2 / N)``, times the fit's serial inflation) over
``n``, with :data:`CALIBRATION_SHARE` of ``a`` for what the release's other
details (the phase between the modes, a third mode started with them) do to
that calibration.

What the record cannot show (:func:`hidden_modes`, session 13): every other
mode, up to a stated bound on what the release started unseen
(``--uncertainty release``, m of a swing's travel, :data:`DEFAULT_RELEASE`;
over the longest wire, rad, for an angle mode), is released with the timed
one in one run at that bound, and its period shift enters the budget
(``hidden_second_mode``) as a shift anywhere between 0 and it
(:func:`hidden_shift_std`).

Units: periods s; amplitudes in the unit of each mode's normalised shape
(rad for a rotation-dominated mode, m for a translation-dominated one);
tones relative to the dominant mode's amplitude (unit-free; a rate record's
converted to angles by its frequencies).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import BifilarError
from .signal_swing_rate import DECAY_SHARE, decay_kernel, swing_decay  # noqa: F401  (their home since session 17)

#: a record's other oscillation counts when its amplitude exceeds this many of its std
TONE_Z = 5.0
#: a model tone matches the record's when their frequencies differ by at most this share
#: (or 5 of the record tone's frequency std, if larger): the model runs at the start point,
#: whose timed mode may be ~1 % off the record's
FREQ_TOL = 0.01
#: the trial amplitude of a candidate mode: rad, or this times the longest wire (m)
TRIAL_ANGLE = 0.02
#: the calibration's own relative uncertainty (the phase between the modes at the release,
#: a third mode started with them): measured on releases other than the model's own
#: (docs/design.md, session 12)
CALIBRATION_SHARE = 0.1
#: a record's oscillation the timed mode's release alone makes in the model within this share (or
#: :data:`TONE_Z` of its std) is the model's own, no sign of a second mode: the damped trifilar's swings at
#: 0.48 Hz, 0.16 % of its torsion (tests/test_chirp_coupled_swing.py), were taken for a 0.35 mm swing-x
EXPLAINED_SHARE = 0.3
#: a record's envelope decays measurably (and a found second mode is taken to decay with it) where its damping
#: ratio exceeds this many of its std (the amplitude law's criterion, :mod:`.signal_law`)
DECAY_Z = 3.0
#: integrator tolerance of the tone runs (at most)
TONE_RTOL = 1e-8
#: an inferred second mode beyond this (rad, or times the longest wire in m) is refused: the
#: period's shift then is no small correction and the model's release no record of the hand's
MAX_ANGLE = 0.15


@dataclass
class Secondary:
    """The second mode a recording's release started, as the model is released with it."""

    label: str  #: the mode's label
    index: int  #: its index among the hanging's modes at the prior (``HangingModel.modes0``)
    amplitude: float  #: rad or m (its normalised shape)
    amplitude_std: float  #: same unit
    tone_period: float  #: s, the record's oscillation that gave it
    tone_ratio: float  #: that oscillation's amplitude over the dominant mode's (angle-equivalent)
    exponent: float  #: the tone's power law in the amplitude, measured
    #: s: the model period's shift from the second mode at the estimate and its std (set by the law)
    shift: float | None = None
    shift_std: float | None = None
    #: rad or m: the amplitude at the record's start that the tone gives (``amplitude`` is the one the record's
    #: period refers to, ``decay`` times it, :func:`swing_decay`); None: the same as ``amplitude``
    amplitude_start: float | None = None
    decay: float = 1.0  #: ``amplitude`` over ``amplitude_start`` (1: the record does not decay measurably)
    #: (1/s, its std): the mode's own decay rate read off its tone (:mod:`.signal_swing_rate`), None where it is
    #: taken as the timed mode's (with :data:`DECAY_SHARE`)
    decay_rate: tuple | None = None
    #: runs of :func:`_check_joint_release` that failed (their sign combinations unchecked), out of ``joint_runs``
    joint_failed: int = 0
    joint_runs: int = 0
    #: the other reading of the record's tone, where the other modes released together within the bound make it
    #: too (:func:`_check_joint_release`); None where the tone has one reading
    joint: JointReading | None = None

    def to_json(self) -> dict:
        start = self.amplitude if self.amplitude_start is None else self.amplitude_start
        d = {"mode": self.label, "amplitude": self.amplitude, "amplitude_std": self.amplitude_std,
             "amplitude_start": start, "decay": self.decay,
             "decay_rate": None if self.decay_rate is None else self.decay_rate[0],
             "decay_rate_std": None if self.decay_rate is None else self.decay_rate[1],
             "tone_period": self.tone_period, "tone_ratio": self.tone_ratio, "tone_exponent": self.exponent,
             "period_shift": self.shift, "period_shift_std": self.shift_std}
        if self.joint is not None:
            d["joint_reading"] = self.joint.to_json()
        return d


@dataclass
class JointReading:
    """The record's tone read as every other mode of the hanging released with the timed one within the
    release bound (:func:`_check_joint_release`): their amplitudes ``scale`` times the bound, the tone's law
    taken as the found mode's."""

    labels: list  #: the modes released together (the found one among them)
    scale: float  #: their amplitudes over the bound that make the record's tone (the worst velocity signs)
    release: float  #: m, the release bound
    found_bound: float  #: the found mode's amplitude at the bound (rad or m, its normalised shape)
    #: s: the timed mode's period shift of this reading at ``scale`` (the worst signs) and at 1 (other signs, or a
    #: scale beyond 1 within its uncertainty: every mode at the bound), set by the law (:func:`joint_reading_std`)
    shifts: tuple | None = None
    #: s: the std the budget's ``tone_reading`` group carries: the larger difference of those shifts from the
    #: found mode's (the answer's)
    shift_std: float | None = None

    def to_json(self) -> dict:
        return {"modes": list(self.labels), "scale": self.scale, "release": self.release,
                "period_shift": None if self.shifts is None else list(self.shifts),
                "period_shift_std": self.shift_std}


def record_tones(m) -> list[dict]:
    """The resolved other oscillations of measurement ``m``'s fitted record
    (its fit's modes after the dominant one), strongest first: ``period``
    (s), ``ratio`` (amplitude over the dominant mode's, angle-equivalent:
    a rate record's times ``omega_0 / omega_j``), ``ratio_std``, ``period_std``.
    Kept where the amplitude exceeds :data:`TONE_Z` of its std and the
    oscillation has two cycles in the record; not a mode that dies within
    two of its cycles (a transient), nor, where the record decays
    measurably, one within 2 / T_record of the fundamental (the chirp's, as
    :func:`residual_tones` skips it): where one is set aside, the fit's
    residuals are read as a single-mode fit's are (docs/design.md,
    "damprate, session 16")."""
    fit = getattr(m, "fit", None)
    if fit is None or not (getattr(fit, "modes", None) or []):
        return []
    if len(fit.modes) < 2:
        return residual_tones(m)
    m0 = fit.modes[0]
    a0, w0 = float(m0["amplitude"]), float(m0["omega"])
    if not a0 > 0:
        return []
    n = max(int(fit.n_samples), 1)
    s_amp = float(fit.noise_std) * math.sqrt(2.0 / n) * max(float(fit.std_inflation or 1.0), 1.0)
    T_rec = float(fit.t1 - fit.t0)
    rate = m.details.get("quantity") == "rate"
    # a decaying record's chirp (the timed mode's frequency following its amplitude) is fitted by a multi-mode
    # model as a mode beside the dominant one; residual_tones skips such peaks, and so is such a mode skipped; and a
    # mode that dies within two of its cycles (sigma > f / 2) is a transient of the record's start, no free mode's
    # tone (audit15 row 1: 2.1-2.2 s at 0.26-0.28 1/s, 1.3-2.2 / T_record from the torsion, read as a metre of swing-x)
    chirp = 4 * math.pi / T_rec if _decays(fit) else 0.0  # rad/s: 2 / T_record
    out, skipped = [], False
    for md in fit.modes[1:]:
        a, w = float(md["amplitude"]), abs(float(md["omega"]))
        if not (w > 0 and a > TONE_Z * s_amp and w * T_rec >= 4 * math.pi):
            continue
        if abs(w - abs(w0)) <= chirp or float(md.get("sigma", 0.0) or 0.0) > w / (4 * math.pi):
            skipped = True
            continue
        conv = (w0 / w) if rate else 1.0
        out.append({"period": 2 * math.pi / w, "period_std": float(md.get("std", 0.0) or 0.0),
                    "ratio": a / a0 * conv, "ratio_std": s_amp / a0 * conv,
                    "sigma": float(md.get("sigma", 0.0) or 0.0), "sigma_std": float(md.get("sigma_std", 0.0) or 0.0)})
    if skipped:  # the tones the fit left in its residuals, where it spent a mode on the chirp
        out += residual_tones(m)
    return sorted(out, key=lambda d: -d["ratio"])


def _decays(fit) -> bool:
    """Whether ``fit``'s record decays measurably: its damping ratio beyond :data:`DECAY_Z` of its std (the
    amplitude law's criterion)."""
    zeta = float(getattr(fit, "damping_ratio", float("nan")))
    modes = getattr(fit, "modes", None) or [{}]
    z_std = float(modes[0].get("damping_ratio_std", 0.0) or 0.0)
    return math.isfinite(zeta) and math.isfinite(z_std) and zeta > DECAY_Z * z_std


def residual_tones(m) -> list[dict]:
    """The other oscillations left in the residuals of measurement ``m``'s
    single-mode fit (``viscous``, ``quadratic``, ...), in
    :func:`record_tones`' form with ``source`` ``"residual"``: each
    significant periodogram peak (:func:`~bifilar.estimation.signal_checks.residual_peaks`)
    that is no harmonic and lies more than 2 / T_record from the
    fundamental, fitted there as one damped cosine (least squares on the
    residuals: frequency, decay rate, amplitude at the window's start, its
    std from the fit's covariance times the fit's serial inflation); kept
    where the amplitude exceeds :data:`TONE_Z` of its std and the
    oscillation has two cycles in the record.

    Why: a damped record's chirp can make every multi-mode fit inadmissible
    (a spurious oscillation beside the dominant one), so ``auto`` chooses a
    single-mode model whose fit holds no other mode, and a swing the record
    shows was never looked for (docs/design.md, "dampswing, session 13":
    the quadcopter's 2.566 s tone at 3e-3 of the torsion, Izz z -3.7)."""
    from scipy.optimize import least_squares

    from .signal_checks import residual_peaks

    fit = m.fit
    t, r = getattr(fit, "t_used", None), getattr(fit, "residuals", None)
    m0 = fit.modes[0]
    a0, w0 = float(m0["amplitude"]), float(m0["omega"])
    if t is None or r is None or len(t) < 16 or not a0 > 0:
        return []
    t, r = np.asarray(t, float), np.asarray(r, float)
    T_rec = float(t[-1] - t[0])
    f0 = w0 / (2 * math.pi)
    try:
        peaks = residual_peaks(t, r, f0)
    except (ValueError, np.linalg.LinAlgError):
        return []
    rate = m.details.get("quantity") == "rate" if isinstance(m.details, dict) else False
    infl = max(float(fit.std_inflation or 1.0), 1.0)
    tau = t - t[0]
    sg0 = float(m0.get("sigma", 0.0) or 0.0)
    out = []
    for pk in peaks:
        f = float(pk["frequency"])
        if pk["harmonic"] is not None or abs(f - f0) <= 2.0 / T_rec or f * T_rec < 2.0:
            continue

        def res(q):
            e = np.exp(-q[1] * tau)
            return e * (q[2] * np.cos(q[0] * tau) + q[3] * np.sin(q[0] * tau)) - r

        w = 2 * math.pi * f
        c, s_ = np.cos(w * tau), np.sin(w * tau)
        ab = np.linalg.lstsq(np.c_[c, s_], r, rcond=None)[0]
        try:
            sol = least_squares(res, [w, sg0, ab[0], ab[1]], x_scale="jac")
        except (ValueError, np.linalg.LinAlgError):
            continue
        q = sol.x
        if not (sol.success and abs(q[0] - w) <= 2 * math.pi / T_rec and q[0] * T_rec >= 4 * math.pi):
            continue
        dof = max(t.size - 4, 1)
        s2 = float(np.sum(sol.fun ** 2)) / dof
        try:
            cov = s2 * np.linalg.inv(sol.jac.T @ sol.jac)
        except np.linalg.LinAlgError:
            continue
        a = math.hypot(q[2], q[3])
        if not a > 0:
            continue
        g = np.array([q[2], q[3]]) / a
        k_t = tone_inflation(t, sol.fun, q[0] / (2 * math.pi), s2, infl)  # the noise about the tone, without it
        s_amp = math.sqrt(max(float(g @ cov[2:4, 2:4] @ g), 0.0)) * k_t
        sd_w = math.sqrt(max(float(cov[0, 0]), 0.0)) * k_t
        if not (s_amp > 0 and a > TONE_Z * s_amp):
            continue
        conv = (w0 / q[0]) if rate else 1.0
        T = 2 * math.pi / q[0]
        out.append({"period": T, "period_std": T / q[0] * sd_w, "ratio": a / a0 * conv,
                    "ratio_std": s_amp / a0 * conv, "source": "residual", "sigma": float(q[1]),
                    "sigma_std": math.sqrt(max(float(cov[1, 1]), 0.0)) * k_t})
    return sorted(out, key=lambda d: -d["ratio"])


def tone_inflation(t, r, f: float, s2: float, infl: float) -> float:
    """Factor (1 .. ``infl``) by which the residuals' serial correlation
    inflates the least-squares std of a tone fitted at ``f`` (Hz) whose
    fit leaves ``r`` ([y], at times ``t``, s: the residuals with the tone
    removed, so that its own sidelobes do not count as noise) of
    least-squares variance ``s2`` ([y]^2): ``sqrt(S(f) / s2)``, ``S(f)``
    the periodogram level of ``r`` around ``f`` (the median of the
    neighbouring bins, the tone's own +-3 excluded:
    ``signal_checks._local_level``; white noise of variance ``s2`` has
    level ``s2``).

    Why not the fit's ``std_inflation`` (the AR density at the fundamental):
    a tone beside the fundamental (the swing's ``2 f_s - f_t`` on a rig whose
    swing and torsion nearly coincide) raises the density there, and the low
    order AR model, which cannot resolve 0.15 Hz at 60 samples/s, spreads it
    over every low frequency: on audit15's record (row 2) the AR factor is
    5.6 at the fundamental and 6.3 at the far tone (0.308 Hz), where the
    periodogram's local level is 0.74 of ``s2``; the tone, 325x the noise
    level, read 3.3 of its std and was dropped (docs/design.md, "neartone,
    session 15").  Capped at ``infl`` (a tone's
    std never grows over the old rule's) and floored at 1 (never below the
    least-squares std, whose ``s2`` holds every unfitted tone's power too):
    where the residuals are white (``infl`` 1) nothing changes."""
    if not infl > 1.0 or not s2 > 0:
        return infl
    from .signal_checks import _local_level, periodogram

    try:
        fr, I, _ = periodogram(t, r)
    except (ValueError, np.linalg.LinAlgError):
        return infl
    k = int(np.argmin(np.abs(fr - f)))
    S = _local_level(I, k)
    if not S > 0:
        return infl
    return float(min(infl, max(1.0, math.sqrt(S / s2))))


def _run_tones(hm, values, k: int, j, amplitude: float, a_j, cycles: float, rtol: float):
    """The other oscillations (``three_mode`` fit, else ``two_mode``) of the timed coordinate of a
    model run with base mode ``k`` released at ``amplitude`` and base mode
    ``j`` started at ``a_j`` (or, ``j`` and ``a_j`` tuples, each of those
    modes at its signed amplitude at once, :func:`~bifilar.analysis.simulate.multi_mode_state`):
    list of (frequency Hz, ratio to the dominant)."""
    from ..analysis.simulate import multi_mode_state, relative_pose, simulate, two_mode_state
    from .signal import fit_period
    from .signal_io import SignalError

    scene = hm.scene(values)
    rest, ms, match = hm.locate(scene)
    kk = int(match[k])
    mk = ms.modes[kk]
    if isinstance(j, tuple):
        y0 = multi_mode_state(scene, rest, mk, amplitude, [(ms.modes[int(match[i])], a) for i, a in zip(j, a_j)])
    else:
        y0 = two_mode_state(scene, rest, mk, amplitude, ms.modes[int(match[j])], a_j)
    # a tone's amplitude to ~1e-4 of itself needs no more than rtol 1e-8 (the factor's runs use 1e-10)
    sim = simulate(scene, kk + 1, amplitude, cycles, rest=rest, modes=ms, y0=y0, t_end=cycles * mk.period,
                   rtol=max(rtol, TONE_RTOL), check=False, samples_per_period=32)
    y = relative_pose(sim.y, rest, mk.dominant)
    try:
        fit = fit_period(sim.t, y, "three_mode", crossing_check=False, split_check=False)
    except SignalError:  # no third oscillation beside the dominant one to fit: its tones lie elsewhere, if any
        fit = None
    if fit is None or len(fit.modes) < 2:  # a noise-free run's third oscillation may not be resolved from the first two
        fit = fit_period(sim.t, y, "two_mode", crossing_check=False, split_check=False)
    if len(fit.modes) < 2 or not float(fit.modes[0]["amplitude"]) > 0:  # no multi-mode fit (its fallback)
        return []
    a0 = float(fit.modes[0]["amplitude"])
    out = [(abs(float(d["omega"])) / (2 * math.pi), float(d["amplitude"]) / a0) for d in fit.modes[1:]]
    # the tones the multi-mode fit leaves in its residuals (a swing's f_pitch - f_swing where its strongest
    # tone lies beside the dominant: docs/design.md, "neartone, session 15")
    from types import SimpleNamespace

    out += [(1.0 / d["period"], d["ratio"]) for d in residual_tones(SimpleNamespace(fit=fit, details={}))]
    return out


def _match(tones, f: float, tol: float):
    hits = [(abs(fs - f), r) for fs, r in tones if abs(fs - f) <= tol]
    return min(hits)[1] if hits else None


def infer_secondary(pb, k: int, p, rtol: float = 1e-10):
    """The second mode measurement ``k``'s record shows its release started
    (module docstring), at the unknowns ``p``: a :class:`Secondary`, None
    where the record resolves no other oscillation, or the string of a
    warning where it does but no other mode released with the timed one
    makes it (the record then holds a motion the model does not).  Raises
    :class:`~bifilar.errors.InputError` naming the measurement's field where
    the inferred mode is beyond :data:`MAX_ANGLE`."""
    from ..errors import InputError

    m = pb.measurements[k]
    tones = record_tones(m)
    if not tones or not m.amplitude:
        return None
    tone = tones[0]
    f_rec = 1.0 / tone["period"]
    tol = max(FREQ_TOL * f_rec, 5 * tone["period_std"] / tone["period"] ** 2)
    hm = pb.models[m.hanging]
    values = pb.values(p)
    k0 = pb.mode_index[k]
    # the record's tones are its fit's amplitudes at the window's start: the model runs from the amplitude there
    # (a decaying record's fitted period refers to a smaller one, ``decay`` times it)
    decay = m.details.get("decay") if isinstance(m.details, dict) else None
    A = m.amplitude / decay if decay and 0 < decay <= 1 else m.amplitude
    Lmax = float(np.max(hm.scene(values).lengths))
    try:  # the timed mode's release alone makes some other oscillations too (the model has those already)
        c0 = _match(_run_tones(hm, values, k0, k0, A, 0.0, m.cycles, rtol), f_rec, tol)
    except BifilarError:
        c0 = None
    if c0 is not None and abs(tone["ratio"] - c0) <= max(TONE_Z * tone["ratio_std"], EXPLAINED_SHARE * tone["ratio"]):
        return None
    best = None
    for j, mj in enumerate(hm.modes0.modes):
        if j == k0 or not mj.period:
            continue
        a_t = TRIAL_ANGLE * (1.0 if mj.dominant >= 3 else Lmax)
        try:
            c1 = _match(_run_tones(hm, values, k0, j, A, a_t, m.cycles, rtol), f_rec, tol)
            if c1 is None:
                continue
            c2 = _match(_run_tones(hm, values, k0, j, A, 0.5 * a_t, m.cycles, rtol), f_rec, tol)
        except BifilarError:
            continue
        # the part the second mode adds to what the timed mode's release alone makes (amplitudes, not phasors:
        # the two differ in frequency only by the run's nonlinear shift, so they add nearly in phase)
        c1, c2, cr = c1 - (c0 or 0.0), (c2 - (c0 or 0.0)) if c2 else None, tone["ratio"] - (c0 or 0.0)
        if not (c1 > 0 and cr > 0):
            continue
        n = math.log2(c1 / c2) if c2 and c2 > 0 else 2.0
        if not 0.5 <= n <= 4.0:  # not a tone of this mode (the timed mode's own, or noise in the run's fit)
            continue
        a = a_t * (cr / c1) ** (1.0 / n)
        rel = math.hypot(tone["ratio_std"] / cr / n, CALIBRATION_SHARE)
        cand = Secondary(mj.label, j, float(a), float(rel * a), tone["period"], tone["ratio"], float(n))
        if best is None or abs(cand.amplitude) / (1.0 if mj.dominant >= 3 else Lmax) < \
                abs(best.amplitude) / (1.0 if hm.modes0.modes[best.index].dominant >= 3 else Lmax):
            best = cand  # several explain it: the smallest motion that does
    lab = m.label
    if best is None:  # the answer leaves it out: covered for a camera's oscillation (no shift) and, by the hidden
        # modes' budget, for a motion of the rig within the release bound, not beyond it (the quadcopter's torsion with
        # its swing-y unattributed: 1 cm, z -0.58; 3 cm, z -5.3; docs/design.md, "damprate, session 16")
        return (f"mode '{lab}': the record holds an oscillation at {tone['period']:.4g} s ({tone['ratio']:.2g} of "
                f"the {lab}'s amplitude, {tone['ratio'] / tone['ratio_std']:.0f} of its std) that no other mode "
                "released with it makes in the model: the answer leaves it out, and its std holds it only if it is "
                "the camera's or its mount's, or a motion of the rig within the release bound (--uncertainty "
                "release); a larger motion shifts the period beyond that std: release more cleanly (let go without "
                "a push or a swing)")
    limit = MAX_ANGLE * (1.0 if hm.modes0.modes[best.index].dominant >= 3 else Lmax)
    if abs(best.amplitude) > limit:
        raise InputError(m.field, (
            f"mode '{lab}': the record's oscillation at {tone['period']:.4g} s says the release also started the "
            f"{best.label} mode at about {best.amplitude:.3g} (beyond {limit:.3g}): a second motion that large "
            f"shifts the {lab}'s period by more than the model of its release can answer for; release more "
            "cleanly (let go without a push or a swing) and record again"))
    best.joint = _check_joint_release(ToneContext(pb, k, hm, values, k0, A, tone, f_rec, tol, c0, Lmax, rtol), best)
    best.amplitude_start = best.amplitude
    g, g_rel = swing_decay(m)
    if g != 1.0:  # the amplitude the record's period refers to (the model runs undamped at it)
        from .signal_swing_rate import own_decay

        g, g_rel, best.decay_rate = own_decay(m, tone, hm, best.index, k0, g, g_rel)
        rel = math.hypot(best.amplitude_std / abs(best.amplitude), g_rel)
        best.amplitude, best.decay = best.amplitude * g, g
        best.amplitude_std = rel * abs(best.amplitude)
    return best


@dataclass(frozen=True)
class ToneContext:
    """What :func:`infer_secondary` knows of measurement ``k``'s record and model when it checks a found mode
    (:func:`_check_joint_release`)."""

    pb: object  #: the problem
    k: int  #: the measurement's index
    hm: object  #: its hanging's model
    values: dict  #: the model's values at the unknowns
    k0: int  #: the timed mode's index among the hanging's modes at the prior
    A: float  #: the timed mode's amplitude at the record's start (rad or m)
    tone: dict  #: the record's strongest other oscillation (:func:`record_tones`)
    f_rec: float  #: Hz, its frequency
    tol: float  #: Hz, how far a model tone's frequency may lie from it
    c0: float | None  #: the tone the timed mode's release alone makes (over its amplitude), None if none
    Lmax: float  #: m, the longest wire
    rtol: float  #: the tone runs' integrator tolerance


def _check_joint_release(ctx: ToneContext, best: Secondary) -> JointReading | None:
    """The other reading (:class:`JointReading`) of measurement ``k``'s
    record where the record's tone (``tone``, at ``f_rec`` Hz within ``tol``)
    gives the second mode ``best`` beyond the release bound
    (:func:`release_bound`) while every other mode of the hanging, released
    with the timed one at once within that bound (each at it, every
    combination of their velocities' signs: :data:`MAX_JOINT_RUNS` runs at
    most), makes that tone at a scale of their amplitudes within 2 of its
    std of the bound (or below it): the tone's law taken as ``best``'s
    (``c ~ a^n``), the scale's relative std as ``best``'s amplitude's (the
    tone's noise over ``n``, :data:`CALIBRATION_SHARE`).  The record then
    cannot tell a second mode beyond the bound from several within it, and
    their period shifts differ: the budget carries the difference
    (:func:`joint_reading_std`).  None (nothing run) where ``best`` lies
    within the bound or the hanging has one other mode; None where the
    joint release makes no such tone.

    Why: with every other mode of the drone config at its 1 cm bound (the
    pitch at 0.0067 rad) the torsion's record held a tone at 1.64 s, 2.4e-3
    of the torsion, that the swing-y alone makes only at 2.25 cm; read as
    one swing-y, Izz z -3.0..-4.0 in 16 of 40 draws (docs/design.md,
    "tonepair, session 14").  Session 14 refused those records; a real 1.5
    or 2 cm swing-y of the quadcopter-like body was refused with them
    (docs/design.md, "tonewiden, session 15")."""
    pb, k, hm, values, k0, A = ctx.pb, ctx.k, ctx.hm, ctx.values, ctx.k0, ctx.A
    tone, f_rec, tol, c0, Lmax, rtol = ctx.tone, ctx.f_rec, ctx.tol, ctx.c0, ctx.Lmax, ctx.rtol
    bound, _ = release_bound(pb)
    own = bound / Lmax if hm.modes0.modes[best.index].dominant >= 3 else bound
    if not (bound > 0 and abs(best.amplitude) > own):
        return None
    js = [j for j, mj in enumerate(hm.modes0.modes) if j != k0 and mj.period]
    if len(js) < 2:
        return None
    amps = [bound / Lmax if hm.modes0.modes[j].dominant >= 3 else bound for j in js]
    n_signs = min(len(js) - 1, int(math.log2(MAX_JOINT_RUNS)))
    cmax = None
    for code in range(2 ** n_signs):  # the first mode's sign fixed: reversing every velocity reverses time
        sgn = [1.0] + [(-1.0 if code >> i & 1 else 1.0) for i in range(len(js) - 1)]
        try:
            c = _match(_run_tones(hm, values, k0, tuple(js), A, tuple(s * a for s, a in zip(sgn, amps)),
                                  pb.measurements[k].cycles, rtol), f_rec, tol)
        except BifilarError:
            best.joint_failed += 1
            continue
        finally:
            best.joint_runs += 1
        if c is not None and (cmax is None or c > cmax):
            cmax = c
    cj, cr = (cmax or 0.0) - (c0 or 0.0), tone["ratio"] - (c0 or 0.0)
    if not (cj > 0 and cr > 0):
        return None
    # the scale of the joint release that makes the record's tone (its law the found mode's, ~ a^n), and its
    # relative std as the found amplitude's (the tone's noise, CALIBRATION_SHARE for the modes' phases)
    scale = (cr / cj) ** (1.0 / best.exponent)
    if scale > 1.0 + 2.0 * math.hypot(tone["ratio_std"] / cr / best.exponent, CALIBRATION_SHARE):
        return None
    return JointReading([hm.modes0.modes[j].label for j in js], float(scale), bound, own)


def joint_reading_std(m) -> float:
    """s: the std of the budget's ``tone_reading`` group for measurement
    ``m`` whose second mode (``m.secondary``, its ``shift`` set at the
    estimate) has another reading (:attr:`Secondary.joint`); 0 without one.
    The other reading's shift (set on the reading) is the found mode's at
    its bound and every hidden mode's at its bound (``m.hidden``, their
    shifts set: :func:`~bifilar.estimation.solve._hidden_shifts`), summed
    (second order in each amplitude: the modes' shifts add) and times
    ``(decay scale)^2`` (the modes' amplitudes ``scale`` times the bound,
    decaying with the record as the found mode is taken to), at the
    ``scale`` the worst velocity signs give and at 1 (other signs, whose
    tone at the bound is smaller: every mode at the bound; and a scale
    beyond 1 within its uncertainty: the bound itself).  The std is the larger
    difference of those two shifts from the found mode's, the answer's:
    the answer keeps the one-mode reading, and the other one then lies
    within one std of this group, inside the 95 % interval with the rest of
    the budget (a two-point uncertainty, not a spread about a mean).

    Raises :class:`~bifilar.errors.InputError` naming the measurement's
    field where a shift the other reading needs is not known (a hidden
    mode's run at the bound failed): the two answers cannot be bracketed."""
    from ..errors import InputError

    sec = getattr(m, "secondary", None)
    jr = None if sec is None else sec.joint
    if jr is None:
        return 0.0
    hidden = getattr(m, "hidden", None) or []
    failed = [h.label for h in hidden if h.shift is None]
    if sec.shift is None or not sec.amplitude or failed:
        raise InputError(m.field, (
            f"mode '{m.label}': the record's oscillation at {sec.tone_period:.4g} s is as the {sec.label} mode "
            f"alone makes it at {sec.amplitude:.3g} (beyond the release bound {jr.release:g} m) and as the "
            f"{', '.join(jr.labels)} modes make it released together within that bound, and the run of "
            f"{', '.join(failed) or sec.label} that gives the second reading's period shift failed, so no std can "
            "cover both; state the release bound you can vouch for (--uncertainty release, m of travel) or "
            "release more cleanly and record again"))
    at_bound = sec.shift * (jr.found_bound / sec.amplitude) ** 2 + sum(h.shift for h in hidden)
    g2 = sec.decay ** 2
    jr.shifts = tuple(float(g2 * sc ** 2 * at_bound) for sc in (jr.scale, 1.0))
    jr.shift_std = float(max(abs(sec.shift - x) for x in jr.shifts))
    return jr.shift_std


#: m: the default bound on a second mode a release starts unseen (``--uncertainty release``): the travel of the
#: CoM (a swing) an experimenter can see by eye on a ~1 m rig; a stated default, not a measurement
DEFAULT_RELEASE = 0.01
#: the first two moments of ``u = shift / s_max``, a hidden mode's period shift as a share of its shift at the bound,
#: taken uniform in ``[0, 1]`` (GUM's rectangular distribution of a bounded quantity): mean 1/2, mean square 1/3, so
#: one mode's zero-centred std is ``s_max / sqrt(3)`` and the 95 % interval (1.13 ``s_max``) holds a second mode at
#: the bound itself.  The amplitude uniform in ``[0, a_max]`` instead (the shift ~ a^2: ``u = (a / a_max)^2``,
#: moments 1/3 and 1/5, std ``s_max / sqrt(5)``) left a 1 cm swing at the 1 cm bound outside it: quadcopter z -1.8
#: to -2.1, drone config +2.1 to +2.2 (docs/design.md, "Hidden second modes, session 13")
HIDDEN_U_MEAN, HIDDEN_U_SQUARE = 1.0 / 2.0, 1.0 / 3.0


#: the most runs :func:`_check_joint_release` makes (the combinations of the other modes' velocity signs)
MAX_JOINT_RUNS = 8


def release_bound(pb) -> tuple[float, bool]:
    """(bound m, stated): problem ``pb``'s bound on a second mode a release
    starts unseen (the uncertainty key ``release``, else :data:`DEFAULT_RELEASE`)."""
    unc = getattr(pb, "unc", None) or {}
    given = "release" in unc
    return (float(unc["release"]) if given else DEFAULT_RELEASE), given


@dataclass
class Hidden:
    """A mode a recording's release may have started unseen: the largest
    amplitude the record cannot exclude by the stated bound, and the timed
    mode's period shift it would make."""

    label: str  #: the mode's label
    index: int  #: its index among the hanging's modes at the prior (``HangingModel.modes0``)
    amplitude: float  #: a_max, rad or m (its normalised shape): ``release`` m, over the longest wire (m) for an angle
    source: str  #: where ``amplitude`` comes from (the stated bound, or its default)
    release: float  #: m, that bound (``--uncertainty release``)
    #: s: the timed mode's period shift at ``amplitude`` (simulated at the estimate; None if that run failed)
    shift: float | None = None

    def to_json(self) -> dict:
        return {"mode": self.label, "amplitude_max": self.amplitude, "source": self.source,
                "release": self.release, "period_shift_max": self.shift}


def hidden_modes(pb, k: int, p, found: int | None = None) -> list[Hidden]:
    """The modes measurement ``k``'s recording may hide (every mode of its
    hanging but the timed one and ``found``, the second mode the record
    showed; neutral ones left out), at the unknowns ``p``, each at the
    largest amplitude the stated bound allows: ``release`` (m, the problem's
    uncertainty key, default :data:`DEFAULT_RELEASE`) for a
    translation-dominated mode, ``release`` over the longest wire (rad) for a
    rotation-dominated one.  Empty where ``release`` is 0.  Raises
    :class:`~bifilar.errors.InputError` naming ``--uncertainty`` where the
    bound exceeds :data:`MAX_ANGLE` (of the longest wire): the model's
    release with it could not answer for the period.

    Why: a second mode whose tones stay below the record's noise still
    shifts the timed period at second order in its amplitude; unbudgeted, a
    tightly stated amplitude made ``invert`` confidently wrong (the
    quadcopter-like body, 1 % camera noise, a hidden 1 cm swing-y,
    ``--uncertainty amplitude=0.01``: Izz z -5.6 to -6.6; docs/design.md,
    "Hidden second modes, session 13").  The record's own detection limit
    is not used: at 1 % noise it cannot exclude a swing-y of 1.8 cm nor a
    pitch of 0.14 rad (session 12), both beyond the default bound."""
    from ..errors import InputError

    m = pb.measurements[k]
    bound, given = release_bound(pb)
    if not bound > 0:
        return []
    hm = pb.models[m.hanging]
    Lmax = float(np.max(hm.scene(pb.values(p)).lengths))
    if bound > MAX_ANGLE * Lmax:
        raise InputError("--uncertainty", (
            f"release {bound:g} m is beyond {MAX_ANGLE:g} of the longest wire ({MAX_ANGLE * Lmax:.3g} m; the key "
            "release, of --uncertainty or a file's uncertainty block): a second "
            "motion that large shifts the period by more than the model of the release can answer for; release more "
            "cleanly and state a smaller bound"))
    source = "stated bound (uncertainty key release)" if given else f"default bound ({DEFAULT_RELEASE:g} m)"
    k0 = pb.mode_index[k]
    out = []
    for j, mj in enumerate(hm.modes0.modes):
        if j in (k0, found) or not mj.period:
            continue
        out.append(Hidden(mj.label, j, bound / Lmax if mj.dominant >= 3 else bound, source, bound))
    return out


def hidden_shift_std(hidden) -> float:
    """s: the RMS of the total period shift of the hidden modes ``hidden``
    (:class:`Hidden` with their shifts ``s_j`` at ``a_max``), each shift
    independent and uniform in ``[0, s_j]``: ``E[(sum s_j u_j)^2] =
    (sum s_j)^2 m1^2 + sum s_j^2 (m2 - m1^2)`` with ``m1``, ``m2`` the
    moments of ``u`` (:data:`HIDDEN_U_MEAN`, :data:`HIDDEN_U_SQUARE`); one
    mode: ``|s_max| / sqrt(3)``.  Zero-centred in the budget: a clean
    release, no shift, is the likeliest.

    Shifts of both signs: the largest of that RMS over all the modes, over
    those that lengthen the period and over those that shorten it.  A
    release that started only the modes of one sign (the others clean) is
    not offset by the others' shifts, so their cancellation in the signed
    sum's mean must not shrink the interval below what that one-sign set
    needs: the drone config's swing-y (+1.23e-4 s at 1 cm) against its
    swing-x and pitch (-1.2e-5, -1.1e-5 s) gave 6.2e-5 s instead of the
    swing-y's own 7.1e-5 s, and a swing-y at the bound fell outside the
    95 % interval in 10 % of draws (z +1.81 mean; docs/design.md,
    "Estimation audit, session 14")."""
    s = np.array([h.shift for h in hidden if h.shift is not None], float)
    if not s.size:
        return 0.0

    def rms(x):
        return x.sum() ** 2 * HIDDEN_U_MEAN ** 2 + np.sum(x * x) * (HIDDEN_U_SQUARE - HIDDEN_U_MEAN ** 2)

    return float(math.sqrt(max(rms(s), rms(s[s > 0]), rms(s[s < 0]))))


def attach_second_modes(pb, p, rtol: float, notes: list) -> list:
    """Each fitted recording's second mode, started by its release
    (:func:`infer_secondary` at the unknowns ``p``, SI), set on its
    measurement (``m.secondary``) so that ``invert``'s nonlinear runs release
    it too; a line appended to ``notes`` says so.  Returns the warnings of
    records holding an oscillation no other mode explains."""
    warnings = []
    for k, m in enumerate(pb.measurements):
        m.secondary = None
        m.hidden = []
        if not (m.amplitude and m.fundamental):
            continue
        sec = infer_secondary(pb, k, p, rtol)
        if isinstance(sec, str):
            warnings.append(sec)
        elif sec is not None:
            m.secondary = sec
            at = f"at {sec.amplitude:.3g} +- {sec.amplitude_std:.2g}" if sec.decay == 1.0 else (
                f"at {sec.amplitude_start:.3g} at the record's start and {sec.amplitude:.3g} +- {sec.amplitude_std:.2g} "
                f"over it, the amplitude its period refers to (decaying "
                + (f"as the {m.label} does)" if sec.decay_rate is None
                   else f"at {sec.decay_rate[0]:.3g} +- {sec.decay_rate[1]:.2g} 1/s, its tone's)"))
            notes.append(f"mode '{m.label}': the record's oscillation at {sec.tone_period:.4g} s "
                         f"({sec.tone_ratio:.2g} of its amplitude) says its release also started the {sec.label} "
                         f"mode, {at}; the nonlinear model is released "
                         "with both, and the budget carries that amplitude's uncertainty (second_mode)")
            if sec.joint is not None:  # the tone has two readings: the std carries their difference
                jr = sec.joint
                warnings.append(f"--signal: mode '{m.label}': the record's oscillation at {sec.tone_period:.4g} s is as "
                                f"the {sec.label} mode alone makes it at {sec.amplitude:.3g} (beyond the release bound "
                                f"{jr.release:g} m), and as the {', '.join(jr.labels)} modes make it released together "
                                f"at {jr.scale:.2g} times that bound: the record cannot tell them apart, so the answer "
                                "is the first reading's with the difference of their period shifts in its std "
                                "(tone_reading); a tighter --uncertainty release that you can vouch for narrows it")
            if sec.joint_failed:  # the check that smaller modes within the bound do not make the tone is partial
                warnings.append(f"mode '{m.label}': the {sec.label} mode at {sec.amplitude:.3g} lies beyond the "
                                f"release bound, and {sec.joint_failed} of the {sec.joint_runs} runs that check whether "
                                "the other modes released together within it make the same oscillation failed: the "
                                "second mode may be several smaller ones, which shift the period otherwise; state the "
                                "release bound you can vouch for (--uncertainty release)")
        m.hidden = hidden_modes(pb, k, p, None if m.secondary is None else m.secondary.index)
        if m.hidden:
            h0 = m.hidden[0]
            how = "the stated bound" if h0.source.startswith("stated") else \
                "the default bound; state yours with --uncertainty release"
            notes.append(f"mode '{m.label}': a second mode its release may have started unseen is budgeted by the "
                         f"period shift it would make (hidden_second_mode): "
                         f"{', '.join(f'{h.label} up to {h.amplitude:.3g}' for h in m.hidden)} ({how}: "
                         f"{h0.release:g} m of travel, over the longest wire in rad for an angle mode)")
    return warnings


def hidden_warnings(pb) -> list[str]:
    """One warning per measurement whose run at a hidden mode's bound
    failed (:attr:`Hidden.shift` None after the nonlinear solve): that
    mode's shift is not in the budget."""
    out = []
    for m in pb.measurements:
        failed = [h.label for h in getattr(m, "hidden", None) or [] if h.shift is None]
        if failed:
            out.append(f"mode '{m.label}': the run released with {', '.join(failed)} at the release bound failed: the "
                       "period shift a second mode hidden below the record's noise would make is not in the std for "
                       "it; state a smaller --uncertainty release")
    return out
