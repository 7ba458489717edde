"""`bifilar sweep`: compare suspension configurations and recommend one."""

from __future__ import annotations

import click

from .common import (MAX_SWEEP_PERIODS, check_journal_path, check_output_path, check_workers, console, emit_json, esc,
                     handle_errors, progress_bar)

UNC_HELP = "Measurement uncertainty KEY=VALUE (repeatable): timing [s], length, position, com [m], mass, gravity [relative]."


def common_options(fn):
    """Options shared by `sweep` and `plan` (evaluation settings and constraints)."""
    opts = [
        click.option("--component", "components", multiple=True,
                     help="Inertia component to estimate (repeatable; default Ixx, Iyy, Izz)."),
        click.option("--target", default=None,
                     help="Component to rank by (default: the worst relative uncertainty of the components)."),
        click.option("--amplitude", type=float, default=None,
                     help="Excitation amplitude, times each mode's normalised shape (default plan.amplitude or 0.05)."),
        click.option("--sigma", "sigmas", multiple=True, metavar="KEY=VALUE", help=UNC_HELP),
        click.option("--max-tension", type=float, default=None, help="Largest allowed wire tension during the excitation [N]."),
        click.option("--max-depth", type=float, default=None, help="Largest allowed depth of the body below the ceiling, swing included [m]."),
        click.option("--lengths-available", default=None, metavar="L1,L2,...", help="Wire lengths one can use [m]."),
        click.option("--min-separation", type=float, default=None,
                     help="Smallest allowed relative gap between a chosen mode's period and any other (e.g. 0.05)."),
        click.option("--no-tensions", is_flag=True, help="Skip the nonlinear runs (no tensions, swing depth or amplitude bias)."),
        click.option("--periods", "sim_periods", type=float, default=3.0, show_default=True,
                     help="Periods simulated per mode for the tensions."),
        click.option("--json", "as_json", is_flag=True, help="Print one JSON document."),
    ]
    for o in reversed(opts):
        fn = o(fn)
    return fn


def parse_sigmas(sigmas) -> dict:
    from ..errors import InputError

    out = {}
    for s in sigmas:
        if "=" not in s:
            raise InputError("--sigma", f"{s!r} must be KEY=VALUE, e.g. timing=0.002")
        k, v = (x.strip() for x in s.split("=", 1))
        try:
            out[k] = float(v)
        except ValueError:
            raise InputError("--sigma", f"{s!r}: {v!r} is not a number") from None
    return out


def resolve_all(cfg, components, target, amplitude, sigmas, max_tension, max_depth, lengths_available,
                min_separation, no_tensions, sim_periods):
    """(settings, constraints, target) from the config and the flags; exit 2 on bad input."""
    from ..errors import InputError
    from ..studies.shorthands import parse_values
    from ..studies.sweep import resolve_constraints, resolve_settings, resolve_target

    if sim_periods is not None and sim_periods > MAX_SWEEP_PERIODS:
        raise InputError("--periods", f"must be at most {MAX_SWEEP_PERIODS} periods per mode, got {sim_periods:g}")
    la = None
    if lengths_available is not None:
        la = [float(v) for v in parse_values(lengths_available, "--lengths-available")]
    cons = resolve_constraints(cfg, max_tension, max_depth, la, min_separation)
    settings = resolve_settings(cfg, components=list(components) or None, amplitude=amplitude,
                                sigma=parse_sigmas(sigmas), tensions=not no_tensions, periods=sim_periods)
    if no_tensions and cons.needs_nonlinear:
        which = "--max-tension" if cons.max_tension is not None else "--max-depth"
        raise InputError("--no-tensions", f"{which} needs the nonlinear run; drop one of them")
    return settings, cons, resolve_target(cfg, target, settings.components)


@click.command("sweep")
@click.argument("config", type=click.Path(dir_okay=False))
@click.option("--param", "params", multiple=True, required=True, metavar="NAME=VALUES",
              help="Parameter to vary (repeatable): a dotted config path (rig.attachments.0.0) or a shorthand "
                   "(spacing, ceiling_spacing, length, length_offset, height, amplitude, rotate_x/_y/_z[_deg]); "
                   "VALUES as START:STOP:NUM, log:START:STOP:NUM, [a, b, c] or a,b,c.")
@click.option("--zip", "zip_", is_flag=True, help="Vary the parameters together instead of over a grid.")
@common_options
@click.option("--out", type=click.Path(dir_okay=False), help="Write one CSV row per point (and a resumable journal FILE.partial.jsonl while running).")
@click.option("--resume", is_flag=True, help="Reuse the finished points of an interrupted sweep with the same --out.")
@click.option("--plot", type=click.Path(dir_okay=False), help="Draw the figures to this image file (PNG, PDF, SVG).")
@click.option("--workers", type=int, default=1, show_default=True, help="Processes to use (1..1024; at most one per CPU and per point starts).")
@click.option("--force", is_flag=True, help="Replace existing --out/--plot files (and a stale journal).")
@click.option("--stop-after", type=int, default=None, hidden=True, help="Stop after N new points (tests: a stand-in for Ctrl-C).")
@handle_errors
def sweep(config, params, zip_, components, target, amplitude, sigmas, max_tension, max_depth, lengths_available,
          min_separation, no_tensions, sim_periods, as_json, out, resume, plot, workers, force, stop_after):
    """Compare suspension configurations of CONFIG: predicted inertia
    uncertainty, estimator bias, mode separation, tensions and clearance per
    point; rank the feasible points and recommend one."""
    import time

    from ..config import read_yaml, scene_from_dict
    from ..errors import InputError
    from ..studies import sweep as sw
    from ..studies.shorthands import check_param, parse_param

    check_workers(workers)
    if resume and not out:
        raise InputError("--resume", "needs --out FILE (the journal is FILE.partial.jsonl)")
    cfg = read_yaml(config)
    if not isinstance(cfg, dict):
        raise InputError("config", "must be a YAML mapping with keys body and rig")
    scene_from_dict(cfg, config)  # the base config must be valid itself (ConfigErrors: exit 2, every problem)
    specs = [parse_param(p) for p in params]
    for s in specs:
        check_param(cfg, s.name)
    grid = sw.build_grid(specs, zip_)
    settings, cons, target = resolve_all(cfg, components, target, amplitude, sigmas, max_tension, max_depth,
                                         lengths_available, min_separation, no_tensions, sim_periods)
    journal = None
    if out:
        journal = check_journal_path(sw.journal_path(out), [config, plot], "--out", resume=resume)
        if journal.exists() and not resume and not force:
            raise InputError("--out", f"{journal} holds an interrupted sweep; pass --resume to continue it or --force to start over")
    out_p = check_output_path(out, force, [config, journal], "--out")
    plot_p = check_output_path(plot, force, [config, out, journal], "--plot")
    t0 = time.perf_counter()
    try:
        with progress_bar(f"sweeping {len(grid)} points", enabled=len(grid) > 1) as upd:
            points = sw.run_sweep(cfg, config, grid, settings, workers=workers, journal=journal, resume=resume,
                                  progress=upd, stop_after=stop_after)
    except sw.SweepInterrupted as exc:
        if journal is not None:
            click.echo(f"interrupted after {exc.done} of {exc.total} points; the finished points are kept in "
                       f"{journal}: rerun the same command with --resume to continue", err=True)
        raise
    runtime = time.perf_counter() - t0
    rec = sw.assess(points, cons, target)
    names = [s.name for s in specs]
    if out_p:
        sw.write_points_csv(out_p, points, names, list(settings.components))
        journal.unlink(missing_ok=True)
    if plot_p:
        from pathlib import Path

        sw.plot_sweep(plot_p, points, specs, zip_, list(settings.components), cons, rec,
                      title=f"{cfg.get('name', Path(config).stem)}: sweep of {', '.join(names)}")
    if as_json:
        emit_json({"points": points, "recommendation": rec, "settings": settings.describe(),
                   "parameters": names, "zip": zip_, "runtime_s": runtime})
        return
    render(cfg, config, points, names, settings, cons, rec, runtime)


_ABBR = {"torsion": "tor", "swing-x": "sx", "swing-y": "sy", "bounce": "bn", "roll": "rl", "pitch": "pt"}


def _pct(x, digits=3):
    return "-" if x is None else ("inf" if x == float("inf") else f"{100 * x:.{digits}g}")


def render(cfg, config, points, names, settings, cons, rec, runtime) -> None:
    """Rich tables: the points, the recommendation and the trade-off front."""
    from pathlib import Path

    from rich.table import Table

    con = console()
    comps = list(settings.components)
    t = Table(title=f"{esc(cfg.get('name', Path(config).stem))}: {len(points)} points ({runtime:.1f} s)")
    t.add_column("#", justify="right")
    for n in names:
        t.add_column(esc(n), justify="right")
    for c in comps:
        t.add_column(f"{c} +-%", justify="right")
    t.add_column("sep %", justify="right")
    t.add_column("peak T N" if settings.tensions else "rest T N", justify="right")
    t.add_column("depth m", justify="right")
    t.add_column("rank", justify="right")
    notes = []
    for i, p in enumerate(points):
        row = [str(i)] + [f"{p['params'][n]:.6g}" for n in names]
        if not p["valid"]:
            row += ["-"] * (len(comps) + 3) + ["[red]invalid[/red]"]
            notes.append(f"{i}: [red]invalid:[/red] {esc(p['error'])}")
            t.add_row(*row)
            continue
        seps = []
        for c in comps:
            e = p["components"][c]
            if not e["identifiable"]:
                row.append("[yellow]n/a[/yellow]")
            else:
                row.append(f"{_pct(e['rel_sigma'])} {_ABBR.get(e['mode'], e['mode'])}")
                seps.append(e["separation"])
        row.append(_pct(min(seps)) if seps else "-")
        pk = p["tension"]["peak"] if settings.tensions else max(p["tension"]["rest"])
        row.append("-" if pk is None else f"{pk:.4g}")
        d = p["depth"]["max"] if p["depth"]["max"] is not None else p["depth"]["rest"]
        row.append(f"{d:.4g}")
        row.append(str(p["rank"]) if p["rank"] is not None else "[yellow]x[/yellow]" if p["violations"] else "-")
        if p["violations"]:
            notes.append(f"{i}: " + esc("; ".join(p["violations"])))
        t.add_row(*row)
    con.print(t)
    for line in notes[:20]:
        con.print(f"  [yellow]x[/yellow] {line}")
    if len(notes) > 20:
        con.print(f"  ... {len(notes) - 20} more (see --json or --out)")
    con.print("(n/a: no mode's period depends on that component; modes: " + ", ".join(
        f"{v} = {k}" for k, v in _ABBR.items()) + ")")
    unc = settings.unc
    con.print("measurement uncertainties: " + ", ".join(
        f"{k} {v:g}{' s' if k == 'timing' else ' m' if k in ('length', 'position', 'com') else ' (relative)'}"
        for k, v in unc.items()) + f"; amplitude {settings.amplitude:g}")
    if rec.get("best") is None:
        con.print(f"[bold red]no recommendation:[/bold red] {esc(rec['reason'])}")
    else:
        b = points[rec["best"]]
        con.print(f"[bold green]recommended:[/bold green] point {rec['best']}: "
                  + esc(", ".join(f"{k} = {v:.6g}" for k, v in b["params"].items())))
        for line in rec["why"]:
            con.print(f"  - {esc(line)}")
        acc = Table(title="expected accuracy at the recommended point",
                    caption=f"bias: estimator vs the full model at amplitude {b['amplitude']:g}")
        for h in ("comp", "value", "sigma", "rel %", "mode", "T s", "sm-angle %", "thesis %", "linear %"):
            acc.add_column(h, justify="right")
        for c in comps:
            e = b["components"][c]
            if not e["identifiable"]:
                acc.add_row(c, f"{e['value']:.5g}", "-", "n/a", "-", "-", "-", "-", "-")
                continue
            bias = e["bias"]
            thesis = _pct(bias.get("thesis")) if bias.get("thesis") is not None else (
                "pending" if "pending" in e["bias_notes"].get("thesis", "") else "-")
            acc.add_row(c, f"{e['value']:.5g}", f"{e['sigma']:.3g}", _pct(e["rel_sigma"]), _ABBR.get(e["mode"], e["mode"]),
                        f"{e['period']:.5g}", _pct(bias.get("small_angle")), thesis, _pct(bias.get("linear")))
        con.print(acc)
    front = rec.get("pareto_front") or []
    if len(front) > 1:
        ft = Table(title="trade-off: predicted uncertainty vs peak tension (Pareto front)")
        ft.add_column("#", justify="right")
        for n in names:
            ft.add_column(esc(n), justify="right")
        ft.add_column("uncertainty %", justify="right")
        ft.add_column("peak T N", justify="right")
        ft.add_column("feasible")
        for i in front:
            p = points[i]
            ft.add_row(str(i), *[f"{p['params'][n]:.6g}" for n in names], _pct(p["objective"]),
                       f"{p['tension']['peak']:.4g}", "yes" if p["feasible"] else "no")
        con.print(ft)
