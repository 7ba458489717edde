"""The result of a period fit (:class:`PeriodFit`) and its construction
from a least-squares solution: covariance, serial-correlation factor,
modes and damping.  Part of :mod:`bifilar.estimation.signal` (import from
there).  Times in s, frequencies in Hz, angular rates in rad/s, signal
quantities in the signal's unit [y]."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .signal_checks import LB_ALPHA, ljung_box, serial_factor
from .signal_crossings import CrossingPeriod
from .signal_models import _Raw, _names, _envelope, _lag1, _mode_rank, _model, _noise_sigma, further_modes

# ---------------------------------------------------------------------------
# result
# ---------------------------------------------------------------------------

@dataclass
class PeriodFit:
    """Result of :func:`fit_period`.  Times in s, frequencies in Hz,
    angular rates in rad/s, signal quantities in the signal's unit [y].

    Attributes
    ----------
    model : str
        ``viscous``, ``quadratic``, ``quadratic+viscous``, ``two_mode``,
        ``three_mode``, ``viscous+chirp`` (the viscous model whose
        frequency follows the envelope's square, ``omega(t) = omega +
        beta u + beta2 u^2`` with ``u = (A(t) / A(t0))^2``; only in place of
        a viscous fit whose halves disagree, ``amplitude_law``) or
        ``crossings`` (fallback).
    period : float
        s, the observed (damped) period ``2 pi / omega`` of the oscillation;
        for ``two_mode`` / ``three_mode`` the mode with the largest
        amplitude at ``t0``; for ``viscous+chirp`` the period at the
        amplitude ``amplitude_period`` (a stated constant in [y]: its std
        holds the frequency, ``beta``, ``beta2`` and ``A(t0)``).
    std : float
        s, 1-sigma uncertainty of ``period``:
        ``hypot(max(std_raw * std_inflation, std_quantisation),
        std_nonstationary)`` (module
        docstring); ``uncertainty`` lists the terms and the dominant one.
    frequency : float
        Hz, ``1 / period``.
    period_undamped : float or None
        s, ``2 pi / omega_n`` with ``omega_n = hypot(omega_d, sigma)``
        (viscous models; the period an undamped pendulum formula wants).
    damping_ratio : float
        Viscous: ``zeta = sigma / omega_n``.  Quadratic: the equivalent
        viscous ratio at the amplitude of ``t0``, ``(sigma + kappa) / omega``.
    damping : dict
        Model parameters of the damping (with ``*_std`` entries):
        viscous ``sigma`` (1/s, envelope exp(-sigma (t - t0))) and ``zeta``;
        quadratic ``k`` (1/([y] s), dA/dt = -k A^2 - sigma A), ``kappa``
        (= k A0, 1/s) and ``sigma`` (1/s, 0 unless a viscous term is fitted).
    amplitude, phase : float
        [y] and rad, of the oscillation at ``t0``:
        ``A cos(omega (t - t0) + phase)``.
    amplitude_rms : float
        [y], RMS over the fit window of the (dominant) oscillation's
        envelope.  A finite-amplitude pendulum's period depends on its
        amplitude, and one record rarely spans enough amplitude to measure
        that dependence; compare periods of recordings at their amplitude
        (docs/real_data.md).
    amplitude_period : float
        [y], the amplitude the fitted period refers to: the period a
        pendulum shows at this constant amplitude is the one fitted to the
        decaying record, for a period that changes as ``A^2``
        (:func:`period_amplitude`).  Equals the envelope without decay;
        for a strong decay it lies between ``amplitude_rms`` and the
        energy-weighted RMS.
    offset, drift : float
        [y] at ``t_ref`` and [y]/s: ``c0 + c1 (t - t_ref)``.
    residual_rms, r_squared : float
        [y] and dimensionless, over the fit window.
    n_samples : int
        Samples in the fit window.
    params, param_names, covariance :
        Fitted parameter vector, names and covariance ``s^2 (J^T J)^-1``
        (not inflated; fixed parameters have zero rows).
    t0, t1, t_ref : float
        s, fit window and the drift's reference time (window middle).
    std_raw, std_inflation, lag1_autocorr :
        White-noise period std (s), the serial-correlation factor applied
        because the residuals are not white (1.0 if they are), and the
        residuals' lag-1 autocorrelation (dimensionless).
    std_nonstationary : float
        s, between-window std of the period when the windows disagree
        beyond their noise (0 otherwise); ``windows`` lists them.
    std_quantisation : float
        s, spread of the period over re-quantised copies of the fit when the
        record is quantised (on a lattice of steps, or on unevenly spaced
        levels such as pixels converted to an angle) with too little noise
        to dither them (0 otherwise; ``signal._quantisation``); it replaces
        the noise term (with its serial factor) when larger.
    amplitude_law : dict or None
        None unless a viscous fit's halves disagreed.  Then ``used`` (bool:
        the fit is ``viscous+chirp``), ``reason`` (one sentence),
        ``without_law`` (the viscous fit's ``period``, ``std``,
        ``std_nonstationary``, ``half_periods``) and, when the law was
        fitted, ``criterion_delta`` (its BIC/AIC minus the viscous one),
        ``beta``, ``beta_std``, ``beta2``, ``beta2_std`` (rad/s, the
        frequency shift at ``t0`` in ``A^2`` and ``A^4``),
        ``curvature_ratio`` (``beta2 omega / beta^2 = 1 - d/c^2`` for ``T
        = T0 (1 + c A^2 + d A^4)``), ``reference_amplitude`` ([y],
        ``amplitude_period``), ``period_zero_amplitude`` and
        ``period_start`` (s, at zero amplitude and at ``t0``), and its own
        split check ``halves`` (each half's period at the reference
        amplitude, with the law held), ``Q``, ``critical_Q``.
    uncertainty : dict
        ``noise``, ``serial_correlation`` (the extra std it adds, s),
        ``quantisation`` (the extra std of an undithered quantised record, s),
        ``nonstationarity`` (s), ``total`` (= ``std``), ``dominant``
        (the name of the largest term) and the rules' parameters.
    windows : list of dict
        Per window: ``t0``, ``t1``, ``period``, ``std`` (s); plus the
        test of their agreement in ``uncertainty``.
    residual_check : dict
        ``ljung_box`` statistic and ``p`` (whiteness), ``white`` (bool),
        ``lag1``, ``peaks`` left in the residuals (``frequency`` Hz,
        ``ratio`` to the local noise level, ``harmonic`` k or None).
    oscillation : dict
        The spectral-peak test the record passed (frequency, ratio,
        threshold, cycles).
    noise_std : float
        [y], white-noise level of the residuals from their second differences.
    aic, bic : float
        Gaussian information criteria ``n ln(RSS/n) + 2p`` / ``+ p ln n``.
    modes : list of dict
        Per mode: ``period``, ``std``, ``frequency``, ``damping_ratio``,
        ``amplitude`` (s, s, Hz, -, [y]).
    crossing : CrossingPeriod or None
        Cross-check by :func:`period_from_crossings` on the same window.
    half_periods : tuple or None
        ``((T1, std1), (T2, std2))``, s: the same model fitted to the first
        and the second half of the window.  A difference beyond 3 combined
        sigma (noted) means the period changes along the record, e.g. with
        amplitude, so ``std`` understates the uncertainty of "the" period.
    alternatives, selection, chosen_by, choice_reason :
        For ``model="auto"``: every candidate fit; ``selection`` holds
        ``candidates`` (per model: RSS, parameters, AIC, BIC, delta to the
        chosen, period, std, r^2, ``admissible`` and ``rejected_because``)
        and ``ranking`` (admissible models, best first); the criterion
        used and one sentence saying why the model was chosen.
    t_used, residuals : ndarray
        Times (s) and residuals ([y]) of the window, for plotting.
    notes : list of str
        Trimming, inflation, bounds hit, fallbacks, disagreements.
    """

    model: str
    period: float
    std: float
    frequency: float
    damping_ratio: float
    damping: dict
    amplitude: float
    phase: float
    offset: float
    drift: float
    residual_rms: float
    r_squared: float
    n_samples: int
    covariance: np.ndarray = field(repr=False)
    params: np.ndarray = field(repr=False)
    param_names: tuple = field(repr=False)
    t0: float = 0.0
    t1: float = 0.0
    t_ref: float = 0.0
    std_raw: float = float("nan")
    std_inflation: float = 1.0
    lag1_autocorr: float = 0.0
    noise_std: float = float("nan")
    amplitude_rms: float = float("nan")
    amplitude_period: float = float("nan")
    period_undamped: float | None = None
    aic: float = float("nan")
    bic: float = float("nan")
    converged: bool = True
    modes: list = field(default_factory=list)
    crossing: CrossingPeriod | None = field(default=None, repr=False)
    half_periods: tuple | None = None
    std_nonstationary: float = 0.0
    std_quantisation: float = 0.0
    amplitude_law: dict | None = None
    uncertainty: dict = field(default_factory=dict)
    windows: list = field(default_factory=list)
    residual_check: dict = field(default_factory=dict)
    oscillation: dict = field(default_factory=dict)
    choice_reason: str | None = None
    alternatives: dict = field(default_factory=dict, repr=False)
    selection: dict = field(default_factory=dict)
    chosen_by: str | None = None
    t_used: np.ndarray = field(default=None, repr=False)
    residuals: np.ndarray = field(default=None, repr=False)
    notes: list = field(default_factory=list)
    _kind: str = field(default="", repr=False)

    @property
    def window(self) -> tuple[float, float]:
        """Fit window (t0, t1), s."""
        return (self.t0, self.t1)

    def predict(self, t) -> np.ndarray:
        """Fitted model at times ``t`` (s), in [y]."""
        t = np.asarray(t, dtype=float)
        if not self._kind:
            raise ValueError("no model curve for a crossing-only result")
        return _model(self._kind, self.params, t.ravel(), self.t0, self.t_ref).reshape(t.shape)

    def envelope(self, t) -> np.ndarray:
        """Amplitude envelope ([y]) of the (dominant) oscillation at ``t`` (s)."""
        t = np.asarray(t, dtype=float)
        return _envelope(self._kind, self.params, t.ravel(), self.t0).reshape(t.shape)

    def summary(self) -> str:
        s = (f"{self.model}: T = {self.period:.6f} +- {self.std:.2g} s"
             f" (zeta = {self.damping_ratio:.4g}, r^2 = {self.r_squared:.5f}, n = {self.n_samples},"
             f" window {self.t0:.3f}-{self.t1:.3f} s")
        if self.std_inflation > 1.0:
            s += f", std x{self.std_inflation:.2f} for correlated residuals"
        if self.std_nonstationary > 0:
            s += f", +{self.std_nonstationary:.2g} s non-stationarity"
        return s + ")"

    def to_dict(self) -> dict:
        """JSON-friendly scalars (no arrays)."""
        keys = ("model", "period", "std", "frequency", "period_undamped", "damping_ratio", "damping",
                "amplitude", "amplitude_rms", "amplitude_period", "phase", "offset", "drift", "residual_rms", "r_squared", "n_samples",
                "t0", "t1", "std_raw", "std_inflation", "std_nonstationary", "std_quantisation", "amplitude_law", "uncertainty",
                "lag1_autocorr", "noise_std", "aic", "bic", "converged", "modes", "selection",
                "chosen_by", "choice_reason", "windows", "residual_check", "oscillation", "notes")
        d = {k: getattr(self, k) for k in keys}
        if self.crossing is not None:
            d["crossing_period"] = self.crossing.period
            d["crossing_std"] = self.crossing.std
        if self.half_periods is not None:
            d["half_periods"] = [list(h) for h in self.half_periods]
        return d


def _std(cov, i):
    v = cov[i, i]
    return float(math.sqrt(v)) if np.isfinite(v) and v >= 0 else float("nan")


def _grad_std(cov, idx, grad):
    g = np.asarray(grad, float)
    sub = cov[np.ix_(idx, idx)]
    v = float(g @ sub @ g)
    return math.sqrt(v) if np.isfinite(v) and v >= 0 else float("nan")


def _hc_std(raw: _Raw, covf, s2: float, r, dof: int) -> dict:
    """Heteroscedasticity-consistent std (White's sandwich, scaled by
    ``n/(n-p)``) of each frequency parameter ``omega`` (rad/s), by index
    into ``raw.p``.  The least-squares ``s^2 (J^T J)^-1`` assumes every
    sample equally noisy; a camera's timestamp jitter or repeated frames
    err by ``y'(t) dt``, most at the zero crossings where the frequency is
    measured, and the plain std then understates the error (session 6
    audit: sd of z ~1.2).  The period's noise std is the larger of the two,
    for white residuals (Ljung-Box); residuals that are not white get the
    serial-correlation factor instead (smooth, deterministic residuals such
    as a sensor's harmonics would make the sandwich overstate the std)."""
    out: dict = {}
    if not np.all(np.isfinite(covf)) or not s2 > 0 or raw.kind == "chirp":
        return out  # the chirp's frequency is a combination: _hc_lin_std
    for iw in range(4, raw.p.size, 4):
        if raw.free[iw]:
            v = _hc_lin_std(raw, covf, s2, r, dof, {iw: 1.0})
            if np.isfinite(v):
                out[iw] = v
    return out


def _hc_lin_std(raw: _Raw, covf, s2: float, r, dof: int, grad: dict) -> float:
    """Sandwich std (as :func:`_hc_std`) of the linear combination
    ``sum grad[i] p[i]`` of the parameters (``grad`` by index into
    ``raw.p``; fixed parameters ignored); nan when undefined."""
    if not np.all(np.isfinite(covf)) or not s2 > 0:
        return float("nan")
    fi = np.nonzero(raw.free)[0]
    c = np.array([grad.get(int(i), 0.0) for i in fi])
    g = raw.J @ (covf / s2 @ c)  # J (J^T J)^-1 c
    v = float(np.sum((g * r) ** 2)) * r.size / dof
    return math.sqrt(v) if np.isfinite(v) and v >= 0 else float("nan")


def _build(raw: _Raw, t, y, model_name: str, notes: list[str]) -> PeriodFit:
    n = t.size
    npar = int(raw.free.sum())
    dof = max(n - npar, 1)
    s2 = raw.cost / dof
    # covariance s^2 (J^T J)^-1 via the SVD of J (free parameters only)
    # singular values and right vectors of J from its small triangular factor
    # (J = Q R: same S and V, without the n x p matrix U)
    _, S, Vt = np.linalg.svd(np.linalg.qr(raw.J, mode="r"))
    tol = S[0] * max(raw.J.shape) * np.finfo(float).eps if S.size else 0.0
    with np.errstate(divide="ignore"):
        inv2 = np.where(S > tol, 1.0 / S ** 2, np.inf)
    covf = (Vt.T * inv2) @ Vt * s2 if np.all(np.isfinite(inv2)) else np.full((npar, npar), np.nan)
    if not np.all(np.isfinite(inv2)):
        notes.append("Jacobian is rank deficient: covariance undefined")
    cov = np.zeros((raw.p.size, raw.p.size))
    fi = np.nonzero(raw.free)[0]
    cov[np.ix_(fi, fi)] = covf

    r = raw.resid
    rho = _lag1(r)
    roundoff = math.sqrt(raw.cost / n) <= 1e-9 * max(float(np.std(y)), np.finfo(float).tiny)
    lb_q, lb_p = ljung_box(r)
    white = roundoff or lb_p >= LB_ALPHA or not np.all(np.isfinite(inv2))
    # independent but unequal errors: the sandwich std; correlated ones get the serial factor instead
    hc = _hc_std(raw, covf, s2, r, dof) if white and not roundoff else {}
    dt = float(np.median(np.diff(t)))

    def factor(i_param: int) -> float:
        if white or not raw.free[i_param]:
            return 1.0
        return serial_factor(r, abs(raw.p[i_param]) / (2 * math.pi), dt)[0]

    infl = factor(4)
    multi = raw.kind in ("two_mode", "three_mode")
    facs = {iw: (factor(iw) if multi and iw > 4 else infl) for iw in range(4, raw.p.size, 4)}
    if infl > 1.0:
        notes.append(f"residuals not white (Ljung-Box p = {lb_p:.2g} < {LB_ALPHA:g}, lag-1 rho = {rho:.3f}): "
                     f"std x{infl:.2f}, the residual spectral density at the oscillation frequency relative "
                     f"to white noise (AR model)")
    check = {"ljung_box": lb_q, "p": lb_p, "white": bool(white), "lag1": rho}
    tss = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - raw.cost / tss if tss > 0 else float("nan")
    rss_n = max(raw.cost / n, np.finfo(float).tiny)
    aic = n * math.log(rss_n) + 2 * npar
    bic = n * math.log(rss_n) + npar * math.log(n)
    p = raw.p
    names = _names(raw.kind, p.size)

    def mode(ia, ib, iw, isg, w=None, sd_w=None):
        """One damped cosine; ``w`` (rad/s) and its std ``sd_w`` default
        to the parameter ``p[iw]`` and its std."""
        fac = facs.get(iw, infl)
        a, b, sg = (float(p[i]) for i in (ia, ib, isg))
        w = float(p[iw]) if w is None else w
        T = 2 * math.pi / w
        sd_w = max(_std(cov, iw), hc.get(iw, 0.0)) if sd_w is None else sd_w
        sdT_raw = 2 * math.pi / w ** 2 * sd_w
        wn = math.hypot(w, sg)
        zeta = sg / wn
        zstd = _grad_std(cov, [iw, isg], [-sg * w / wn ** 3, w ** 2 / wn ** 3])
        return {"period": T, "std": sdT_raw * fac, "std_raw": sdT_raw, "frequency": 1 / T,
                "omega": w, "omega_n": wn, "period_undamped": 2 * math.pi / wn,
                "damping_ratio": zeta, "damping_ratio_std": zstd * fac,
                "sigma": sg, "sigma_std": _std(cov, isg) * fac,
                "amplitude": math.hypot(a, b), "phase": math.atan2(-b, a)}

    if raw.kind == "viscous":
        modes = [mode(2, 3, 4, 5)]
        m = modes[0]
        damping = {"sigma": m["sigma"], "sigma_std": m["sigma_std"],
                   "zeta": m["damping_ratio"], "zeta_std": m["damping_ratio_std"]}
        T_und = m["period_undamped"]
    elif raw.kind == "chirp":
        # the frequency at the amplitude the least-squares phase weights
        # (period_amplitude of the envelope), a stated constant
        a, b, w, sg, beta, beta2 = (float(v) for v in p[2:8])
        A0 = math.hypot(a, b)
        a_ref = period_amplitude(t, A0 * np.exp(-sg * (t - raw.t0)))
        u = (a_ref / A0) ** 2 if A0 > 0 else 0.0
        du = -2.0 * u * (beta + 2.0 * beta2 * u) / A0 ** 2 if A0 > 0 else 0.0  # d(omega)/dA0 / A0
        grad = {2: du * a, 3: du * b, 4: 1.0, 6: u, 7: u * u}
        idx = sorted(grad)
        sd_w = _grad_std(cov, idx, [grad[i] for i in idx])
        if white and not roundoff:
            sd_w = max(sd_w, _hc_lin_std(raw, covf, s2, r, dof, grad))
        modes = [mode(2, 3, 4, 5, w=w + beta * u + beta2 * u * u, sd_w=sd_w)]
        modes += [mode(i, i + 1, i + 2, i + 3) for i in further_modes(raw.kind, p.size)]  # other oscillations
        m = modes[0]
        bstd = _std(cov, 6) * infl
        damping = {"sigma": m["sigma"], "sigma_std": m["sigma_std"],
                   "zeta": m["damping_ratio"], "zeta_std": m["damping_ratio_std"]}
        m.update(reference_amplitude=a_ref, beta=beta, beta_std=bstd,
                 beta2=beta2, beta2_std=_std(cov, 7) * infl if raw.free[7] else 0.0,
                 period_zero_amplitude=2 * math.pi / w, period_start=2 * math.pi / (w + beta + beta2))
        T_und = m["period_undamped"]
    elif multi:
        modes = [mode(i, i + 1, i + 2, i + 3) for i in range(2, p.size, 4)]
        T_rec = float(t[-1] - t[0])
        modes.sort(key=lambda d: _mode_rank(d["omega"], d["amplitude"], T_rec, d["sigma"]))
        m = modes[0]
        damping = {"sigma": m["sigma"], "sigma_std": m["sigma_std"], "zeta": m["damping_ratio"],
                   "zeta_std": m["damping_ratio_std"], "second_sigma": modes[1]["sigma"],
                   "second_zeta": modes[1]["damping_ratio"]}
        T_und = m["period_undamped"]
    else:  # quadratic
        a, b, w, kap, sg = (float(v) for v in p[2:7])
        A0 = math.hypot(a, b)
        T = 2 * math.pi / w
        sdT_raw = 2 * math.pi / w ** 2 * max(_std(cov, 4), hc.get(4, 0.0))
        k = kap / A0 if A0 > 0 else float("nan")
        kstd = _grad_std(cov, [2, 3, 5], [-kap * a / A0 ** 3, -kap * b / A0 ** 3, 1 / A0]) if A0 > 0 else float("nan")
        zeta = (sg + kap) / w
        zstd = _grad_std(cov, [4, 5, 6], [-(sg + kap) / w ** 2, 1 / w, 1 / w])
        damping = {"k": k, "k_std": kstd * infl, "kappa": kap, "kappa_std": _std(cov, 5) * infl,
                   "sigma": sg, "sigma_std": _std(cov, 6) * infl if raw.free[6] else 0.0}
        modes = [{"period": T, "std": sdT_raw * infl, "std_raw": sdT_raw, "frequency": 1 / T, "omega": w,
                  "damping_ratio": zeta, "damping_ratio_std": zstd * infl, "amplitude": A0,
                  "phase": math.atan2(-b, a)}]
        m = modes[0]
        T_und = None
        T_rec = float(t[-1] - t[0])
        if kap * T_rec < 1e-6:
            notes.append("quadratic damping coefficient at its bound k = 0 (the data want none)")
        if raw.free[6] and sg * T_rec < 1e-6:
            notes.append("viscous term of the quadratic model at its bound sigma = 0")
    free_n = [nm for nm, f in zip(names, raw.free) if f]
    env = np.abs(_envelope(raw.kind, p, t, raw.t0))
    if not raw.converged:
        notes.append(f"least squares did not converge: {raw.message}")
    return PeriodFit(
        model=model_name, period=m["period"], std=m["std"], frequency=m["frequency"],
        damping_ratio=m["damping_ratio"], damping=damping, amplitude=m["amplitude"], phase=m["phase"],
        offset=float(p[0]), drift=float(p[1]), residual_rms=float(math.sqrt(raw.cost / n)),
        r_squared=float(r2), n_samples=int(n), covariance=cov, params=p.copy(), param_names=names,
        t0=float(t[0]), t1=float(t[-1]), t_ref=float(raw.tm), std_raw=m["std_raw"], std_inflation=infl,
        lag1_autocorr=rho, noise_std=_noise_sigma(r),
        amplitude_rms=float(np.sqrt(np.mean(env ** 2))), amplitude_period=period_amplitude(t, env),
        period_undamped=T_und, aic=aic, bic=bic,
        converged=raw.converged, modes=modes, t_used=t.copy(), residuals=r.copy(), notes=notes,
        selection={"free_parameters": free_n}, residual_check=check, _kind=raw.kind)


def period_amplitude(t: np.ndarray, env: np.ndarray) -> float:
    """The constant amplitude ([y]) at which a pendulum shows the period a
    least-squares fit finds in a record whose envelope ``env`` (at the
    sample times ``t``, s) decays, when the period changes with the
    amplitude as ``A^2`` (a pendulum's first nonlinear term).

    The fitted frequency is the slope of the phase over time, weighted by
    the squared amplitude (the information of each sample): with weights
    ``w = env^2`` and their mean time ``t_w``, the slope averages the
    instantaneous frequency with the kernel ``K(t_i) = dt_i sum_{j >= i}
    w_j (t_j - t_w)`` (non-negative, zero at both ends of the window), so
    the amplitude it refers to is ``sqrt(sum K env^2 / sum K)``.  Not the
    energy-weighted RMS ``sqrt(sum env^4 / sum env^2)``, which ignores the
    lever arm ``t - t_w`` of a slope: 47 % too high in ``A^2`` for a
    record decaying to a fifth (docs/invert.md, "Inputs").  Without decay
    every weighting gives the envelope."""
    t = np.asarray(t, dtype=float)
    env = np.asarray(env, dtype=float)
    if t.size < 3 or not np.all(np.isfinite(env)):
        return float(np.sqrt(np.mean(env ** 2))) if env.size else float("nan")
    w = env ** 2
    sw = float(np.sum(w))
    if not sw > 0:
        return 0.0
    K = period_kernel(t, w)
    sk = float(np.sum(K))
    return float(np.sqrt(np.sum(K * w) / sk)) if sk > 0 else float(np.sqrt(sw / env.size))


def period_kernel(t: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The weights ``K(t_i)`` (s [y]^2, non-negative) with which a
    least-squares fit's frequency averages the instantaneous frequency of a
    record sampled at ``t`` (s, at least 2 samples) whose squared envelope
    is ``w`` ([y]^2, positive sum): ``K(t_i) = dt_i sum_{j >= i} w_j (t_j -
    t_w)``, ``t_w`` the ``w``-weighted mean time (:func:`period_amplitude`).
    Any other quantity the frequency follows (a second mode's squared
    amplitude, :func:`~bifilar.estimation.signal_swing.swing_decay`) is
    averaged by the same kernel."""
    tw = float(np.sum(w * t) / float(np.sum(w)))
    dt = np.diff(t, prepend=t[0] - float(np.median(np.diff(t))))
    K = dt * np.cumsum((w * (t - tw))[::-1])[::-1]
    return np.maximum(K, 0.0)  # non-negative in exact arithmetic; rounding at the ends
