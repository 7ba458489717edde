"""A found second mode's own decay rate, read off the envelope of the tone
that showed it (docs/design.md, "swingrate, session 17").

Why: a damped record's second mode (a swing found from its tone,
:func:`~bifilar.estimation.signal_swing.infer_secondary`) is run in the
undamped model at the amplitude the record's period refers to, which
depends on how fast the swing decays.  Taken as the timed mode's rate with
a stated relative std (:data:`DECAY_SHARE`
= 1.0, wide enough for a swing decaying at a third to three times the
torsion's rate), the Izz std of every damped record with a found swing was
1.5-1.6x what the 0.5 share gave (docs/design.md, "damprate, session 16").

What the tone says: a multi-mode fit holds the tone as a damped cosine,
its amplitude decaying at ``sigma_tone``; relative to the timed mode (rate
``sigma_t``) at ``rho = sigma_tone - sigma_t``.  How that rate follows the
swing's depends on how the tone is made, which its frequency tells (the
model's linear frequencies, :data:`COMBO_TOL`):

* ``|2 f_s - f_t|`` (swing^2 x timed mode: the quadcopter's 2.40 s tone):
  ``rho = 2 sigma_s``;
* ``|f_o +- f_s|`` with ``o`` any other mode, the timed one included (the
  quadcopter's 2.57 s tone, pitch x swing, the pitch a free oscillation
  the release started): ``rho = sigma_s + sigma_o - sigma_t``, with
  ``sigma_o`` taken as ``sigma_t`` (a stated assumption: the other factor
  decays as the timed mode does; exact for the timed mode itself, and for
  a body's rotations damped alike), so ``sigma_s = rho``.

Its std: the two fitted rates' (each with its fit's serial inflation) over
the swing's power in the tone, and :data:`RATE_SHARE` of the rate for what
the fit's neighbouring oscillations and the assumption above do to it.  A
tone from a single-mode fit's residuals has its rate refitted beside the
fit's mismatch at the fundamental (:func:`residual_tone_rate`).  A tone
whose frequency matches no combination, a fit without the timed mode's
rate (``quadratic``), and a rate whose std gives a wider share than the
stated one (the rule it replaces) keep the old rule.

Units: rates 1/s (amplitude ``exp(-sigma t)``), frequencies Hz.
"""

from __future__ import annotations

import math

import numpy as np

#: the relative std of a found second mode's decay rate where it is taken as the timed mode's (the record's envelope;
#: where its tone does not give its own, :func:`own_decay`): a stated share, not a measurement.  The tone law alone
#: cannot tell it (the tone's frequency says how it is made, :func:`tone_swing_rate`): the quadcopter's tones
#: decay as the swing and the motion that makes them do (its 2.57 s tone, pitch x swing, at the swing's rate over
#: the torsion's, the 2.40 s one, swing^2 x torsion, at twice it), which the undamped model's tone law does not say
#: (docs/design.md, "dampdecay, session 14").  What it covers, measured (the quadcopter, torsion Q 100, 30
#: cycles): at 0.5 a swing decaying between half and three times the timed mode's rate (|z| <= 1.92), but at a
#: third of it 14 of 20 inside (z -2.21..-1.47); at 1.0 every rate measured, a third to three times, inside
#: (20 of 20 at a third), the Izz std of a damped record with a found swing 1.5-1.6x wider (docs/design.md,
#: "damprate, session 16"; lead, session 16: a swing decaying three times slower than the torsion is a real
#: rig's, a torsion damped by the body's air drag, so the wider share)
DECAY_SHARE = 1.0
#: a tone's frequency is read as a combination of the model's linear frequencies within this share of it (the
#: model's frequencies are at the prior and small amplitude: the quadcopter's tones lie within 0.3 % of theirs)
COMBO_TOL = 0.02
#: the degree in time of the single-mode fit's mismatch at its fundamental fitted beside a residual tone
#: (:func:`residual_tone_rate`): the quadcopter's tones read their truth's rate at 3, not below it
CHIRP_DEGREE = 3
#: the relative std of a swing's rate read off its tone, beyond the fits' own: the other factor of a pitch x swing
#: tone decaying otherwise than the timed mode, the multi-mode fit's neighbouring oscillations (measured on the
#: quadcopter's fits, docs/design.md, "swingrate, session 17": truth 3x the torsion's rate read 2.5-5.2x, one draw
#: whose start holds a transient 1.2x; 17 of 18 within 2 of their std)
RATE_SHARE = 0.3


def _combination(f_tone: float, f_t: float, f_s: float, others) -> int | None:
    """The swing's power in the tone at ``f_tone`` (Hz): 2 where it is
    ``|2 f_s - f_t|``, 1 where it is ``|f_o +- f_s|`` (``f_o`` the timed
    mode's ``f_t`` or one of ``others``), the closer match within
    :data:`COMBO_TOL`; None where neither."""
    cands = [(abs(abs(2 * f_s - f_t) - f_tone), 2)]
    for f_o in [f_t, *others]:
        cands += [(abs(abs(f_o - f_s) - f_tone), 1), (abs(f_o + f_s - f_tone), 1)]
    err, n = min(cands)
    return n if err <= COMBO_TOL * f_tone else None


def tone_swing_rate(m, tone: dict, hm, j: int, k0: int) -> tuple[float, float] | None:
    """(sigma_s, std), 1/s: the decay rate of the second mode ``j`` (index
    among ``hm.modes0.modes``) that measurement ``m``'s record shows by
    ``tone`` (:func:`~bifilar.estimation.signal_swing.record_tones`' dict,
    with its fitted ``sigma`` and ``sigma_std``), the timed mode being
    ``k0``; None where the record's tone cannot say (module docstring): a
    fit without the timed mode's rate, a frequency no combination makes.
    The rate is floored at 0 (a swing does not grow; its std stays)."""
    fit = getattr(m, "fit", None)
    modes = getattr(fit, "modes", None) or []
    if not modes or "sigma" not in tone:
        return None
    m0 = modes[0]
    sg_t, sd_t = m0.get("sigma"), m0.get("sigma_std")
    sg, sd = tone.get("sigma"), tone.get("sigma_std")
    if tone.get("source") == "residual":
        sg, sd = residual_tone_rate(fit, 1.0 / tone["period"], float(sg))
    if any(v is None or not math.isfinite(float(v)) for v in (sg_t, sd_t, sg, sd)):
        return None
    ms = hm.modes0.modes
    f_s = 1.0 / ms[j].period
    others = [1.0 / mo.period for i, mo in enumerate(ms) if i not in (j, k0) and mo.period]
    n = _combination(1.0 / tone["period"], float(m0["frequency"]), f_s, others)
    if n is None:
        return None
    rate = (float(sg) - float(sg_t)) / n
    std = math.hypot(math.hypot(float(sd), float(sd_t)) / n, RATE_SHARE * abs(rate))
    return max(rate, 0.0), std


def residual_tone_rate(fit, f_tone: float, sigma0: float) -> tuple[float, float]:
    """(sigma, std), 1/s: the decay rate of the tone at ``f_tone`` (Hz) in
    single-mode fit ``fit``'s residuals, fitted as one damped cosine (start
    ``sigma0``, 1/s) beside the fit's own mismatch at its fundamental: that
    frequency's cosine and sine under the fit's envelope times ``tau^p``, p
    0..:data:`CHIRP_DEGREE` (``tau`` s from the window's start), linear
    unknowns (variable projection).  The std is the least-squares one times
    the residuals' local inflation at the tone
    (:func:`~bifilar.estimation.signal_swing.tone_inflation`).  (nan, nan)
    where the fit fails.

    Why: a damped record's chirp leaves the single-mode fit's mismatch about
    its fundamental, and the tone's own damped cosine fit
    (:func:`~bifilar.estimation.signal_swing.residual_tones`) takes part of
    it into its envelope: on the quadcopter's records (docs/design.md,
    "swingrate, session 17") a swing decaying at 1/3 (3x) the torsion's rate
    read -0.39..-0.03 (1.2-1.4) of it; beside a cubic mismatch
    0.23-0.26 (2.6-3.1)."""
    from scipy.optimize import least_squares

    from .signal_swing import tone_inflation

    t, r = np.asarray(fit.t_used, float), np.asarray(fit.residuals, float)
    tau = t - t[0]
    m0 = fit.modes[0]
    w0, s0 = float(m0["omega"]), float(m0.get("sigma", 0.0) or 0.0)
    e0 = np.exp(-s0 * tau)
    B = np.column_stack([e0 * tau ** p * f(w0 * tau) for p in range(CHIRP_DEGREE + 1) for f in (np.cos, np.sin)])

    def res(q):
        e = np.exp(-q[1] * tau)
        X = np.c_[e * np.cos(q[0] * tau), e * np.sin(q[0] * tau), B]
        return X @ np.linalg.lstsq(X, r, rcond=None)[0] - r

    try:
        sol = least_squares(res, [2 * math.pi * f_tone, sigma0], x_scale="jac")
        dof = max(t.size - 4 - B.shape[1], 1)
        s2 = float(np.sum(sol.fun ** 2)) / dof
        var = s2 * float(np.linalg.inv(sol.jac.T @ sol.jac)[1, 1])
    except (ValueError, np.linalg.LinAlgError):
        return float("nan"), float("nan")
    infl = max(float(getattr(fit, "std_inflation", 1.0) or 1.0), 1.0)
    k_t = tone_inflation(t, sol.fun, sol.x[0] / (2 * math.pi), s2, infl)
    return float(sol.x[1]), math.sqrt(max(var, 0.0)) * k_t


def decay_at_rate(t, K, rate: float, std: float) -> tuple[float, float]:
    """(g, s): the share of a second mode's start amplitude that a record's
    fitted period refers to when the mode decays as ``exp(-rate tau)``
    (``tau`` s from the window's start ``t[0]``, ``rate`` 1/s), its period
    shift going as its amplitude squared and averaged with the weights
    ``K`` (:func:`~bifilar.estimation.signal_result.period_kernel` of the
    record's samples ``t``, s): ``g = sqrt(sum K e^(-2 rate tau) / sum
    K)``; and ``g``'s relative std from the rate's ``std`` (1/s): ``|d ln
    g / d rate| std``, ``d ln g / d rate = -sum K e^(-2 rate tau) tau /
    sum K e^(-2 rate tau)``."""
    t = np.asarray(t, float)
    tau = t - t[0]
    w = np.asarray(K, float) * np.exp(-2.0 * rate * tau)
    sk, sw = float(np.sum(K)), float(np.sum(w))
    g = math.sqrt(sw / sk)
    return g, abs(float(np.sum(w * tau)) / sw) * std


def own_decay(m, tone: dict, hm, j: int, k0: int, g: float, g_rel: float):
    """(g, g_rel, rate): the second mode ``j``'s decay share ``g`` and its
    relative std (:func:`swing_decay`'s
    meaning) from its own rate read off ``tone`` (:func:`tone_swing_rate`),
    with ``rate`` its (value, std) in 1/s; the given ``g``, ``g_rel`` (the
    timed mode's rate with the stated share) and None where the tone cannot
    say or its rate is the less certain (its ``g_rel`` the larger)."""
    rate = tone_swing_rate(m, tone, hm, j, k0)
    kern = decay_kernel(m)
    if rate is None or kern is None:
        return g, g_rel, None
    g2, rel2 = decay_at_rate(kern[0], kern[2], *rate)
    if not (math.isfinite(rel2) and rel2 < g_rel and g2 > 0):
        return g, g_rel, None
    return g2, rel2, rate


def swing_decay(m) -> tuple[float, float]:
    """(g, s): a second mode's amplitude that measurement ``m``'s fitted
    period refers to over its amplitude at the fit window's start
    (unit-free, <= 1 for a decaying record), and the relative std of that
    amplitude from ``g``'s uncertainty.  (1, 0) where the record does not
    decay measurably (damping ratio within
    :data:`~bifilar.estimation.signal_swing.DECAY_Z` of its std) or
    holds no fit with an envelope.

    The second mode is taken to decay as the timed mode does (its envelope
    ``u = env / env(t0)`` to the power ``lam``, ``lam`` = 1 with the
    relative std :data:`DECAY_SHARE` and the record's damping ratio's),
    and its period shift to go as its amplitude squared, averaged over the
    window as the fitted frequency averages the instantaneous one
    (:func:`~bifilar.estimation.signal_result.period_kernel`, weights from
    the timed mode's envelope): ``g = sqrt(sum K u^(2 lam) / sum K)``, at
    ``lam`` = 1 the timed mode's own ``decay``; ``d ln g / d lam = sum K
    u^2 ln u / sum K u^2``.

    Why: the model runs undamped; released with the swing at its start
    amplitude it put the swing's whole start shift in a record whose swing
    decays with it (the quadcopter, torsion 0.118 rad and swing-y 3 cm at
    Q 200 / 100 over 30 cycles: Izz z +0.6..+1.3 / +1.2..+2.2).  Measured
    on those records (the fitted period with the swing less without it,
    against the undamped model's shift ~ a^2): the amplitude it refers to
    is 0.812-0.816 / 0.692-0.697 of the start, this rule 0.811 / 0.690,
    the plain RMS of the envelope 0.805 / 0.671 (docs/design.md,
    "dampdecay, session 14")."""
    kern = decay_kernel(m)
    if kern is None:
        return 1.0, 0.0
    fit = m.fit
    zeta = float(fit.damping_ratio)
    z_std = float(fit.modes[0].get("damping_ratio_std", 0.0) or 0.0)
    t, u2, K = kern
    sk, sku = float(np.sum(K)), float(np.sum(K * u2))
    if not (sk > 0 and sku > 0):
        return 1.0, 0.0
    g = math.sqrt(sku / sk)
    dlng = float(np.sum(K * u2 * 0.5 * np.log(u2))) / sku
    return g, abs(dlng) * math.hypot(DECAY_SHARE, z_std / zeta)


def decay_kernel(m):
    """(t s, u2, K): measurement ``m``'s fit window's samples, its timed
    mode's squared envelope over its start's and the weights with which its
    fitted period averages (:func:`~bifilar.estimation.signal_result.period_kernel`);
    None where the record does not decay measurably
    (:func:`~bifilar.estimation.signal_swing._decays`) or
    holds no fit with a positive envelope."""
    from .signal_result import period_kernel
    from .signal_swing import _decays

    fit = getattr(m, "fit", None)
    t = getattr(fit, "t_used", None)
    if fit is None or t is None or len(t) < 3 or not getattr(fit, "modes", None):
        return None
    if not _decays(fit):
        return None
    t = np.asarray(t, float)
    env = np.abs(np.asarray(fit.envelope(t), float))
    if not (np.all(np.isfinite(env)) and env[0] > 0 and np.all(env > 0)):
        return None
    u2 = (env / env[0]) ** 2
    return t, u2, period_kernel(t, u2)
