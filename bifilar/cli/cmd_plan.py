"""`bifilar plan`: the configuration with the smallest predicted inertia
uncertainty that meets the constraints."""

from __future__ import annotations

import click

from .cmd_sweep import _ABBR, _pct, common_options, resolve_all
from .common import check_workers, console, emit_json, esc, handle_errors, progress_bar


@click.command("plan")
@click.argument("config", type=click.Path(dir_okay=False))
@click.option("--param", "params", multiple=True, required=True, metavar="NAME=LO:HI",
              help="Parameter to search within bounds (repeatable): a dotted config path or a shorthand "
                   "(spacing, ceiling_spacing, length, length_offset, height, amplitude, rotate_*).")
@common_options
@click.option("--workers", type=int, default=1, show_default=True, help="Processes for the coarse grid (1..1024; at most one per CPU and per point starts).")
@handle_errors
def plan(config, params, components, target, amplitude, sigmas, max_tension, max_depth, lengths_available,
         min_separation, no_tensions, sim_periods, as_json, workers):
    """Search the parameters of CONFIG for the configuration that minimises
    the predicted uncertainty of the target inertia subject to the
    constraints; report the expected accuracy of each component.  Exit 2,
    naming the binding constraint, when nothing is feasible."""
    from ..config import read_yaml, scene_from_dict
    from ..errors import InputError
    from ..studies.plan import plan as run_plan
    from ..studies.shorthands import check_param, parse_bounds

    check_workers(workers)
    cfg = read_yaml(config)
    if not isinstance(cfg, dict):
        raise InputError("config", "must be a YAML mapping with keys body and rig")
    scene_from_dict(cfg, config)  # the base config must be valid itself (ConfigErrors: exit 2, every problem)
    bounds = [parse_bounds(p) for p in params]
    for n, _, _ in bounds:
        check_param(cfg, n)
    settings, cons, target = resolve_all(cfg, components, target, amplitude, sigmas, max_tension, max_depth,
                                         lengths_available, min_separation, no_tensions, sim_periods)
    with progress_bar("planning", enabled=True) as upd:
        res = run_plan(cfg, config, bounds, settings, cons, target, workers=workers, progress=upd)
    if as_json:
        doc = res.to_json()
        doc["settings"] = settings.describe()
        emit_json(doc)
        return
    _render(cfg, res, settings)


def _render(cfg, res, settings) -> None:
    from rich.table import Table

    con = console()
    b = res.best
    con.print(f"[bold green]best configuration[/bold green] after {len(res.evaluated)} evaluations:")
    for n, lo, hi in res.bounds:
        con.print(f"  {esc(n)} = {b['params'][n]:.6g}   (searched {lo:g} .. {hi:g})")
    what = f"the target {res.target}" if res.target else "the worst component"
    con.print(f"  predicted relative uncertainty of {what}: {_pct(b['objective'])} %")
    if res.active:
        con.print("  limited by: " + esc("; ".join(res.active)))
    t = Table(title="expected accuracy of each inertia component")
    for h in ("comp", "value", "sigma", "rel %", "mode", "T s"):
        t.add_column(h, justify="right")
    for c, e in res.accuracy().items():
        if not e["identifiable"]:
            t.add_row(c, f"{e['value']:.6g}", "-", "not identifiable", "-", "-")
        else:
            t.add_row(c, f"{e['value']:.6g}", f"{e['sigma']:.3g}", _pct(e["rel_sigma"]), _ABBR.get(e["mode"], e["mode"]),
                      f"{e['period']:.6g}")
    con.print(t)
    tn = b["tension"]
    if tn.get("peak") is not None:
        con.print(f"wire tension: rest {', '.join(f'{x:.4g}' for x in tn['rest'])} N, peak {tn['peak']:.4g} N, "
                  f"minimum {min(tn['min']):.4g} N; depth below the ceiling {b['depth']['max']:.4g} m with the swing")
    else:
        con.print(f"wire tension at rest {', '.join(f'{x:.4g}' for x in tn['rest'])} N; depth at rest {b['depth']['rest']:.4g} m")
    con.print("measurement uncertainties: " + ", ".join(f"{k} {v:g}" for k, v in settings.unc.items())
              + f" (timing s; length, position, com m; mass, gravity relative); amplitude {settings.amplitude:g}")
