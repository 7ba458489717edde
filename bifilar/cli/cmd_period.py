"""`bifilar period`: the period of a recorded oscillation or of stopwatch
trials (a thin CLI on :mod:`bifilar.estimation.signal` and
:func:`bifilar.estimation.period_specs.period_from_trials`)."""

from __future__ import annotations

import math

import click

from .common import check_output_path, console, emit_json, esc, fmt, handle_errors

_MODELS = ("auto", "viscous", "quadratic", "quadratic+viscous", "two_mode", "three_mode")


@click.command("period")
@click.argument("signal", type=click.Path(), required=False)
@click.option("--column", default=None, help="Signal column (CSV) or variable (.mat); default: the first non-time numeric one.")
@click.option("--sample-rate", default=None, help="Sample rate, Hz (ignores a time column).")
@click.option("--model", default="auto", show_default=True,
              help="Fit model: viscous, quadratic (drag ~ v^2), quadratic+viscous, two_mode (beating), "
                   "three_mode (two modes and a third oscillation close to the dominant one) or auto (fits them all, each with a drift term, and keeps the lowest BIC among the "
                   "admissible ones).")
@click.option("--t-start", default=None, help="Start of the fit window, s.")
@click.option("--t-stop", default=None, help="End of the fit window, s.")
@click.option("--trim", is_flag=True, help="Drop the settled tail where the envelope is lost in the noise.")
@click.option("--timed", default=None, metavar="LABEL=N:T1,T2,...",
              help="Instead of SIGNAL: stopwatch trials of N cycles each, total times in s.")
@click.option("--target", default=None,
              help="With --timed: the wanted std of the period (0.1%, 1e-3 relative, or 0.5ms); prints the "
                   "cycles per trial needed for 1, 2, 3, 5, 10, 20 trials.")
@click.option("--uncertainty", multiple=True, metavar="KEY=VALUE",
              help="With --timed: override trial_time, the reaction-time floor of one trial's total time (s).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document (interface.md).")
@click.option("--plot", type=click.Path(), default=None,
              help="Draw the signal, the fit and the residuals to this image file.")
@click.option("--force", is_flag=True, help="Replace an existing --plot file.")
@handle_errors
def period(signal, column, sample_rate, model, t_start, t_stop, trim, timed, target, uncertainty, as_json,
           plot, force):
    """Fit the period (s), its standard uncertainty and the damping ratio of a
    recorded oscillation SIGNAL (CSV with a t/time column in s, or .mat), or
    reduce stopwatch trials (--timed).  Exit 2 for a record that is not an
    oscillation (no significant spectral peak, fewer than two cycles, a fit
    explaining almost nothing, a broken time column).  Sampled below twice its
    frequency an oscillation shows as a slower alias that no record alone can
    tell apart (a note flags fits above fs/2.5; `invert --signal` checks the
    config's modes)."""
    from ..errors import InputError

    if timed is not None:
        if signal is not None:
            raise InputError("--timed", "give either SIGNAL or --timed, not both")
        # a recording's options were silently ignored (--plot drew nothing): refused, as --target without --timed is
        for name, v in (("--plot", plot), ("--column", column), ("--sample-rate", sample_rate),
                        ("--t-start", t_start), ("--t-stop", t_stop), ("--trim", trim or None),
                        ("--model", None if model == "auto" else model)):
            if v is not None:
                raise InputError(name, "only with a recording (SIGNAL); --timed trials have no record to "
                                       f"{'draw' if name == '--plot' else 'fit'}")
        return _timed(timed, target, uncertainty, as_json)
    if target is not None:
        raise InputError("--target", "only with --timed (a recording's precision is set by the recording)")
    if signal is None:
        raise InputError("SIGNAL", "give a recording (CSV or .mat) or --timed LABEL=N:T1,T2,...")
    if model not in _MODELS:
        raise InputError("--model", f"unknown model {model!r}; choose {', '.join(_MODELS)}")
    vals = {}
    for name, v in (("--sample-rate", sample_rate), ("--t-start", t_start), ("--t-stop", t_stop)):
        if v is None:
            vals[name] = None
            continue
        try:
            vals[name] = float(v)
        except ValueError:
            raise InputError(name, f"must be a number, got {v!r}") from None
        if math.isnan(vals[name]):  # was read as a window of 'only 0 samples between nan s and inf s'
            raise InputError(name, f"must be a number, got {v}")
    from ..estimation.period_specs import MAX_SAMPLE_RATE

    sr = vals["--sample-rate"]
    if sr is not None and not 0 < sr <= MAX_SAMPLE_RATE:
        raise InputError("--sample-rate", f"must be in (0, {MAX_SAMPLE_RATE:g}] Hz, got {sr:g}")
    plot_p = check_output_path(plot, force, [signal], "--plot")
    from ..estimation.period_specs import fit_record

    t, y, fit, meta, _, _ = fit_record(signal, "SIGNAL", column=column, sample_rate=sr, model=model,
                                       t_start=vals["--t-start"], t_stop=vals["--t-stop"],
                                       trim="auto" if trim else None)
    from ..estimation.period_specs import implausible_period

    slip = implausible_period(fit.period, None, "SIGNAL")
    if slip:  # e.g. a time column in ms read as s, or a wrong --sample-rate
        slip += f" (the time scale came from {meta.get('time_source')}: check its unit)"
        meta["warnings"] = list(meta.get("warnings") or []) + [slip]
    if plot_p is not None:
        from pathlib import Path

        from ..figures import plot_fit

        plot_fit(plot_p, fit, t, y, title=Path(signal).name)
    sig = {k: meta.get(k) for k in ("path", "format", "decimal", "column", "columns", "time_source", "sample_rate",
                                    "sample_rate_source", "n_samples", "n_dropped", "duration", "time_base", "warnings")}
    sig["path"] = str(sig["path"]) if sig["path"] is not None else str(signal)
    if as_json:
        d = fit.to_dict()
        doc = {"period": fit.period, "std": fit.std, "damping_ratio": fit.damping_ratio}
        doc.update({k: v for k, v in d.items() if k not in doc})
        doc["signal"] = sig
        doc["warnings"] = list(sig.get("warnings") or [])  # the record's, as the --timed path's
        emit_json(doc)
        for w in meta.get("warnings", []) or []:
            click.echo(f"warning: {w}", err=True)
        return
    from rich.table import Table

    con = console()
    tb = Table(title=f"{esc(sig['path'])}: column {esc(sig['column'])}, {sig['n_samples']} samples at "
                     f"{fmt(sig['sample_rate'], 6)} Hz ({sig['time_source']})")
    tb.add_column("quantity")
    tb.add_column("value", justify="right")
    tb.add_row("period (s)", f"{fit.period:.9g} +- {fit.std:.2g}")
    u = fit.uncertainty
    if u:
        quant = f", quantisation +{u['quantisation']:.2g}" if u.get("quantisation") else ""
        if u.get("noise_replaced_by_quantisation"):
            quant = f"; in their place quantisation {u['quantisation']:.2g} (re-quantised copies)"
        tbase = f", time base +{u['time_base']:.2g}" if u.get("time_base") else ""
        tb.add_row("  std terms (s)", f"noise {u['noise']:.2g}, serial corr. +{u['serial_correlation']:.2g}{quant}, "
                                      f"non-stationarity {u['nonstationarity']:.2g}{tbase}")
        tb.add_row("  dominant term", u["dominant"].replace("_", " "))
    tb.add_row("frequency (Hz)", fmt(fit.frequency, 9))
    if fit.period_undamped is not None:
        tb.add_row("undamped period (s)", fmt(fit.period_undamped, 9))
    tb.add_row("damping ratio", fmt(fit.damping_ratio, 4))
    tb.add_row("model", fit.model + (f" (chosen by {fit.chosen_by})" if fit.chosen_by else ""))
    if fit.choice_reason:
        tb.add_row("  why", fit.choice_reason)
    cands = fit.selection.get("candidates") or {}
    for name in (fit.selection.get("ranking") or [])[1:]:
        c = cands[name]
        tb.add_row(f"  runner-up {name}", f"{c['period']:.9g} +- {c['std']:.2g} s, "
                                          f"{fit.chosen_by} +{c['delta']:.1f}")
    for name, c in cands.items():
        if not c["admissible"]:
            tb.add_row(f"  rejected {name}", str(c["rejected_because"]))
    if fit.modes and len(fit.modes) > 1:
        tb.add_row("second mode (s)", f"{fit.modes[1]['period']:.6g}")
    if len(fit.modes) > 2:
        m3 = fit.modes[2]
        tb.add_row("third mode (s)", f"{m3['period']:.6g} (amplitude {m3['amplitude']:.3g})")
    tb.add_row("amplitude (signal units)", f"{fmt(fit.amplitude, 5)} at t0, {fmt(fit.amplitude_rms, 5)} RMS over the fit, "
                                           f"{fmt(fit.amplitude_period, 5)} the period's")
    tb.add_row("r^2", fmt(fit.r_squared, 7))
    rc = fit.residual_check
    if rc:
        # harmonic 1: within 1.5/T_record of a fitted mode, unresolved from it (not "1f": see the notes)
        peaks = ", ".join(f"{p['frequency']:.4g} Hz" + ((" (beside a fitted mode)" if p["harmonic"] == 1 else
                                                          f" ({p['harmonic']}f)") if p["harmonic"] else "")
                          for p in rc.get("peaks", [])) or "none"
        tb.add_row("residuals", f"{'white' if rc.get('white') else 'not white'} (Ljung-Box p = {rc['p']:.2g}); "
                                f"peaks left: {peaks}")
    tb.add_row("fit window (s)", f"{fit.t0:.4g} .. {fit.t1:.4g}")
    if fit.half_periods:
        (T1, s1), (T2, s2) = fit.half_periods
        tb.add_row("halves (s)", f"{T1:.7g} +- {s1:.2g} / {T2:.7g} +- {s2:.2g}")
    if fit.crossing is not None:
        tb.add_row("cross-check: crossings (s)", f"{fit.crossing.period:.9g} +- {fit.crossing.std:.2g}")
    con.print(tb)
    for n in fit.notes:
        con.print(f"[dim]note: {esc(n)}[/dim]")
    for w in meta.get("warnings", []) or []:
        con.print(f"[bold red]WARNING:[/bold red] {esc(w)}")


def _timed(spec, target, uncertainty, as_json):
    from ..estimation import period_specs as ps

    label, n, times = ps.parse_timed_spec(spec)
    unc = ps.parse_uncertainty_overrides(uncertainty)
    T, s, det = ps.period_from_trials(n, times, None, unc)
    if "trial_time" in unc:  # a stated floor, checked as a stated period std is
        ps.check_assumed_sigma(T, s, f"--timed {label}", "--uncertainty")
    warnings = [w for w in (ps.implausible_period(T, label, "--timed", cycles=n),) if w]
    plan = None
    if target is not None:
        goal = ps.parse_target(target, T)
        plan = {"target_std": goal, "trial_std": det["trial_std"],
                "options": ps.trials_for_target(T, det["trial_std"], goal)}
    if as_json:
        doc = {"period": T, "std": s, "damping_ratio": None, "label": label, "timed": det}
        if plan is not None:
            doc["target"] = plan
        doc["warnings"] = warnings
        emit_json(doc)
        for w in warnings:
            click.echo(f"warning: {w}", err=True)
        return
    from rich.table import Table

    con = console()
    tb = Table(title=f"{esc(label)}: {len(times)} trial(s) of {n:g} cycles")
    tb.add_column("quantity")
    tb.add_column("value", justify="right")
    tb.add_row("period (s)", f"{T:.7g} +- {s:.2g}")
    tb.add_row("95 % interval (s)", f"{det['interval95'][0]:.7g} .. {det['interval95'][1]:.7g} "
                                    f"(k = {det['coverage_factor']:.3g}"
                                    + (f", Student t, {det['dof']} dof)" if det["dof"] else ", normal)"))
    tb.add_row("std of one trial (s)", f"{det['trial_std']:.3g} ({det['trial_std_source']})")
    tb.add_row("reaction-time floor trial_time (s)", f"{det['floor']:.3g}")
    con.print(tb)
    if plan is not None:
        tp = Table(title=f"to reach a period std of {plan['target_std']:.2g} s "
                         f"({plan['target_std'] / T:.2%}) with {plan['trial_std']:.3g} s per trial")
        for c in ("trials", "cycles per trial", "s per trial", "period std (s)"):
            tp.add_column(c, justify="right")
        for o in plan["options"]:
            tp.add_row(str(o["trials"]), str(o["cycles"]), f"{o['seconds_per_trial']:.4g}", f"{o['std']:.2g}")
        con.print(tp)
        con.print("[dim]note: assumes the oscillation lasts that many cycles with a visible amplitude[/dim]")
    for w in warnings:
        con.print(f"[bold red]WARNING:[/bold red] {esc(w)}")
