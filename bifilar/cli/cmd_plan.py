"""`bifilar plan`: the configuration with the smallest predicted inertia
uncertainty that meets the constraints."""

from __future__ import annotations

import click

from .cmd_sweep import (_ABBR, SHORTHAND_HELP, _pct, common_options, recommendation_warnings, render_amplitude,
                        render_identifiability, render_multi_hanging, render_rig, render_timing)
from .common import check_output_path, check_workers, console, emit_json, esc, fmt, handle_errors, progress_bar


@click.command("plan")
@click.argument("config", type=click.Path())
@click.option("--param", "params", multiple=True, required=True, metavar="NAME=LO:HI",
              help="Parameter to search within bounds (repeatable). " + SHORTHAND_HELP)
@click.option("--zip", "zip_", is_flag=True,
              help="Move the parameters together, each the same fraction of its range (e.g. spacing and "
                   "ceiling_spacing over one range keep the wires parallel).")
@common_options
@click.option("--workers", type=int, default=1, show_default=True, help="Processes for the coarse grid (1..1024; at most one per CPU and per point starts).")
@click.option("--force", is_flag=True, help="Replace existing --write-config / --write-measurements files.")
@handle_errors
def plan(config, params, zip_, components, target, amplitude, sigmas, max_tension, max_depth, lengths_available,
         min_separation, no_tensions, sim_periods, write_config, reaction, sensor, as_json, workers, hangings,
         rig, write_measurements, force):
    """Search the parameters of CONFIG for the configuration that minimises
    the predicted uncertainty of the target inertia subject to the
    constraints; report the expected accuracy of each component.  Exit 2,
    naming the binding constraint, when nothing is feasible."""
    from ..config import read_yaml, scene_from_dict
    from ..errors import InputError
    from ..studies.plan import plan as run_plan
    from ..studies.shorthands import check_param, overlap_warnings, parse_bounds
    from ..studies.point_advice import write_point_config
    from ..studies.recommend import add_point_remedies, point_advice, unmeasured
    from ..studies.study_inputs import resolve_study

    check_workers(workers)
    cfg = read_yaml(config)
    if not isinstance(cfg, dict):
        raise InputError("config", "must be a YAML mapping with keys body and rig")
    scene_from_dict(cfg, config)  # the base config must be valid itself (ConfigErrors: exit 2, every problem)
    bounds = [parse_bounds(p) for p in params]
    for n, lo, hi in bounds:
        check_param(cfg, n, (lo, hi))
    pre = overlap_warnings([b[0] for b in bounds])
    for w in pre:
        click.echo(f"warning: {w}", err=True)
    from ..studies.timing import check_reaction, parse_sensor

    reaction, sensor = check_reaction(reaction), parse_sensor(sensor)
    if zip_ and len(bounds) < 2:
        raise InputError("--zip", "needs two parameters or more to move together")
    settings, cons, target = resolve_study(cfg, components, target, amplitude, sigmas, max_tension, max_depth,
                                           lengths_available, min_separation, no_tensions, sim_periods,
                                           [b[0] for b in bounds], config, rig)
    wc_p = check_output_path(write_config, force, [config], "--write-config")
    wm_p = check_output_path(write_measurements, force, [config, write_config], "--write-measurements")
    with progress_bar("planning", enabled=True) as upd:
        res = run_plan(cfg, config, bounds, settings, cons, target, workers=workers, progress=upd, zip_=zip_,
                       hangings=hangings)
    doc = res.to_json()
    deferred = res.separation_guard == "multi_hanging"  # --min-separation left to the hangings plan
    need = unmeasured(doc)  # not identifiable, or set aside: their remedies and the multi-hanging plan
    # the hangings first: a plan that cannot meet --min-separation exits 2 before any warning or file
    doc["warnings"] = pre + recommendation_warnings(doc, cfg, config, res.best, settings, cons, reaction, sensor,
                                                    hangings or bool(need), wm_p, "bifilar plan", "the planned point",
                                                    deferred, hangings)
    from ..studies.sweep import stretching_summary

    if (w := stretching_summary(res.evaluated)) is not None:  # rigid-wire runs on modes the wires cannot follow
        click.echo(f"warning: {w}", err=True)
        doc["warnings"].append(w)
    doc["settings"] = settings.describe()
    doc.update(point_advice(res.best, cfg, config, settings, reaction, sensor,
                            cons.min_separation if deferred else None, res.among))
    add_point_remedies(doc, need, res.best, cfg, config, settings)
    if wc_p:
        write_point_config(wc_p, cfg, config, res.best, "configuration planned by bifilar plan")
        doc["config_written"] = str(wc_p)
    if as_json:
        emit_json(doc)
        return
    _render(cfg, res, settings, doc)


def _render(cfg, res, settings, doc) -> None:
    from rich.table import Table

    from ..studies.ranking import guarded_limits

    con = console()
    b = res.best
    con.print(f"[bold green]best configuration[/bold green] after {len(res.evaluated)} evaluations:")
    for n, lo, hi in res.bounds:
        con.print(f"  {esc(n)} = {b['params'][n]:.6g}   (searched {lo:g} .. {hi:g})")
    what = f"the target {res.target}" if res.target else "the worst component"
    if res.hangings_objective is not None:  # ranked by the multi-hanging plan (--hangings)
        why = "--hangings: the points were ranked by it" + (
            "; the planned hanging's own modes do not meet --min-separation" if res.separation_guard == "multi_hanging"
            else "")
        con.print(f"  predicted relative uncertainty of {what}: {_pct(res.hangings_objective)} % by the multi-hanging "
                  f"plan below ({why}); the planned hanging alone: {_pct(b['objective'])} %")
        con.print(f"  ({esc(res.hangings_note())})")
    else:
        con.print(f"  predicted relative uncertainty of {what}: {_pct(b['objective'])} %")
    if res.active:
        con.print("  limited by: " + esc("; ".join(res.active)))
    if res.preference:
        con.print("  " + esc(res.preference))
    t = Table(title="expected accuracy of each inertia component",
              caption="sigma: " + (f"the amplitude stated to invert (--amplitude {settings.amplitude:g}, +-10 %)"
                                   if settings.tensions else "for a small amplitude (--amplitude 0)"))
    for h in ("comp", "value", "sigma", "rel %", "mode", "T s"):
        t.add_column(h, justify="right")
    for c, e in res.accuracy().items():
        if not e["identifiable"]:
            t.add_row(c, f"{e['value']:.6g}", "-", "not identifiable", "-", "-")
        else:
            t.add_row(c, f"{e['value']:.6g}", fmt(e["sigma"], 3), _pct(e["rel_sigma"]), _ABBR.get(e["mode"], e["mode"]),
                      f"{e['period']:.6g}")
    con.print(t)
    con.print("identifiability:")
    render_identifiability(con, doc["identifiability"])
    render_rig(con, b["rig"])
    render_timing(con, doc["how_to_time"])
    render_amplitude(con, doc.get("amplitude_advice"))
    render_multi_hanging(con, doc)
    tn = b["tension"]
    if tn.get("peak") is not None:
        con.print(f"wire tension: rest {', '.join(f'{x:.4g}' for x in tn['rest'])} N, peak {tn['peak']:.4g} N, "
                  f"minimum {min(tn['min']):.4g} N; depth below the ceiling {b['depth']['max']:.4g} m with the swing")
        if (g := guarded_limits(b, res.among))["left_out"]:  # a set-aside component's run, not timed
            con.print(f"  the limits without the {', '.join(g['left_out'])} run (only a set-aside component's mode, "
                      f"not timed): peak {g['peak']:.4g} N, depth {g['depth']:.4g} m")
    else:
        con.print(f"wire tension at rest {', '.join(f'{x:.4g}' for x in tn['rest'])} N; depth at rest {b['depth']['rest']:.4g} m")
    con.print("measurement uncertainties: " + ", ".join(f"{k} {v:g}" for k, v in settings.unc.items())
              + f" (timing s; length, position, com m; mass, gravity relative); amplitude {settings.amplitude:g}")
