"""`bifilar simulate`: nonlinear run from a displaced rest, with health."""

from __future__ import annotations

import math

import click

from .common import (check_output_path, config_rest_pose, console, emit_json, esc, fmt, handle_errors, progress_bar,
                     warn_at_rest)


@click.command("simulate")
@click.argument("config", type=click.Path())
@click.option("--mode", "mode", default=None, help="Mode label or 1-based index (default: torsion, else the slowest).")
@click.option("--amplitude", type=float, default=0.05, show_default=True,
              help="Initial displacement: this times the mode's normalised shape (rad or m).")
@click.option("--periods", type=float, default=10.0, show_default=True, help="Number of linear periods to integrate.")
@click.option("--model", type=click.Choice(["maximal", "kane"]), default="maximal", show_default=True,
              help="maximal: general model (any rig); kane: the thesis's five-angle model (two wires).")
@click.option("--theta", default=None, help="kane model: initial theta1..theta4 [rad], comma separated.")
@click.option("--method", default="auto", show_default=True,
              help="auto: LSODA (scipy odeint) on the compiled model, the cheapest for the printed digits "
                   "(docs/performance.md); or a solve_ivp method (DOP853, RK45, Radau, LSODA).")
@click.option("--rtol", type=float, default=1e-10, show_default=True, help="Relative tolerance of the integrator.")
@click.option("--on-slack", type=click.Choice(["continue", "stop"]), default="continue", show_default=True,
              help="What to do when a wire goes slack during the motion.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document (interface.md).")
@click.option("--out", type=click.Path(), help="Write the time series to this CSV file.")
@click.option("--plot", type=click.Path(), help="Draw the time series to this image file (PNG, PDF, SVG).")
@click.option("--force", is_flag=True, help="Replace existing --out/--plot files.")
@handle_errors
def simulate(config, mode, amplitude, periods, model, theta, method, rtol, on_slack, as_json, out, plot, force):
    """Integrate the full nonlinear motion of CONFIG from a displaced rest pose."""
    from .common import MAX_SIM_PERIODS, OptionChecker

    chk = OptionChecker()  # every option problem at once
    chk.finite("--amplitude", amplitude)
    if chk.positive("--periods", periods):
        chk.in_range("--periods", periods, 0, MAX_SIM_PERIODS, lo_open=True)
    from ..analysis.simulate import MIN_RTOL

    chk.in_range("--rtol", rtol, MIN_RTOL, 1e-2, hi_open=True)  # below 100 eps the integrators refuse or loosen it
    if method not in ("auto", "DOP853", "RK45", "RK23", "Radau", "BDF", "LSODA"):
        chk.error("--method", f"unknown method {method!r}; use auto, DOP853, RK45, RK23, Radau, BDF or LSODA")
    if theta is not None and model != "kane":
        chk.error("--theta", "only with --model kane")
    chk.done()
    out_p = check_output_path(out, force, [config], "--out")
    plot_p = check_output_path(plot, force, [config, out], "--plot")
    from ..analysis.modes import linear_modes
    from ..analysis.simulate import simulate as run
    from ..config import read_yaml, scene_from_dict
    from ..studies.settings import stated_timing

    cfg = read_yaml(config)
    scene = scene_from_dict(cfg, source=str(config))
    timing = stated_timing(cfg)  # the period's numerical error is held against a tenth of it
    rest = config_rest_pose(scene, config)
    ms = linear_modes(scene, rest)
    at_rest = warn_at_rest(scene, rest, ms.modes, only=ms.pick(mode).label)
    if model == "kane":
        from ..analysis.kane_run import simulate_kane

        from ..errors import InputError

        with progress_bar("simulating (kane)", enabled=not as_json) as upd:
            try:
                res = simulate_kane(scene, rest, ms, mode=mode, amplitude=amplitude, periods=periods, theta=theta,
                                    rtol=rtol, method="DOP853" if method == "auto" else method,
                                    progress=upd, timing=timing)
            except InputError as exc:
                if exc.field != "theta1to4":  # the model's name for the angles --theta gives
                    raise
                raise InputError("--theta", exc.message) from None
    else:
        mode = ms.pick(mode).label
        with progress_bar("simulating", enabled=True) as upd:
            # the timed coordinate at every sample only for --plot (--out writes the poses from y)
            res = run(scene, mode, amplitude, periods, rest=rest, modes=ms, method=method, rtol=rtol,
                      on_slack=on_slack, progress=upd, timing=timing, coordinate=plot_p is not None)
    if out_p:
        from ..report import write_timeseries_csv

        write_timeseries_csv(out_p, scene, rest, res)
    if plot_p:
        from ..figures import plot_simulation

        plot_simulation(plot_p, res, scene.name)
    if as_json:
        doc = res.to_json()
        doc["warnings"] = at_rest + doc["warnings"]  # the rest pose's, printed above, then the run's
        emit_json(doc)
        for w in res.warnings:
            click.echo(f"warning: {w}", err=True)
        return
    _render(scene, res)


def _render(scene, res) -> None:
    from rich.table import Table

    con = console()
    t = Table(title=f"{esc(scene.name)}: {res.model} model, mode {res.mode}, amplitude {res.amplitude:g}")
    t.add_column("quantity")
    t.add_column("value", justify="right")
    t.add_row("measured period (s)", _period_text(res.period, res.period_error))
    t.add_row("linear period (s)", fmt(res.linear_period, 10))
    if res.period and res.linear_period:
        t.add_row("period shift vs linear", f"{(res.period / res.linear_period - 1):+.3e}")
    t.add_row("cycles timed", str(max(len(res.crossings) - 1, 0)) + f" (coordinate {res.coordinate_name})")
    t.add_row("max constraint violation (m)", f"{res.max_constraint_violation:.2e}")
    t.add_row("energy drift (rel. to oscillation)", _drift_text(res))
    for i in range(scene.n_wires):
        t.add_row(f"tension wire {i + 1} min / max (N)", f"{res.tension_min[i]:.6g} / {res.tension_max[i]:.6g}")
    t.add_row("lowest point z (m)", f"{res.lowest_z_min:.6g}")
    t.add_row("depth below ceiling (m)", f"{res.depth_max:.6g}")
    if res.clearance is not None:  # the rest pose's checks over the run's samples
        t.add_row("highest point z (m)", f"{res.clearance['highest_point_z']:.6g}")
        if res.clearance["min_wire_distance"] is not None:
            i, j = res.clearance["min_wire_distance_wires"]
            t.add_row(f"closest wires {i} and {j} (m)", f"{res.clearance['min_wire_distance']:.4g}")
    t.add_row("integrator", f"{res.method} rtol={res.rtol:g}, {res.nfev} evaluations, {res.runtime:.3g} s")
    con.print(t)
    for w in res.warnings:
        con.print(f"[bold red]WARNING:[/bold red] {esc(w)}")


def _drift_text(res) -> str:
    """The energy drift's table cell: the number, or why there is none to give."""
    if not math.isfinite(res.energy_drift):
        return "- (no oscillation energy)"
    if res.energy_drift_below_resolution:
        return f"below resolution {res.energy_drift_resolution:.1e}"
    return f"{res.energy_drift:.2e}"


def _period_text(period, error) -> str:
    """The measured period to the digits its numerical error leaves (the last
    one at the error's leading decade, at most 12), with that error."""
    if period is None:
        return fmt(None)
    if error is None or math.isnan(error):
        return f"{period:.10g} (numerical error not established)"
    if not (error is not None and math.isfinite(error) and error > 0):
        return fmt(period, 10)
    digits = min(max(math.floor(math.log10(abs(period))) - math.floor(math.log10(error)) + 1, 1), 12)
    return f"{period:.{digits}g} +- {error:.1g} (numerical)"
