"""Damped-oscillation models, their least-squares solver and start values,
and the spectral helpers they use.  Part of :mod:`bifilar.estimation.signal`.

Every model: ``y = c0 + c1 (t - tm) + oscillation(t - t0)`` with ``t`` in s,
``t0`` the window start and ``tm`` its middle; rates in rad/s and 1/s;
samples in the signal's unit ``[y]``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from .signal_io import SignalError

def _uniform(t, y):
    d = np.diff(t)
    dt = float(np.median(d))
    if np.all(np.abs(d - dt) <= 1e-3 * dt):
        return y, dt
    tu = np.arange(t[0], t[-1], dt)
    return np.interp(tu, t, y), dt


def _spectrum(t, y, window=True, pad=8):
    """|FFT| of the linearly detrended signal, zero-padded ``pad`` times."""
    yu, dt = _uniform(t, y)
    n = yu.size
    x = np.arange(n)
    yd = yu - np.polyval(np.polyfit(x, yu, 1), x)
    w = np.hanning(n) if window else np.ones(n)
    nfft = 1 << int(math.ceil(math.log2(pad * n)))
    S = np.abs(np.fft.rfft(yd * w, nfft))
    f = np.fft.rfftfreq(nfft, dt)
    return f, S, n * dt


def _spectral_peaks(f, S, T_rec, k=1):
    """Frequencies (Hz) of the ``k`` largest local maxima above 1.5 cycles
    per record, refined by a parabola through the log magnitudes."""
    fmin = 1.5 / T_rec
    i = np.arange(1, S.size - 1)
    lm = i[(S[i] >= S[i - 1]) & (S[i] > S[i + 1]) & (f[i] >= fmin)]
    if lm.size == 0:
        return []
    lm = lm[np.argsort(S[lm])[::-1][:k]]
    df = f[1] - f[0]
    out = []
    for j in lm:
        l0, l1, l2 = np.log(S[j - 1:j + 2] + 1e-300)
        den = l0 - 2 * l1 + l2
        d = 0.5 * (l0 - l2) / den if den < 0 else 0.0
        out.append(float(f[j] + np.clip(d, -0.5, 0.5) * df))
    return out


def _robust_std(x) -> float:
    x = np.asarray(x, float)
    mad = np.median(np.abs(x - np.median(x)))
    return float(1.4826 * mad) if mad > 0 else float(np.std(x))


def _noise_sigma(y) -> float:
    """White-noise level of ``y`` from its second differences (a smooth
    oscillation contributes ``A w^2 dt^2`` there, negligible when sampled
    finely); robust (MAD) unless the signal is so quantised that the MAD is
    zero."""
    if len(y) < 4:
        return 0.0
    return _robust_std(np.diff(y, 2)) / math.sqrt(6.0)


def _lag1(r) -> float:
    r = np.asarray(r, float) - np.mean(r)
    den = float(r @ r)
    return float(r[:-1] @ r[1:] / den) if den > 0 else 0.0



# ---------------------------------------------------------------------------
# models
# ---------------------------------------------------------------------------
# every model: y = c0 + c1 (t - tm) + oscillation(t - t0); linear amplitudes
# (a, b) with A cos(w tau + phi) = a cos(w tau) + b sin(w tau), i.e.
# A = hypot(a, b), phi = atan2(-b, a).

#: the parameter layout of every model: (c0, c1) the line at 0 and 1, the
#: first (dominant) oscillation's parameters from 2 (_NAMES), then further
#: damped cosines (a, b, omega, sigma), 4 each, from this index on; a kind
#: not listed has none
FURTHER_FROM = {"two_mode": 6, "three_mode": 6, "chirp": 8}


def further_modes(kind: str, n: int) -> range:
    """Index of each further damped cosine's ``a`` (its ``a, b, omega,
    sigma`` at ``i .. i + 3``) among the ``n`` parameters of a ``kind``
    model (:data:`FURTHER_FROM`); empty for a kind without any."""
    return range(FURTHER_FROM.get(kind, n), n, 4)


_NAMES = {
    "viscous": ("c0", "c1", "a", "b", "omega_d", "sigma"),
    "quadratic": ("c0", "c1", "a", "b", "omega", "kappa", "sigma"),
    "chirp": ("c0", "c1", "a", "b", "omega", "sigma", "beta", "beta2"),
    "two_mode": ("c0", "c1", "a1", "b1", "omega1", "sigma1", "a2", "b2", "omega2", "sigma2"),
    "three_mode": ("c0", "c1", "a1", "b1", "omega1", "sigma1", "a2", "b2", "omega2", "sigma2",
                   "a3", "b3", "omega3", "sigma3"),
}


def _E(sg: float, tau: np.ndarray):
    """E = (1 - exp(-sg tau)) / sg and dE/dsg, with the series for small
    sg tau (E -> tau as sg -> 0)."""
    x = sg * tau
    small = np.abs(x) < 1e-4
    E = np.empty_like(tau)
    dE = np.empty_like(tau)
    if np.any(~small):
        xs, ts = x[~small], tau[~small]
        E[~small] = -np.expm1(-xs) / sg
        dE[~small] = (ts * np.exp(-xs) - E[~small]) / sg
    xs, ts = x[small], tau[small]
    E[small] = ts * (1 - xs / 2 + xs ** 2 / 6 - xs ** 3 / 24)
    dE[small] = ts ** 2 * (-0.5 + xs / 3 - xs ** 2 / 8 + xs ** 3 / 30)
    return E, dE


def _damped(a, b, w, sg, tau, J=None, col=0):
    e = np.exp(-sg * tau)
    c, s = np.cos(w * tau), np.sin(w * tau)
    osc = a * c + b * s
    if J is not None:
        J[:, col] = e * c
        J[:, col + 1] = e * s
        J[:, col + 2] = e * tau * (b * c - a * s)
        J[:, col + 3] = -tau * e * osc
    return e * osc


def _model(kind: str, p, t, t0, tm, want_jac=False):
    tau = t - t0
    s = t - tm
    J = np.empty((t.size, len(p))) if want_jac else None
    if J is not None:
        J[:, 0] = 1.0
        J[:, 1] = s
    y = p[0] + p[1] * s
    if kind in ("viscous", "two_mode", "three_mode"):
        y = y + _damped(p[2], p[3], p[4], p[5], tau, J, 2)
    elif kind == "quadratic":
        a, b, w, kap, sg = p[2:7]
        E, dE = _E(sg, tau)
        D = 1.0 + kap * E
        g = np.exp(-sg * tau) / D
        c, sn = np.cos(w * tau), np.sin(w * tau)
        osc = a * c + b * sn
        y = y + g * osc
        if J is not None:
            J[:, 2] = g * c
            J[:, 3] = g * sn
            J[:, 4] = g * tau * (b * c - a * sn)
            J[:, 5] = -g * E / D * osc
            J[:, 6] = (-tau * g - g * kap * dE / D) * osc
    elif kind == "chirp":
        # viscous envelope, frequency following its square u = (A / A0)^2:
        # omega(tau) = omega + beta u + beta2 u^2, u = exp(-2 sigma tau),
        # phase omega tau + beta E(2 sigma, tau) + beta2 E(4 sigma, tau)
        a, b, w, sg, beta, beta2 = p[2:8]
        e = np.exp(-sg * tau)
        E2, dE2 = _E(2.0 * sg, tau)
        E4, dE4 = _E(4.0 * sg, tau)
        th = w * tau + beta * E2 + beta2 * E4
        c, sn = np.cos(th), np.sin(th)
        osc = a * c + b * sn
        y = y + e * osc
        if J is not None:
            dth = e * (b * c - a * sn)  # d(e osc)/d(theta)
            J[:, 2] = e * c
            J[:, 3] = e * sn
            J[:, 4] = dth * tau
            J[:, 5] = -tau * e * osc + dth * (beta * 2.0 * dE2 + beta2 * 4.0 * dE4)
            J[:, 6] = dth * E2
            J[:, 7] = dth * E4
    else:  # pragma: no cover - guarded by fit_period
        raise ValueError(kind)
    # further modes, and the other oscillations a chirp's record carries (a
    # coupled swing the release excites): plain damped cosines
    for col in further_modes(kind, len(p)):
        y = y + _damped(p[col], p[col + 1], p[col + 2], p[col + 3], tau, J, col)
    return (y, J) if want_jac else y


def _names(kind: str, n: int) -> tuple:
    """Parameter names of a ``kind`` model with ``n`` parameters (a
    ``chirp`` may carry other oscillations after its eight)."""
    names = _NAMES[kind]
    if kind == "chirp":
        names = names + tuple(f"{nm}{k}" for k in range(2, 2 + len(further_modes(kind, n)))
                              for nm in ("a", "b", "omega", "sigma"))
    return names


def _envelope(kind: str, p, t, t0):
    """Amplitude envelope ([y]) of the (first) oscillation."""
    tau = t - t0
    if kind in ("viscous", "two_mode", "three_mode", "chirp"):
        return math.hypot(p[2], p[3]) * np.exp(-p[5] * tau)
    E, _ = _E(p[6], tau)
    return math.hypot(p[2], p[3]) * np.exp(-p[6] * tau) / (1.0 + p[5] * E)


def _linear_amplitudes(t, y, t0, tm, omegas, sigmas, kap=0.0):
    """Least-squares offset, drift and (a, b) per mode for fixed nonlinear
    parameters (variable projection start)."""
    tau = t - t0
    cols = [np.ones_like(t), t - tm]
    for w, sg in zip(omegas, sigmas):
        g = np.exp(-sg * tau)
        if kap:
            g = g / (1.0 + kap * _E(sg, tau)[0])
        cols += [g * np.cos(w * tau), g * np.sin(w * tau)]
    A = np.vstack(cols).T
    # normal equations of the column-scaled design (k <= 8 columns: k^2 n
    # flops, several times faster than the SVD of lstsq, which the start
    # search calls hundreds of times); lstsq where they are ill-conditioned
    sc = np.sqrt(np.einsum("ij,ij->j", A, A))
    sc[sc == 0] = 1.0
    As = A / sc
    G = As.T @ As
    if np.linalg.cond(G) < 1e8:
        coef = np.linalg.solve(G, As.T @ y) / sc
    else:
        coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    r = y - A @ coef
    return coef, float(r @ r)


@dataclass
class _Raw:
    kind: str
    p: np.ndarray
    free: np.ndarray
    t0: float
    tm: float
    resid: np.ndarray
    J: np.ndarray
    cost: float
    converged: bool
    message: str


def _solve(kind, t, y, t0, tm, p0, free=None, squared=(), max_nfev_per_param=200) -> _Raw:
    """Levenberg-Marquardt (MINPACK) on the free parameters; parameters in
    ``squared`` must stay >= 0 and are solved for as ``q`` with ``p = q^2``
    (no bounded solver needed: the bounded 'trf' costs ten times more per
    iteration on long records).  The returned Jacobian is in the natural
    parameters."""
    p0 = np.asarray(p0, float).copy()
    free = np.ones(p0.size, bool) if free is None else np.asarray(free, bool)
    sq = np.zeros(p0.size, bool)
    sq[list(squared)] = True
    sq &= free
    p0[sq] = np.maximum(p0[sq], 0.0)
    q0 = p0.copy()
    q0[sq] = np.sqrt(p0[sq])

    def full(q):
        p = p0.copy()
        p[free] = q
        p[sq] = p[sq] ** 2
        return p

    def fun(q):
        with np.errstate(all="ignore"):
            r = _model(kind, full(q), t, t0, tm) - y
        return np.nan_to_num(r, nan=1e150, posinf=1e150, neginf=-1e150)

    def jac(q):
        with np.errstate(all="ignore"):
            J = _model(kind, full(q), t, t0, tm, want_jac=True)[1]
        qq = p0.copy()
        qq[free] = q
        J[:, sq] *= 2.0 * qq[sq]
        return np.nan_to_num(J[:, free])

    res = optimize.least_squares(fun, q0[free], jac=jac, method="lm", x_scale="jac",
                                 ftol=1e-13, xtol=1e-13, gtol=1e-13,
                                 max_nfev=max_nfev_per_param * int(free.sum()))
    p = full(res.x)
    yhat, J = _model(kind, p, t, t0, tm, want_jac=True)
    r = y - yhat
    ok = bool(res.status > 0) and bool(np.all(np.isfinite(r)))
    return _Raw(kind, p, free, t0, tm, r, J[:, free], float(r @ r), ok, res.message)



# ---------------------------------------------------------------------------
# fitting
# ---------------------------------------------------------------------------

def _envelope_thirds(t, yd):
    """RMS-based amplitudes (sqrt 2 RMS) of the first and last thirds and
    their centre times."""
    T_rec = t[-1] - t[0]
    m1 = t <= t[0] + T_rec / 3
    m3 = t >= t[-1] - T_rec / 3
    A1 = math.sqrt(2 * np.mean(yd[m1] ** 2))
    A3 = math.sqrt(2 * np.mean(yd[m3] ** 2))
    return A1, A3, float(np.mean(t[m1])), float(np.mean(t[m3]))


def _start_viscous(t, y, t0, tm, f_guess, drift):
    T_rec = t[-1] - t[0]
    if f_guess is None:
        f, S, _ = _spectrum(t, y)
        pk = _spectral_peaks(f, S, T_rec, 1)
        if not pk:
            raise SignalError("signal", "no spectral peak above 1.5 cycles per record: "
                                        "the window holds too few oscillations")
        f_guess = pk[0]
    w0 = 2 * math.pi * f_guess
    coef, _ = _linear_amplitudes(t, y, t0, tm, [w0], [0.0])
    yd = y - coef[0] - coef[1] * (t - tm)
    A1, A3, tc1, tc3 = _envelope_thirds(t, yd)
    sg0 = math.log(A1 / A3) / (tc3 - tc1) if A1 > 0 and A3 > 0 else 0.0
    sg0 = float(np.clip(sg0, -10.0 / T_rec, 10.0 / T_rec))
    coef, _ = _linear_amplitudes(t, y, t0, tm, [w0], [sg0])
    p0 = [coef[0], coef[1] if drift else 0.0, coef[2], coef[3], w0, sg0]
    return np.array(p0), (A1, A3, tc1 - t0, tc3 - t0)


def _fit_viscous(t, y, t0, tm, f_guess, drift):
    p0, env = _start_viscous(t, y, t0, tm, f_guess, drift)
    free = np.ones(6, bool)
    free[1] = drift
    return _solve("viscous", t, y, t0, tm, p0, free), env


def _fit_quadratic(t, y, t0, tm, visc: _Raw, env, drift, viscous_term):
    A1, A3, tau1, tau3 = env
    # 1/A(tau) = (1 + kappa tau)/A0 through the two thirds
    den = A3 * tau3 - A1 * tau1
    kap0 = (A1 - A3) / den if den > 0 and A1 > A3 else 0.0
    kap0 = float(np.clip(kap0, 1e-3 / (t[-1] - t[0]), 100.0 / (t[-1] - t[0])))
    w = visc.p[4]
    free = np.ones(7, bool)
    free[1] = drift
    free[6] = viscous_term
    starts = []
    coef, _ = _linear_amplitudes(t, y, t0, tm, [w], [0.0], kap0)
    starts.append([coef[0], coef[1] if drift else 0.0, coef[2], coef[3], w, kap0, 0.0])
    if viscous_term:
        sg = max(visc.p[5], 0.0)
        tiny = 1e-3 / (t[-1] - t[0])
        starts.append([visc.p[0], visc.p[1], visc.p[2], visc.p[3], w, tiny, max(sg, tiny)])
        coef, _ = _linear_amplitudes(t, y, t0, tm, [w], [0.5 * sg], 0.5 * kap0)
        starts.append([coef[0], coef[1] if drift else 0.0, coef[2], coef[3], w, 0.5 * kap0, 0.5 * sg])
    best = None
    for p0 in starts:
        raw = _solve("quadratic", t, y, t0, tm, np.array(p0), free, squared=(5, 6))
        if best is None or raw.cost < best.cost:
            best = raw
    return best


def _fit_chirp(t, y, t0, tm, pv, drift, curvature=True):
    """The viscous model whose frequency follows the envelope's square (a
    pendulum's first nonlinear term, ``omega(A) = omega_0 + gamma A^2``):
    ``omega(tau) = omega + beta exp(-2 sigma tau)``, ``beta = gamma A0^2``
    the shift at ``t0``.  Started from the viscous fit's parameters
    ``pv`` (same ``t0``, ``tm``) with
    ``beta = 0`` and with the ``beta`` the viscous fits of the two halves
    imply (their frequencies against ``exp(-2 sigma tau)`` at their
    middles); the lower cost is kept.  With ``curvature`` the frequency
    has a term in ``A^4`` too (``beta2``, the shift at ``t0``), so the
    period at the reference amplitude is right to that order whether the
    frequency or the period is linear in ``A^2`` (they differ there)."""
    w, sg = float(pv[4]), float(pv[5])
    free = np.ones(8, bool)
    free[1] = drift
    free[7] = curvature
    starts = [np.r_[pv, 0.0, 0.0]]
    mid = 0.5 * (t[0] + t[-1])
    halves = (t <= mid, t >= mid)
    try:
        om, u = [], []
        for m in halves:
            th, yh = t[m], y[m]
            rh, _ = _fit_viscous(th, yh, float(th[0]), float(0.5 * (th[0] + th[-1])), w / (2 * math.pi), drift)
            om.append(float(rh.p[4]))
            u.append(math.exp(-2.0 * sg * (0.5 * (th[0] + th[-1]) - t0)))
        if abs(u[0] - u[1]) > 1e-6:
            beta0 = (om[0] - om[1]) / (u[0] - u[1])
            w0 = om[0] - beta0 * u[0]
            coef, _ = _linear_amplitudes(t, y, t0, tm, [w0], [sg])
            starts.append(np.array([coef[0], coef[1] if drift else 0.0, coef[2], coef[3], w0, sg, beta0, 0.0]))
    except (SignalError, ValueError, RuntimeError, np.linalg.LinAlgError, FloatingPointError):
        pass
    best = None
    for p0 in starts:
        raw = _solve("chirp", t, y, t0, tm, p0, free)
        if best is None or (raw.converged and (not best.converged or raw.cost < best.cost)):
            best = raw
    return best


def _fit_two_mode(t, y, t0, tm, visc: _Raw, drift):
    T_rec = t[-1] - t[0]
    cands = []
    for win in (False, True):
        f, S, _ = _spectrum(t, y, window=win)
        cands += _spectral_peaks(f, S, T_rec, 6)
    f, S, _ = _spectrum(t, visc.resid)
    cands += _spectral_peaks(f, S, T_rec, 3)
    cands.append(visc.p[4] / (2 * math.pi))
    uniq: list[float] = []
    for c in cands:  # candidates closer than a third of a bin are one
        if all(abs(c - u) >= 0.3 / T_rec for u in uniq):
            uniq.append(c)
    cands = uniq
    sg = visc.p[5]
    best_pair, best_rss = None, np.inf
    for i, fa in enumerate(cands):
        for fb in cands[i + 1:]:
            if abs(fa - fb) < 0.3 / T_rec:
                continue
            _, rss = _linear_amplitudes(t, y, t0, tm, [2 * math.pi * fa, 2 * math.pi * fb], [sg, sg])
            if rss < best_rss:
                best_pair, best_rss = (fa, fb), rss
    if best_pair is None:
        raise SignalError("signal", "cannot find two distinct spectral peaks for a two-mode fit")
    w1, w2 = (2 * math.pi * best_pair[0], 2 * math.pi * best_pair[1])
    coef, _ = _linear_amplitudes(t, y, t0, tm, [w1, w2], [sg, sg])
    p0 = [coef[0], coef[1] if drift else 0.0, coef[2], coef[3], w1, sg, coef[4], coef[5], w2, sg]
    free = np.ones(10, bool)
    free[1] = drift
    raw = _solve("two_mode", t, y, t0, tm, np.array(p0), free)
    return _canonical(raw, t)


def _mode_rank(omega: float, amplitude: float, T_rec: float, sigma: float = 0.0) -> tuple:
    """Sort key of a fitted mode (``omega`` rad/s, ``amplitude`` [y] at
    ``t0``, decay rate ``sigma`` 1/s, record ``T_rec`` s): modes with at
    least ``MIN_CYCLES`` cycles in the record first, then by their RMS
    amplitude over the record, ``amplitude sqrt((1 - e^{-2 sigma T_rec}) /
    (2 sigma T_rec))``.  A slow swell fitted as a "mode" (a baseline
    wandering through part of a cycle) can outweigh the oscillation but
    cannot be its period; a transient at the record's start fitted as a
    heavily damped "mode" (the hand that twisted the body before the
    release: damping ratio ~0.6, gone within a cycle) can be larger at
    ``t0`` than the oscillation but carries little of the record."""
    from .signal_checks import MIN_CYCLES  # signal_checks imports this module

    x = 2.0 * sigma * T_rec
    # mean of e^{-2 sigma tau} over the record (a mode growing 300 e-folds or more ranks as if it grew 350: the
    # exponential would overflow; dropfix2 met one in a refit on a recovered time base)
    share = 1.0 if abs(x) < 1e-12 else -math.expm1(min(-x, 700.0)) / x
    return (abs(omega) * T_rec / (2 * math.pi) < MIN_CYCLES, -amplitude * math.sqrt(max(share, 0.0)))


def _canonical(raw: _Raw, t) -> _Raw:
    """Modes of a multi-mode fit in canonical order (:func:`_mode_rank`):
    by RMS amplitude over the record among the modes with two or more cycles in the
    record, the dominant (the reported period) first."""
    starts = list(range(2, raw.p.size, 4))
    order = sorted(starts, key=lambda i: _mode_rank(raw.p[i + 2], math.hypot(raw.p[i], raw.p[i + 1]),
                                                   float(t[-1] - t[0]), raw.p[i + 3]))
    if order != starts:
        perm = np.r_[0, 1, [i + k for i in order for k in range(4)]]
        raw.p = raw.p[perm]
        raw.free = raw.free[perm]
        raw.J = _model(raw.kind, raw.p, t, raw.t0, raw.tm, want_jac=True)[1][:, raw.free]
    return raw


#: candidate frequencies of a third oscillation tried by ``_fit_three_mode``
THIRD_MODE_TRIES = 2
#: the third oscillation lies within this fraction of the dominant frequency
THIRD_MODE_BAND = 0.25


def _near_dominant(fc: float, f1: float, T_rec: float) -> bool:
    """Is ``fc`` (Hz) a third oscillation that can bias the dominant mode's
    frequency ``f1`` (Hz): resolved from it (at least ``1/T_rec`` away) and
    within ``THIRD_MODE_BAND * f1`` of it?  Farther components (the swing
    mode, harmonics ``k f1`` of a nonlinear sensor, a bounce mode) are
    nearly orthogonal to the dominant cosine over the record and hardly
    move its period; a close one beats with it."""
    return 1.0 / T_rec <= abs(fc - f1) <= THIRD_MODE_BAND * f1


def _third_mode_candidates(t, p2, resid2) -> list[float]:
    """Frequencies (Hz) of the significant peaks left in the two-mode
    residuals (the residual check's test, :func:`.signal_checks.residual_peaks`)
    that can be a third oscillation (:func:`_near_dominant`, and resolved
    from the second mode), strongest first."""
    from .signal_checks import residual_peaks  # signal_checks imports this module

    T_rec = float(t[-1] - t[0])
    f1, f2 = p2[4] / (2 * math.pi), p2[8] / (2 * math.pi)
    # the peak's Fourier bin may lie half a bin closer to f1 than the
    # oscillation itself: the fitted third mode is checked again
    return [pk["frequency"] for pk in residual_peaks(t, resid2, f1, max_peaks=8)
            if _near_dominant(pk["frequency"], f1, 2 * T_rec) and abs(pk["frequency"] - f2) >= 1.0 / T_rec]


def _fit_three_mode(t, y, t0, tm, p2, resid2, drift):
    """``two_mode`` plus a third damped oscillation close to the dominant
    mode, where the residuals ``resid2`` of the two-mode fit ``p2`` show a significant peak there
    (:func:`_third_mode_candidates`).  The candidates are ranked by the
    residual sum of squares of the linear fit with all frequencies fixed;
    the best ``THIRD_MODE_TRIES`` are refined by nonlinear least squares and
    the best fit whose third oscillation stays close (:func:`_near_dominant`)
    is kept."""
    T_rec = float(t[-1] - t[0])
    cands = _third_mode_candidates(t, p2, resid2)
    if not cands:
        raise SignalError("signal", "no significant peak in the two-mode residuals close to the dominant "
                                    "mode: no third oscillation to fit")
    ws = [p2[4], p2[8]]
    ss = [p2[5], p2[9]]
    starts = []
    for fc in cands:
        w3 = [*ws, 2 * math.pi * fc]
        s3 = [*ss, p2[5]]
        coef, rss = _linear_amplitudes(t, y, t0, tm, w3, s3)
        p0 = [coef[0], coef[1] if drift else 0.0]
        for k in range(3):
            p0 += [coef[2 + 2 * k], coef[3 + 2 * k], w3[k], s3[k]]
        starts.append((rss, p0))
    starts.sort(key=lambda sp: sp[0])
    free = np.ones(14, bool)
    free[1] = drift
    best = None
    for _, p0 in starts[:THIRD_MODE_TRIES]:
        # a start that converges does so in tens of evaluations; one that
        # wanders off would spend the full budget of 200 per parameter
        raw = _solve("three_mode", t, y, t0, tm, np.array(p0), free, max_nfev_per_param=40)
        near = _near_dominant(abs(raw.p[12]) / (2 * math.pi), abs(raw.p[4]) / (2 * math.pi), T_rec)
        if raw.converged and near and (best is None or raw.cost < best.cost):
            best = raw
    if best is None:
        raise ValueError("no three-mode fit kept its third oscillation close to the dominant mode")
    return _canonical(best, t)


def _auto_trim(t, y, raw: _Raw, k: float):
    """Last time at which the envelope (sqrt 2 x moving RMS over one period
    of the offset- and drift-free signal, noise power removed) is still at
    least ``k`` x the white-noise level of the residuals."""
    noise = _noise_sigma(raw.resid)
    if noise <= 0:
        return None, noise
    T = 2 * math.pi / raw.p[4]
    env, m = _moving_envelope(t, y - raw.p[0] - raw.p[1] * (t - raw.tm), T, noise)
    if env is None:
        return None, noise
    above = np.nonzero(env >= k * noise)[0]
    if above.size == 0:
        return None, noise
    return float(t[min(above[-1] + m // 2, t.size - 1)]), noise


def _moving_envelope(t, yd, T: float, noise: float):
    """Envelope ([y]) of the offset-free signal ``yd``: sqrt 2 x its moving
    RMS over one period ``T`` (s; centred window of ``m`` samples at the
    median step), the noise power ``noise^2`` removed.  Returns ``(env,
    m)``, ``(None, m)`` when the record is shorter than one period."""
    dt = float(np.median(np.diff(t)))
    m = max(int(round(T / dt)), 1)
    if m >= yd.size:
        return None, m
    ms = np.convolve(yd ** 2, np.ones(m) / m, mode="same")
    return np.sqrt(2 * np.clip(ms - noise ** 2, 0, None)), m


#: a leading stretch is at rest when it lasts at least one period and its
#: envelope stays below this fraction of the largest one
REST_FRACTION = 0.2


def _leading_rest(t, y, T: float):
    """Onset of an oscillation that follows a stretch at rest (the body still
    hanging before the release), or None when the record starts oscillating.

    With ``env`` the one-period moving envelope (:func:`_moving_envelope`,
    about the median level, noise from second differences) and ``A`` its
    maximum: the first sample where ``env >= A / 2`` lies ``T / 4`` before
    a sudden onset (a centred window of one period sees half the amplitude
    there), so the oscillation starts near ``t_half + T / 4``.  A stretch
    counts as rest when ``t_half - t[0] >= T`` and the envelope before
    ``t_half - T / 2`` stays below ``REST_FRACTION A``.  Returns ``(t_onset,
    t_start)`` in s: the estimated onset and the first time to fit,
    ``t_half + T / 2`` (a quarter period after the onset, so no sample at
    rest is fitted as part of the decay)."""
    noise = _noise_sigma(y)
    env, m = _moving_envelope(t, y - np.median(y), T, noise)
    if env is None:
        return None
    A = float(np.max(env))
    if not A > 0:
        return None
    i = int(np.argmax(env >= 0.5 * A))
    t_half = float(t[i])
    if t_half - float(t[0]) < T:
        return None
    quiet = env[t <= t_half - 0.5 * T]
    if quiet.size == 0 or float(np.max(quiet)) > REST_FRACTION * A:
        return None
    return t_half + 0.25 * T, t_half + 0.5 * T


