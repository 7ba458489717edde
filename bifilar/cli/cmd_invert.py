"""`bifilar invert`: moments of inertia from measured periods, with the
ladder of estimators and the uncertainty budget (docs/invert.md)."""

from __future__ import annotations

import click

from .common import check_journal_path, check_output_path, console, emit_json, esc, fmt, handle_errors, progress_bar

@click.command("invert")
@click.argument("config", required=False, type=click.Path())
@click.option("--period", "periods", multiple=True, metavar="LABEL=SECONDS[+-SIGMA]",
              help="Measured period of a mode (label or 1-based index); repeatable.  Without +-SIGMA the "
                   "default timing uncertainty is used.")
@click.option("--timed", multiple=True, metavar="LABEL=CYCLES:T1,T2,...",
              help="Timed trials: CYCLES cycles took T1, T2, ... s (e.g. torsion=10:26.81,26.79,26.84); repeatable.")
@click.option("--signal", "signals", multiple=True, metavar="LABEL=PATH",
              help="A recording of the mode's oscillation (CSV or .mat, see `bifilar period`); repeatable. "
                   "Refused when its frequency matches a predicted mode only by alias (sampled below twice "
                   "the mode's frequency); warned below 2.5 samples per cycle.")
@click.option("--column", default=None, help="Signal column / MAT variable (default: first non-time numeric one).")
@click.option("--sample-rate", default=None, help="Signal sample rate, Hz (when the file has no time column).")
@click.option("--signal-model", default="auto", show_default=True,
              help="Signal fit model: viscous, quadratic, two_mode, three_mode or auto.")
@click.option("--signal-quantity", default="other", show_default=True,
              help="What the signal is: angle (the mode's coordinate), rate (its derivative) or other; "
                   "angle and rate give the amplitude from the fit.")
@click.option("--signal-scale", default=None, help="Multiplier taking the signal to rad (or m), e.g. 0.0174533 for degrees.")
@click.option("--amplitude", "amplitudes", multiple=True, metavar="[LABEL=]A[+-SIGMA]",
              help="Oscillation amplitude (A times the mode's normalised shape, as for `simulate`); "
                   "without LABEL it applies to every mode.")
@click.option("--cycles", default=None, help="Cycles the nonlinear method simulates for --period measurements (default 10).")
@click.option("--solve-for", "solve_for", multiple=True, metavar="COMPONENT",
              help="Ixx Iyy Izz Ixy Ixz Iyz (body axes) or com.x com.y com.z; repeatable.  Default: per mode, "
                   "the component its period is most sensitive to.")
@click.option("--method", default=None, help="auto (default), small-angle, thesis, linear or nonlinear.")
@click.option("--uncertainty", "uncertainty", multiple=True, metavar="KEY=VALUE",
              help="Override an assumed input uncertainty: length, position, com (m), mass, gravity, amplitude (relative), "
                   "timing, trial_time (s); release (m, default 0.01: the largest second mode a recording's release "
                   "started unseen); stiffness (relative, the wires' EA where rig.stiffness is stated, default "
                   "0.1); repeatable.")
@click.option("--monte-carlo", "monte_carlo", default=None, metavar="N",
              help="Check the linear uncertainty with N Monte Carlo re-estimates on the full model.")
@click.option("--seed", default=None, help="Random seed of the Monte Carlo draws.")
@click.option("--journal", type=click.Path(), default=None,
              help="Run the Monte Carlo in chunks appended to this file as they finish (survives Ctrl-C).")
@click.option("--resume", is_flag=True, help="Continue the Monte Carlo journal given by --journal.")
@click.option("--measurements", "measurements", type=click.Path(), default=None,
              help="Measurements YAML file (several modes, hangings, recordings; docs/invert.md).")
@click.option("--rig", default=None, metavar="shared|separate",
              help="Several hangings: shared (default) budgets wire lengths, anchors and attachments that are the "
                   "same in their configs as measured once (one error for all of them); separate as measured "
                   "again for each hanging.  Overrides the measurements file's rig key.")
@click.option("--no-ladder", is_flag=True, help="Only the chosen method (skip the comparison).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document (interface.md).")
@click.option("--plot", type=click.Path(), default=None,
              help="Period-vs-inertia curves with the measurement marked (PNG/PDF/SVG); signal fits go to "
                   "FILE's name + .fit-LABEL.")
@click.option("--force", is_flag=True, help="Replace existing --plot files.")
@handle_errors
def invert(config, periods, timed, signals, column, sample_rate, signal_model, signal_quantity, signal_scale,
           amplitudes, cycles, solve_for, method, uncertainty, monte_carlo, seed, journal, resume, measurements,
           rig, no_ladder, as_json, plot, force):
    """Estimate inertia components of CONFIG's body from measured periods."""
    from pathlib import Path

    from ..errors import InputError
    from ..estimation import measurements as mm
    from ..estimation import period_specs as ps
    from ..estimation import stated_inputs as sti

    if method is not None and method not in mm.METHOD_NAMES:
        raise InputError("--method", f"unknown method {method!r}; choose {', '.join(mm.METHOD_NAMES)}")
    from ..estimation.rig import RIG_MODELS

    if rig is not None and rig not in RIG_MODELS:
        raise InputError("--rig", f"must be one of {', '.join(RIG_MODELS)}, got {rig!r}")
    n_mc = _int(monte_carlo, "--monte-carlo", minimum=0)
    seed_v = _int(seed, "--seed", minimum=0)
    if resume and journal is None:
        raise InputError("--resume", "needs --journal FILE")
    if journal is not None and not n_mc:
        raise InputError("--journal", "only with --monte-carlo N")
    cyc = _float(cycles, "--cycles", positive=True)
    sr = _float(sample_rate, "--sample-rate", positive=True)
    if sr is not None and sr > ps.MAX_SAMPLE_RATE:
        raise InputError("--sample-rate", f"must be in (0, {ps.MAX_SAMPLE_RATE:g}] Hz, got {sr:g}")
    scale = _float(signal_scale, "--signal-scale", positive=True)
    if signal_quantity not in ("angle", "rate", "other"):
        raise InputError("--signal-quantity", f"must be angle, rate or other, got {signal_quantity!r}")
    unc = ps.parse_uncertainty_overrides(uncertainty)
    amps = ps.parse_amplitudes(amplitudes)
    bad = [s for s in solve_for if s not in mm.SOLVABLE]
    if bad:
        raise InputError("--solve-for", f"unknown component {bad[0]!r}; choose from {', '.join(mm.SOLVABLE)}")
    # parse the simple specs before any work
    p_specs = [ps.parse_period_spec(s) for s in periods]
    t_specs = [ps.parse_timed_spec(s) for s in timed]
    s_specs = [ps.split_label(s, "--signal", "torsion=recording.csv") for s in signals]
    # every output is distinct from the others and from every input, checked before any work
    inputs = [config, measurements, *(path for _, path in s_specs)]
    if journal is not None:
        check_journal_path(journal, [*inputs, plot], "--journal", resume=resume)
        if Path(journal).exists() and not resume:
            raise InputError("--journal", f"{journal} exists; pass --resume to continue it or choose another name")
    plot_p = check_output_path(plot, force, [*inputs, journal], "--plot")
    if config is None and measurements is None:
        raise InputError("CONFIG", "give a scene config (or --measurements FILE naming one)")
    ms = sti.measurement_set(config, measurements, solve_for, unc, rig, p_specs, t_specs, s_specs, amps, cyc,
                             dict(column=column, sample_rate=sr, model=signal_model, quantity=signal_quantity,
                                  scale=scale))
    # inputs named inside the measurements file (its config, recordings) are inputs too
    inputs += [h.source for h in ms.hangings if getattr(h, "source", None)]
    inputs += [str(m.details["signal"]["path"]) for m in ms.measurements
               if isinstance(m.details, dict) and isinstance(m.details.get("signal"), dict) and m.details["signal"].get("path")]
    if journal is not None:
        check_journal_path(journal, [*inputs, plot], "--journal", resume=resume)
    if plot_p is not None:
        check_output_path(plot, force, [*inputs, journal], "--plot")
    fit_paths = {}
    if plot_p is not None:
        for k, m in enumerate(ms.measurements):
            if m.fit is not None:
                q = plot_p.with_name(f"{plot_p.stem}.fit-{_safe(m.label)}-{k + 1}{plot_p.suffix or '.png'}")
                fit_paths[k] = check_output_path(str(q), force, [*inputs, journal, plot], "--plot")
    from ..estimation.invert import invert as run

    slow = bool(n_mc or ms.monte_carlo) or any(m.amplitude for m in ms.measurements)
    with progress_bar("inverting", enabled=slow) as upd:
        res = run(ms, method=method, solve_for=list(solve_for) or None, unc=unc, monte_carlo=n_mc, seed=seed_v,
                  ladder=not no_ladder, progress=upd, journal=journal, resume=resume)
    if plot_p is not None:
        from ..estimation.invert import inversion_curves
        from ..figures import plot_fit, plot_inversion

        plot_inversion(plot_p, inversion_curves(res))
        for k, q in fit_paths.items():
            m = ms.measurements[k]
            plot_fit(q, m.fit, m.signal[0], m.signal[1],
                     title=f"{m.label}: {Path(str(m.details['signal']['path'])).name}")
    if as_json:
        doc = res.to_json()
        doc["scene"] = {"name": ms.hangings[0].scene.name, "source": ms.source}
        if plot_p is not None:
            doc["plots"] = [str(plot_p)] + [str(q) for q in fit_paths.values()]
        emit_json(doc)
        for w in res.warnings:
            click.echo(f"warning: {w}", err=True)
        return
    _render(ms, res)


def _safe(label: str) -> str:
    import re

    return re.sub(r"[^A-Za-z0-9_.-]+", "_", label)


def _int(v, name, minimum=None):
    from ..errors import InputError

    if v is None:
        return None
    try:
        x = int(str(v))
    except ValueError:
        raise InputError(name, f"must be an integer, got {v!r}") from None
    if minimum is not None and x < minimum:
        raise InputError(name, f"must be >= {minimum}, got {x}")
    return x


def _float(v, name, positive=False):
    import math

    from ..errors import InputError

    if v is None:
        return None
    try:
        x = float(v)
    except ValueError:
        raise InputError(name, f"must be a number, got {v!r}") from None
    if not math.isfinite(x) or (positive and x <= 0):
        raise InputError(name, f"must be a {'positive ' if positive else ''}finite number, got {v!r}")
    return x


def _render(ms, res) -> None:
    import numpy as np
    from rich.table import Table

    con = console()
    names = esc(", ".join(h.scene.name for h in ms.hangings))
    con.print(f"[bold]{names}[/bold]: {len(res.measurements)} period(s), method [bold]{res.method}[/bold] "
              f"({res.to_json()['method_description']})")
    t = Table(title="Estimate (reference body axes)")
    for c in ("unknown", "estimate", "std", "rel. std", "95 % interval"):
        t.add_column(c, justify="left" if c == "unknown" else "right")
    mc = res.monte_carlo
    # timed trials: Student draws (1-2 dof: no variance), so the Monte Carlo's
    # interval is shown with its width relative to the budget's, not its std
    mc_interval = mc is not None and bool(res.budget.dof)
    if mc is not None:
        t.add_column("Monte Carlo 95 %" if mc_interval else "Monte Carlo std", justify="right")
    for i, n in enumerate(res.names):
        v, s = res.values[i], res.std[i]
        unit = "kg m^2" if n.startswith("I") else "m"
        if np.isfinite(s):
            lo, hi = res.interval[i] if res.interval is not None else (v - 1.96 * s, v + 1.96 * s)
            nu = float(res.budget.effective_dof[i])
            dof = f" (t, {nu:.3g} dof)" if np.isfinite(nu) else ""
            cut = res.interval_clipped[i] if res.interval_clipped else None
            dof += f" (cut at the {cut} limit)" if cut else ""  # a note says more
            row = [f"{n} ({unit})", fmt(float(v), 8), fmt(float(s), 3), f"{s / abs(v):.2%}" if v else "-",
                   f"{lo:.6g} .. {hi:.6g}{dof}"]
        else:  # res.std_unavailable says why (printed as a warning)
            row = [f"{n} ({unit})", fmt(float(v), 8), "cannot be given", "-", "-"]
        if mc is not None and mc.n_ok <= 1:
            row.append("-")
        elif mc_interval:
            w = res.interval[i, 1] - res.interval[i, 0]
            row.append(f"{mc.low[i]:.6g} .. {mc.high[i]:.6g} (x{(mc.high[i] - mc.low[i]) / w:.2f})")
        elif mc is not None:
            row.append(f"{mc.std[i]:.3g} (x{mc.ratio[i]:.2f})")
        t.add_row(*row)
    con.print(t)
    if res.ambiguous:
        rt = Table(title=f"AMBIGUOUS: {len(res.roots)} physical solutions reproduce the measurements "
                         "(the first is shown above)")
        rt.add_column("root", justify="right")
        for n in res.names:
            rt.add_column(f"{n}", justify="right")
            rt.add_column("std", justify="right")
        rt.add_column("max |resid|/std", justify="right")
        for q, r in enumerate(res.roots):
            ent = {**r["inertia"], **{f"com.{k}": v for k, v in r.get("com", {}).items()}}
            cells = []
            for n in res.names:
                cells += [fmt(ent[n]["value"], 8), fmt(ent[n]["std"], 3)]
            zmax = max(abs(x["normalised_residual"]) for x in r["residuals"])
            rt.add_row(str(q + 1), *cells, f"{zmax:.2g}")
        sep = res.separation
        if sep is None or sep["separation"] < 3:
            rt.caption = "no mode of the hangings used separates them: hang the body another way and time a mode"
        else:
            rt.caption = (f"to separate them, time mode '{sep['mode']}' (hanging '{sep['hanging']}'): "
                          + ", ".join(f"{p:.6g} s" for p in sep["periods"])
                          + f" at these roots ({sep['separation']:.3g} timing sigma apart)")
        con.print(rt)
    if len(res.ladder) > 1:
        lt = Table(title="Ladder of estimators (what the simpler methods cost)")
        multi = len(res.names) > 1
        cols = ("method",) + (("unknown",) if multi else ()) + ("estimate", "vs best", "in std", "note")
        for c in cols:
            lt.add_column(c, justify="right" if c in ("estimate", "vs best", "in std") else "left")
        for r in res.ladder:
            mark = " *" if r["method"] == res.method else ""
            if not r["applicable"]:
                lt.add_row(r["method"], *(("-",) if multi else ()), "-", "-", "-", f"n/a: {esc(r['note'])}")
                continue
            note = esc(r.get("note") or "")
            if r.get("thesis_table"):
                tt = r["thesis_table"]
                note += (f" (thesis Table 7.1.1: {tt['thesis_value']} vs analytic {tt['analytic']}, "
                         f"{tt['thesis_relative_error']:+.2%})")
            for j, n in enumerate(res.names):
                rel = r["relative_difference"][n]
                ins = r["difference_in_std"][n]
                lt.add_row(r["method"] + mark if j == 0 else "", *((n,) if multi else ()), fmt(r["values"][n], 8),
                           f"{rel:+.3%}" if rel is not None else "-", f"{ins:+.2f}" if ins is not None else "-",
                           note if j == 0 else "")
        con.print(lt)
    for i, n in enumerate(res.names):
        bt = Table(title=f"Uncertainty budget of {n} (linear propagation)")
        bt.add_column("source")
        bt.add_column("share of variance", justify="right")
        bt.add_column("std contribution", justify="right")
        for g, (sh, c) in res.budget.grouped(i).items():
            bt.add_row(esc(g), f"{sh:.1%}", fmt(c, 3))
        sh = res.budget.shares(i)
        top = res.budget.ranked(i, 3)
        bt.caption = "largest single inputs: " + esc(", ".join(f"{k} {sh[k]:.1%}" for k in top))
        con.print(bt)
    if len(res.names) > 1:
        ct = Table(title="Correlation of the estimates")
        ct.add_column("")
        for n in res.names:
            ct.add_column(n, justify="right")
        C = res.budget.correlation
        for i, n in enumerate(res.names):
            ct.add_row(n, *[f"{C[i, j]:+.3f}" for j in range(len(res.names))])
        con.print(ct)
    mt = Table(title="Measurements (periods: undamped, as the model must reproduce them)")
    several = len(ms.hangings) > 1
    for c in (("hanging",) if several else ()) + ("mode", "source", "period (s)", "std (s)", "amplitude",
                                                   "model (s)", "resid/std"):
        mt.add_column(c, justify="left" if c in ("hanging", "mode", "source") else "right")
    doc = res.to_json()
    for m, r in zip(res.measurements, doc["residuals"]):
        mt.add_row(*((esc(r["hanging"]),) if several else ()), esc(m.label),
                   esc(m.source) + (f" (zeta {m.damping_ratio:.3g})" if m.damping_ratio else ""),
                   fmt(m.period, 9), fmt(m.std, 3), fmt(m.amplitude, 4), fmt(r["model"], 9),
                   f"{r['normalised_residual']:+.2f}")
    con.print(mt)
    u = res.uncertainty
    con.print("assumed standard uncertainties: " + "; ".join(f"{k} {v['value']:g} {v['unit'].split(' ')[0]}"
                                                          for k, v in u.items()))
    for n in res.notes:
        con.print(f"[dim]note: {esc(n)}[/dim]")
    for w in res.warnings:
        con.print(f"[bold red]WARNING:[/bold red] {esc(w)}")
