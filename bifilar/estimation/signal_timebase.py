"""Dropped frames in a record without a time column.

A record read at a stated sample rate (``--sample-rate``, or a ``.mat``
file's rate variable) has the nominal time base ``t_j = j / fs``.  A camera
that dropped frames leaves the samples after each drop one frame ``dt = 1 /
fs`` later than that time base says: the oscillation's phase steps forward
by ``h = 2 pi f dt`` at every drop (0.12 rad at 30 fps for a 1.7 s
period), the time base is short by the drops' share and the fitted period
with it (audit 16, row 2d: 1 % dropped, the period 1 % short, z down to
-32, 4 of 10 draws with no warning).  The phase differences here place a
drop to about a cycle only; where the phase shows each frame's step,
:mod:`.signal_frames` puts the frames back, and :func:`check_time_base`
decides the answer (put back, the std widened, or refused).

:func:`phase_steps` finds the staircase: the phase of the fitted frequency
over one cycle of samples just after each sample ``j`` minus that just
before it (complex demodulation, the local mean removed) is flat, at the
record's small frequency offset, where the time base is regular, and rises
by ``h`` in a triangle one cycle wide about each drop.  A dropped frame only
steps forward; an oscillation beating with another mode, or a changing
frequency, moves the phase both ways.  SI units: time s, frequency Hz,
phase rad.
"""

from __future__ import annotations

import numpy as np

#: a step counts when the phase difference rises above its floor by this
#: share of ``h`` (a backward one when it falls below it by as much)
STEP_SHARE = 0.5
#: the floor: this percentile of the phase differences (the regular time
#: base's level, between the drops' triangles)
FLOOR_PERCENTILE = 5.0
#: a sample is at the floor within this share of ``h``
FLOOR_BAND = 0.2
#: a step counts only where the phase difference's noise (white noise over
#: the local amplitude) is below this share of ``h``: its ``STEP_SHARE`` is
#: then 4 sigma (a faint, decayed stretch shows noise peaks as large)
MAX_NOISE_SHARE = 0.125
#: at least this many stretches of a cycle or more at the floor
MIN_FLAT_RUNS = 2
#: the warning needs at least this many steps forward ...
MIN_STEPS = 2
#: ... and at most this share of as many excursions backward (a beat)
MAX_BACKWARD_SHARE = 0.25
#: longer records are not checked (a camera's run at 30-240 fps is far
#: shorter; memory and time stay bounded)
MAX_SAMPLES = 200_000
#: fewer samples a cycle than this: one frame's phase step is too coarse
#: to tell from the cycle's own (not checked)
MIN_SAMPLES_PER_CYCLE = 8


def uniform_cycles(t, y, frequency: float, min_per_cycle: int, max_samples: int):
    """``(t, y, dt, W)`` (arrays, s, samples a cycle at ``frequency`` Hz)
    for a record of four cycles or more, ``min_per_cycle`` samples a cycle
    or more and at most ``max_samples``; else None."""
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    n = t.size
    if n < 2 or not (np.isfinite(frequency) and frequency > 0):
        return None
    dt = float(np.median(np.diff(t)))
    W = int(round(1.0 / (frequency * dt)))
    if W < min_per_cycle or n < 4 * W + 2 or n > max_samples:
        return None
    return t, y, dt, W


def fit_window(t, fit) -> slice:
    """The samples of ``t`` (s, increasing) in ``fit``'s window ``[t0,
    t1]`` (s) as a slice; the whole record where none lies in it.  The time
    base's checks read only these: a fault outside the window (a held
    start, a stretch cut off by ``--t-start``/``--t-stop``) does not touch
    the period fitted inside it."""
    t = np.asarray(t, float)
    if getattr(fit, "t0", None) is None or getattr(fit, "t1", None) is None:  # no window stated: the whole record
        return slice(0, t.size)
    idx = np.flatnonzero((t >= float(fit.t0)) & (t <= float(fit.t1)))
    return slice(int(idx[0]), int(idx[-1]) + 1) if idx.size else slice(0, t.size)


def detrended(y, W: int):
    """``(k, y[k] - m[k])``: the samples ``k`` where the mean ``m`` over
    exactly one cycle of ``W`` samples centred on them exists, less that
    mean (an offset or a drift many times the amplitude would leak into the
    phase otherwise)."""
    c = np.concatenate([[0.0], np.cumsum(y)])
    half = W // 2
    k = np.arange(half, y.size - (W - half) + 1)  # the mean over [k - half, k - half + W) is centred on k
    return k, y[k] - (c[k - half + W] - c[k - half]) / W


def white_noise(y) -> float:
    """The white noise's std in ``y`` ([y]) from its third differences
    (an oscillation sampled W times a cycle leaves ``A (2 pi / W)^3``)."""
    return float(np.sqrt(np.mean(np.diff(np.asarray(y, float), 3) ** 2) / 20.0))


def phase_steps(t, y, frequency: float) -> dict | None:
    """Steps of the phase of an oscillation at ``frequency`` (Hz) along a
    uniformly sampled record ``(t`` in s, ``y`` in any unit).

    Returns None when the record is too short (under four cycles), too
    coarsely sampled (under ``MIN_SAMPLES_PER_CYCLE`` samples a cycle) or
    longer than ``MAX_SAMPLES``;
    else a dict: ``step`` (``h = 2 pi f dt``, rad: one frame's phase),
    ``forward`` (the steps up above ``STEP_SHARE h``, where the phase
    difference's noise is below ``MAX_NOISE_SHARE h``: their times, s, one
    a half cycle at most), ``backward`` (the same, down), ``floor`` (rad, the
    ``FLOOR_PERCENTILE`` of the phase differences), ``flat_runs`` (how
    many stretches of a cycle or more stay within ``FLOOR_BAND h`` of it),
    ``flat_level`` (rad, their median: the fitted frequency's offset from
    the samples' own between drops, ``(omega - omega_fit) W dt``),
    ``samples_per_cycle`` (``W``).
    """
    u = uniform_cycles(t, y, frequency, MIN_SAMPLES_PER_CYCLE, MAX_SAMPLES)
    if u is None:
        return None
    t, y, dt, W = u
    n = t.size
    h = 2.0 * np.pi * frequency * dt
    half = W // 2
    k, yk = detrended(y, W)
    ym = np.full(n, np.nan)
    ym[k] = y[k] - yk
    z = (y - ym) * np.exp(-2j * np.pi * frequency * t)
    good = np.isfinite(z)
    z = np.where(good, z, 0.0)
    cz = np.concatenate([[0.0], np.cumsum(z)])
    lo, hi = int(k[0]), int(k[-1])  # z valid on [lo, hi]
    j = np.arange(lo + W, hi - W + 2)  # left window [j - W, j), right [j, j + W) both valid
    if j.size < 3:
        return None
    left = cz[j] - cz[j - W]
    right = cz[j + W] - cz[j]
    d = np.angle(right * np.conj(left))
    # the phase difference's noise where the record is faint: white noise sigma_y (from the third
    # differences: the oscillation's own is A h^3, small) on a cycle's sum of amplitude a W / 2
    sig_y = white_noise(y)
    amp = 2.0 * np.minimum(np.abs(left), np.abs(right)) / W
    with np.errstate(divide="ignore"):
        noise = np.where(amp > 0, 2.0 * sig_y / (amp * np.sqrt(W)), np.inf)
    floor = float(np.percentile(d, FLOOR_PERCENTILE))
    x = d - floor

    def peaks(v, level):
        # a step's triangle: up by ``level`` within one cycle on either side (a beat or a changing
        # frequency moves the phase difference far more slowly)
        i = np.arange(W, v.size - W)
        ok = (v[i] >= v[i - 1]) & (v[i] > v[i + 1]) & (v[i] > level) & (v[i] - v[i - W] > level) \
            & (v[i] - v[i + W] > level) & (noise[i] < MAX_NOISE_SHARE * h)
        idx = i[ok].tolist()
        kept: list[int] = []
        for i in idx:  # one a half cycle: a step's triangle is one cycle wide
            if kept and i - kept[-1] <= half:
                if v[i] > v[kept[-1]]:
                    kept[-1] = i
                continue
            kept.append(i)
        return [float(t[j[i]]) for i in kept]

    # stretches of a cycle or more flat at the floor: a regular time base between drops
    flat = np.abs(x) < FLOOR_BAND * h
    edges = np.flatnonzero(np.diff(np.concatenate([[0], flat.astype(int), [0]])))
    runs = int(np.sum(edges[1::2] - edges[::2] >= W))
    return {"step": float(h), "forward": peaks(x, STEP_SHARE * h), "backward": peaks(-x, STEP_SHARE * h),
            "floor": floor, "flat_runs": runs,
            "flat_level": float(np.median(x[flat]) + floor) if flat.any() else float("nan"), "samples_per_cycle": W}


def dropped_frames_warning(t, y, fit, time_source: str | None, field: str = "SIGNAL") -> str | None:
    """One line when a record without a time column shows its phase
    stepping forward by one frame's phase (:func:`phase_steps`) at least
    ``MIN_STEPS`` times with few steps backward: dropped frames, a time base
    short by them and a period short with it, which its std does not hold.
    None otherwise (a record with its time column is never checked: its
    times are the frames' own)."""
    if time_source != "sample_rate" or fit is None or getattr(fit, "model", "") == "crossings":
        return None
    win = fit_window(t, fit)
    w = _flat_level_warning(np.asarray(t, float)[win], np.asarray(y, float)[win], fit, field)
    return None if w is None else w[0]


def _flat_level_warning(t, y, fit, field: str) -> tuple[str, float] | None:
    """(the warning, the period between the steps, s) of
    :func:`dropped_frames_warning`, or None."""
    try:
        st = phase_steps(t, y, float(fit.frequency))
    except (ValueError, FloatingPointError):
        return None
    if st is None:
        return None
    nf, nb = len(st["forward"]), len(st["backward"])
    if nf < MIN_STEPS or nb > MAX_BACKWARD_SHARE * nf or st["flat_runs"] < MIN_FLAT_RUNS:
        return None
    where = ", ".join(f"{x:.3g}" for x in st["forward"][:5]) + (" ..." if nf > 5 else "")
    back = f"back only {nb} times" if nb else "never back"
    # between the drops the samples' time base is right: the phase difference's flat level is the
    # fitted frequency's offset from theirs, (omega - omega_fit) W dt
    dt = float(np.median(np.diff(t)))
    T_flat = 2 * np.pi / (2 * np.pi * float(fit.frequency) + st["flat_level"] / (st["samples_per_cycle"] * dt))
    short = 1.0 - float(fit.period) / T_flat
    return (f"{field}: the oscillation's phase steps forward by one frame's phase ({st['step']:.2g} rad) {nf} "
            f"times (at t = {where} s) and {back}: in a record without a time column that is the mark of "
            f"dropped frames (an irregular time base), which shorten the time base and the period by their share, "
            f"beyond the stated std (here about {short:.2%}: between the steps the record runs at a period of about "
            f"{T_flat:.5g} s, the fit {float(fit.period):.5g} s); the samples cannot give the missing times: "
            f"give the time column"), T_flat


def widen_std(fit, extra: float) -> None:
    """Add ``extra`` (s) to the fit's headline std in quadrature, as the
    ``time_base`` term of its ``uncertainty`` (the degrees of freedom
    recombined: the term counts as normal)."""
    import math

    old = float(fit.std)
    fit.std = math.hypot(old, float(extra))
    u = fit.uncertainty
    u["time_base"] = float(extra)
    u["total"] = fit.std
    if u.get("dof") is not None:
        from .uncertainty import combined_dof

        nu = combined_dof([(old, float(u["dof"])), (float(extra), math.inf)])
        u["dof"] = nu if math.isfinite(nu) else None
    if float(extra) > old:
        u["dominant"] = "time_base"
    if fit.modes:
        fit.modes[0]["std_total"] = fit.std


def check_time_base(t, y, fit, time_source: str | None, refit, field: str = "SIGNAL") -> dict | None:
    """The answer of a record without its time column whose camera dropped
    frames (design.md "dropfix, session 17").

    ``refit(t_new, y_new=y)`` fits samples (the record's, or those left
    where repeated frames were removed: only then is ``y_new`` given) on
    another time base (s) with the caller's options and returns a PeriodFit.  Returns None for a
    record with its time column, a crossings-only fit, or a record with no
    sign of dropped or repeated frames; else a dict: ``t`` (s, the time base the answer
    stands on), ``y`` (the samples it stands on, present where repeated
    frames were removed: :mod:`.signal_repeats`), ``fit`` (the answer: its ``std`` holds the time base's own
    term, ``uncertainty["time_base"]``), ``warning`` (one line),
    ``time_base`` (JSON: ``method``, ``dropped_frames``,
    ``nominal_period``, ``std_added``; ``repeated_frames`` where repeats
    were removed, ``method`` then ``"repeats_removed"`` unless frames were
    also put back or the std widened for drops).

    ``method`` is ``"phase_walk"`` where none of that shows but the phase
    strays from the fit's cycle by cycle as frames' steps would move it
    (:func:`.signal_phasewander.phase_walk_check`: the std widened), and
    ``"recovered"`` where :func:`.signal_frames.recover_frames`
    finds the frames' lattice and the refit on it explains the record
    better (the drops put back; the term is
    :func:`.signal_frames.correction_std`), ``"widened"`` where only the
    phase steps are seen (:func:`phase_steps`): the fit on the nominal time
    base stays the answer and the distance to the period between the steps
    joins its std, so its interval reaches the truth.
    """
    if time_source != "sample_rate" or fit is None or getattr(fit, "model", "") == "crossings":
        return None
    from .signal_repeats import remove_repeats

    from .signal_phasewander import phase_walk_check

    rep = remove_repeats(t, y, fit, refit, field)  # frames written twice: removed first (design.md "dropfix2")
    if rep is None:  # nothing seen frame by frame: the phase's walk (faults the noise hides, design.md "dropfix3")
        return _check_drops(t, y, fit, refit, field) or phase_walk_check(t, y, fit, field)
    y = rep["y"]
    res = _check_drops(rep["t"], y, rep["fit"], lambda tn: refit(tn, y), field) \
        or phase_walk_check(rep["t"], y, rep["fit"], field)
    if res is None:
        res = {"t": rep["t"], "fit": rep["fit"], "warning": rep["warning"],
               "time_base": {"method": "repeats_removed", "dropped_frames": None, "std_added": rep["std_added"]}}
    else:
        res["warning"] = rep["warning"] + "; also " + res["warning"]
        if res["time_base"]["method"] == "recovered" and rep["std_added"] > 0:  # a fresh refit: add the repeats'
            widen_std(res["fit"], rep["std_added"])
        both = float(np.hypot(rep["std_added"], res["time_base"]["std_added"]))
        res["time_base"]["std_added"] = res["fit"].uncertainty["time_base"] = both
    res["y"] = y
    res["time_base"].update(repeated_frames=rep["repeated"], nominal_period=rep["nominal_period"])
    return res


def _check_drops(t, y, fit, refit, field: str) -> dict | None:
    """:func:`check_time_base`'s dropped frames, on a record without repeats."""
    from .signal_frames import MAX_RMS_RATIO, correction_std, recover_frames

    t = np.asarray(t, float)
    y = np.asarray(y, float)
    win = fit_window(t, fit)  # only the fit's samples are read
    tw, yw = t[win], y[win]
    rec = None
    if float(fit.residual_rms) >= SEARCH_RESIDUAL_EXCESS * white_noise(yw):
        try:
            rec = recover_frames(tw, yw, float(fit.frequency))
        except (ValueError, FloatingPointError):
            rec = None
    if rec is not None and rec["resolved"]:
        from .signal import SignalError

        # the window's recovered times; the samples after it later by the frames put back
        dt = float(np.median(np.diff(tw)))
        t_rec = np.concatenate([t[:win.start], rec["t"], t[win.stop:] + rec["dropped"] * dt])
        try:
            fit2 = refit(t_rec)
        except SignalError:
            fit2 = None
        if fit2 is not None and fit2.model != "crossings" and fit2.residual_rms <= MAX_RMS_RATIO * fit.residual_rms:
            W = int(round(1.0 / (fit2.frequency * dt)))
            extra = correction_std(float(fit2.period), tw.size, rec["dropped"], rec["edge"], W)
            widen_std(fit2, extra)
            short = 1.0 - float(fit.period) / float(fit2.period)
            msg = (f"{field}: {rec['dropped']} dropped frames found and put back (the oscillation's phase on the "
                   f"nominal time base steps forward by one frame's phase at each; in a record without a time "
                   f"column the time base and the period are short by the drops' share, here {short:.2%}): the "
                   f"period {float(fit2.period):.6g} s is fitted on the recovered time base (on the nominal one "
                   f"{float(fit.period):.6g} s) and its std holds the recovery's own {extra:.2g} s; give the time "
                   f"column to be sure")
            return {"t": t_rec, "fit": fit2, "warning": msg,
                    "time_base": {"method": "recovered", "dropped_frames": rec["dropped"],
                                  "nominal_period": float(fit.period), "std_added": extra}}
    w = _flat_level_warning(tw, yw, fit, field)
    if w is None:
        _refuse_hidden_drops(tw, yw, fit, rec, field)
        return None
    msg, T_flat = w
    extra = abs(T_flat - float(fit.period))
    widen_std(fit, extra)
    return {"t": t, "fit": fit, "warning": msg + f"; the period's std holds the {extra:.2g} s between the two",
            "time_base": {"method": "widened", "dropped_frames": None, "nominal_period": float(fit.period),
                          "std_added": extra, "period_between_steps": T_flat}}


#: the frames' lattice is searched (:func:`.signal_frames.recover_frames`; with the refit 0.75 s CPU for 2075
#: samples, growing as their square: scripts/bench_timebase.py) only where the nominal fit leaves this much more than the record's white noise (third
#: differences, :func:`white_noise`).  On dropfix's 176 synthetic records (docs/design.md "dropfix, session 17")
#: every record put back, widened or refused left 1.22-17 x, so none of those outcomes changes; 71 of the 80
#: drop-free controls (all clean and quantised ones, 23 of 24 beats, 8 of 16 chirps) leave below 1.1 x and skip it
SEARCH_RESIDUAL_EXCESS = 1.1


#: the refusal: a lattice this weak at best (the noise allows no more) hides
#: one frame's step in each sample's phase (the KTH records, 240 Hz, allow
#: 0.71-0.90 and show none: no drops there)
HIDDEN_LATTICE = 0.5
#: ... the fit leaves this much more than the record's white noise (dropped
#: frames the fit cannot follow: 1.2-3.8 measured where they were not put
#: back, one at 1.18 missed; a beat's two-mode fit 0.93-1.12; dropfix2: 1.15,
#: so that 1 % dropped with two repeats removed, 1.176, is refused as the
#: same record with its repeats was, 1.215) ...
MIN_RESIDUAL_EXCESS = 1.15


def _refuse_hidden_drops(t, y, fit, rec, field: str) -> None:
    """Exit 2 (InputError naming ``field``) for a record without its time
    column that shows the phase steps of dropped frames (``MIN_STEPS``
    forward or more, at most ``MAX_BACKWARD_SHARE`` as many back) where
    neither the frames could be put back nor a drop-free stretch gives the
    period between them: its noise hides a frame's step
    (``lattice_expected`` below ``HIDDEN_LATTICE``) and the fit leaves
    ``MIN_RESIDUAL_EXCESS`` times the white noise or more.  The period is
    then short by the drops' unknown share (3 % dense drops: 2.6-4.0 %,
    z -2.3 .. -146) and no std can hold it."""
    if rec is None or not rec["lattice_expected"] < HIDDEN_LATTICE:
        return
    try:
        st = phase_steps(t, y, float(fit.frequency))
    except (ValueError, FloatingPointError):
        return
    if st is None:
        return
    nf, nb = len(st["forward"]), len(st["backward"])
    sig_y = white_noise(y)
    if nf < MIN_STEPS or nb > MAX_BACKWARD_SHARE * nf or not float(fit.residual_rms) >= MIN_RESIDUAL_EXCESS * sig_y:
        return
    from ..errors import InputError
    from .signal_phasewander import lean_direction, phase_lean

    raise InputError(field, hidden_frames_message(nf, nb, float(fit.residual_rms) / sig_y,
                                                  lean_direction(phase_lean(t, y, fit))))


def hidden_frames_message(nf: int, nb: int, excess: float, direction: str | None) -> str:
    """The refusal's words for frame faults the noise hides (``nf`` steps
    forward, ``nb`` back, the fit ``excess`` x the white noise): the time
    base's direction from the skew of the cycles' phase advances
    (:func:`.signal_phasewander.lean_direction`): ``"forward"`` dropped
    frames (the period short), ``"back"`` repeated frames (long), None
    neither named."""
    steps = f"{'back only ' + str(nb) + ' times' if nb else 'never back'}"
    if direction == "forward":
        what = ("the oscillation's phase steps forward by one frame's phase {nf} times and {steps}, and its "
                "cycle-to-cycle advance leans forward")
        mark = "dropped frames in a record without a time column, which shorten the period by their unknown share"
    elif direction == "back":
        what = ("the oscillation's phase jumps by one frame's phase {nf} times, but its cycle-to-cycle advance "
                "leans back")
        mark = ("repeated frames (a frame written twice) in a record without a time column, which lengthen the "
                "period by their unknown share")
    else:
        what = ("the oscillation's phase jumps by one frame's phase {nf} times, its cycle-to-cycle advance "
                "leaning neither way")
        mark = ("dropped or repeated frames in a record without a time column, which shift the period by their "
                "unknown share")
    return (what.format(nf=nf, steps=steps) + f", and the fit leaves {excess:.2g} x the record's noise: the mark of "
            f"{mark}; the noise hides each frame's step, so they cannot be put back: give the record's time column "
            f"in place of --sample-rate")
