"""`bifilar period`: the period of a recorded oscillation (a thin CLI on
:mod:`bifilar.estimation.signal`)."""

from __future__ import annotations

import click

from .common import check_output_path, console, emit_json, esc, fmt, handle_errors

_MODELS = ("auto", "viscous", "quadratic", "two_mode")


@click.command("period")
@click.argument("signal", type=click.Path(dir_okay=False))
@click.option("--column", default=None, help="Signal column (CSV) or variable (.mat); default: the first non-time one.")
@click.option("--sample-rate", default=None, help="Sample rate, Hz (ignores a time column).")
@click.option("--model", default="auto", show_default=True,
              help="Fit model: viscous, quadratic (drag ~ v^2), two_mode (beating) or auto (BIC picks).")
@click.option("--t-start", default=None, help="Start of the fit window, s.")
@click.option("--t-stop", default=None, help="End of the fit window, s.")
@click.option("--trim", is_flag=True, help="Drop the settled tail where the envelope is lost in the noise.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document (interface.md).")
@click.option("--plot", type=click.Path(dir_okay=False), default=None,
              help="Draw the signal, the fit and the residuals to this image file.")
@click.option("--force", is_flag=True, help="Replace an existing --plot file.")
@handle_errors
def period(signal, column, sample_rate, model, t_start, t_stop, trim, as_json, plot, force):
    """Fit the period (s), its standard uncertainty and the damping ratio of a
    recorded oscillation SIGNAL (CSV with a t/time column in s, or .mat)."""
    from ..errors import InputError

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
    from ..estimation.measurements import MAX_SAMPLE_RATE, check_signal_scale

    sr = vals["--sample-rate"]
    if sr is not None and not 0 < sr <= MAX_SAMPLE_RATE:
        raise InputError("--sample-rate", f"must be in (0, {MAX_SAMPLE_RATE:g}] Hz, got {sr:g}")
    plot_p = check_output_path(plot, force, [signal], "--plot")
    from ..estimation.signal import fit_period, plot_fit, read_signal

    t, y, meta = read_signal(signal, column=column, sample_rate=sr)
    check_signal_scale(t, y, "SIGNAL")
    fit = fit_period(t, y, model=model, t_start=vals["--t-start"], t_stop=vals["--t-stop"],
                     trim="auto" if trim else None)
    if plot_p is not None:
        from pathlib import Path

        from .common import atomic_write

        atomic_write(plot_p, lambda tmp: plot_fit(fit, t, y, tmp, title=Path(signal).name))
    sig = {k: meta.get(k) for k in ("path", "format", "column", "columns", "time_source", "sample_rate",
                                    "sample_rate_source", "n_samples", "n_dropped", "duration", "warnings")}
    sig["path"] = str(sig["path"]) if sig["path"] is not None else str(signal)
    if as_json:
        d = fit.to_dict()
        doc = {"period": fit.period, "std": fit.std, "damping_ratio": fit.damping_ratio}
        doc.update({k: v for k, v in d.items() if k not in doc})
        doc["signal"] = sig
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
    tb.add_row("frequency (Hz)", fmt(fit.frequency, 9))
    if fit.period_undamped is not None:
        tb.add_row("undamped period (s)", fmt(fit.period_undamped, 9))
    tb.add_row("damping ratio", fmt(fit.damping_ratio, 4))
    tb.add_row("model", fit.model + (f" (chosen by {fit.chosen_by})" if fit.chosen_by else ""))
    tb.add_row("amplitude (signal units)", fmt(fit.amplitude, 5))
    tb.add_row("r^2", fmt(fit.r_squared, 7))
    tb.add_row("fit window (s)", f"{fit.t0:.4g} .. {fit.t1:.4g}")
    if fit.std_inflation > 1:
        tb.add_row("std inflation (autocorrelated residuals)", f"x{fit.std_inflation:.2f}")
    if fit.crossing is not None:
        tb.add_row("cross-check: crossings (s)", f"{fit.crossing.period:.9g} +- {fit.crossing.std:.2g}")
    con.print(tb)
    for n in fit.notes:
        con.print(f"[dim]note: {esc(n)}[/dim]")
    for w in meta.get("warnings", []) or []:
        con.print(f"[bold red]WARNING:[/bold red] {esc(w)}")
