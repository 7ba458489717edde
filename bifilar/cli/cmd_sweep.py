"""`bifilar sweep`: compare suspension configurations and recommend one."""

from __future__ import annotations

import click

from ..output import write_yaml
from .common import (check_journal_path, check_output_path, check_workers, console, emit_json, esc, fmt,
                     handle_errors, progress_bar)

UNC_HELP = ("Measurement uncertainty KEY=VALUE (repeatable): timing [s], length, position, com [m], mass, gravity, "
            "stiffness (EA, where rig.stiffness is stated; default 0.1) [relative].")


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
                     help="Smallest allowed relative gap between any timed mode's period and any other mode's "
                          "(default 0.02; 0 switches the guard off)."),
        click.option("--no-tensions", is_flag=True, help="Skip the nonlinear runs (no tensions, swing depth or amplitude bias)."),
        click.option("--periods", "sim_periods", type=float, default=3.0, show_default=True,
                     help="Periods simulated per mode for the tensions."),
        click.option("--write-config", "write_config", type=click.Path(), default=None,
                     help="Write the recommended point as a config (anchors, attachments, lengths) that "
                          "`bifilar modes` accepts."),
        click.option("--stopwatch", "reaction", type=float, default=0.1, show_default=True, metavar="SECONDS",
                     help="Timing by hand: standard uncertainty of one trial's total time (start and stop) [s]; "
                          "sets the cycles and trials recommended per timed mode."),
        click.option("--sensor", default=None, metavar="NOISE,RATE",
                     help="Timing from a recording: noise relative to the amplitude and sample rate [Hz]; adds "
                          "the records needed per timed mode."),
        click.option("--hangings", "hangings", is_flag=True,
                     help="Plan several hangings (orientations of the body on the recommended rig) and the modes to "
                          "time in each, so that every --component is identified (automatic when one hanging "
                          "cannot); predicts each component from the joint fit."),
        click.option("--rig", default="shared", show_default=True, metavar="shared|separate",
                     help="The multi-hanging plan's wire lengths and anchors (and attachments at a body point "
                          "two hangings use): shared = the one rig measured once for every hanging, separate = "
                          "measured again for each hanging."),
        click.option("--write-measurements", type=click.Path(), default=None,
                     help="Write the multi-hanging plan as a measurements file for `bifilar invert --measurements` "
                          "(planned periods: replace them with the measured ones)."),
        click.option("--json", "as_json", is_flag=True, help="Print one JSON document."),
    ]
    for o in reversed(opts):
        fn = o(fn)
    return fn


SHORTHAND_HELP = ("NAME is a dotted config path (rig.attachments.0.0, rig.lengths.1, body.mass, "
                  "uncertainty.timing) or a shorthand: spacing (body attachments' spacing, m), ceiling_spacing "
                  "(anchors' spacing, m), length (mean wire length, m), length_offset (last minus first wire, m), "
                  "height (attachments above the CoM, m), stiffness (every wire's EA, N), amplitude (excitation), "
                  "rotate_x/_y/_z[_deg] (turn the body before hanging); see README 'Sweep parameters'.")


def log_warnings(ws: list[str]) -> list[str]:
    """Log each line of ``ws`` to stderr (``warning: ...``); returns ``ws``."""
    for w in ws:
        click.echo(f"warning: {w}", err=True)
    return ws


def multi_hanging(doc: dict, cfg: dict, config: str, params: dict, settings, cons, reaction, sensor, wanted: bool,
                  wm_p, who: str, deferred: dict | None = None, point: dict | None = None) -> list[str]:
    """Add the multi-hanging plan at ``params`` (:func:`bifilar.studies.point_hangings.hangings_at_point`;
    ``point`` the point there) to ``doc`` when ``wanted`` or a measurements
    file ``wm_p`` is asked for, write that file, and log and return the
    plan's warnings."""
    if not (wanted or wm_p):
        return []
    from ..studies.point_hangings import hangings_at_point

    ph = hangings_at_point(cfg, config, params, settings, cons, reaction, sensor, who, deferred, point)
    warnings = log_warnings(list(ph.warnings))
    doc["multi_hanging"] = ph.document
    if wm_p:
        mdoc, notes, header = ph.measurements_file(wm_p.name)
        warnings += log_warnings(notes)
        write_yaml(wm_p, mdoc, header)
        doc["measurements_written"] = str(wm_p)
    return warnings


def recommendation_warnings(doc: dict, cfg: dict, config: str, point: dict, settings, cons, reaction, sensor,
                            wanted: bool, wm_p, who: str, what: str, deferred: bool, hangings: bool) -> list[str]:
    """The warnings of a study's recommended (``sweep``) or planned (``plan``)
    ``point``, logged: the multi-hanging plan at it first (:func:`multi_hanging`,
    into ``doc``; a plan that cannot meet ``--min-separation`` exits 2
    before any warning or file), then the point's cautions
    (:func:`~bifilar.studies.point_advice.point_cautions`, ``what`` names
    the point; with ``hangings`` the joint sigma's physical limits), then
    the plan's warnings.  ``deferred``: the search left ``--min-separation``
    to the multi-hanging plan."""
    from ..studies.point_advice import point_cautions

    mh_warnings = multi_hanging(doc, cfg, config, point["params"], settings, cons, reaction, sensor, wanted, wm_p,
                                who, point if deferred else None, point)
    joint = doc["multi_hanging"]["accuracy"] if hangings and "multi_hanging" in doc else None
    return log_warnings(point_cautions(cfg, config, point, what, cons, joint)) + mh_warnings


def render_multi_hanging(con, doc: dict) -> None:
    mh = doc.get("multi_hanging")
    if not mh:
        return
    from ..studies.hangings import describe_json

    con.print("[bold]multi-hanging plan[/bold] (joint least-squares fit of every timed period, as invert --measurements makes it):")
    for line in describe_json(mh):
        con.print(f"  - {line}")
    if doc.get("measurements_written"):
        con.print(f"measurements file written to {doc['measurements_written']} "
                  f"(bifilar invert --measurements {doc['measurements_written']})")


def render_amplitude(con, adv: dict | None) -> None:
    """The amplitude advice: one sentence, and the invert options per component."""
    if not adv:
        return
    con.print(f"amplitude: {esc(adv['text'])}; after the experiment, per component (POINT: the point's config, "
              "--write-config; the period: the measured one):")
    for c, r in adv["components"].items():
        con.print(f"  - {c}: bifilar invert POINT {esc(r['invert_options'])}")


def render_timing(con, rows: list[dict]) -> None:
    from ..studies.timing import describe

    if rows:
        con.print("how to time it (reaches the assumed timing uncertainty of each period):")
        for r in rows:
            con.print(f"  - {describe(r)}")


def render_identifiability(con, ident: dict) -> None:
    """Per component: measurable, from which modes; set aside, why; else its
    remedy; and a marginal one's line (ranked or set aside near the line)."""
    from ..studies.recommend import remedy_clause

    for c, e in ident.items():
        if e.get("set_aside"):
            con.print(f"  [yellow]{c}: set aside[/yellow]: {esc(e['set_aside']['reason'].split(': ', 1)[1])}"
                      + esc(remedy_clause(e)))
        elif e["identifiable"]:
            modes = ", ".join(f"{m} ({v:.2g})" for m, v in list(e.get("from_modes", {}).items())[:3])
            con.print(f"  {c}: measurable" + (f" from {modes} (|d ln T / d ln I|)" if modes else ""))
        else:
            con.print(f"  [yellow]{c}: not identifiable[/yellow] (no mode's period depends on it)" + esc(remedy_clause(e)))
        if e.get("marginal"):
            con.print(f"    [yellow]marginal[/yellow]: {esc(e['marginal']['reason'].split(': ', 1)[1])}")


def render_rig(con, rig: dict, title: str = "the rig to build") -> None:
    """Anchors (world), attachments (body frame), lengths and wire angles."""
    from rich.table import Table

    t = Table(title=title, caption="anchors: world frame, z up; attachments: body frame, origin at the CoM; "
                                   "angle from the vertical at rest")
    for h in ("wire", "anchor m", "attachment m", "length m", "angle deg"):
        t.add_column(h, justify="right")
    vec = lambda v: "[" + ", ".join(f"{x:.4g}" for x in v) + "]"  # noqa: E731
    for i, (a, b, L, ang) in enumerate(zip(rig["anchors"], rig["attachments"], rig["lengths"], rig["wire_angles_deg"])):
        t.add_row(str(i + 1), vec(a), vec(b), f"{L:.5g}", f"{ang:.3g}")
    con.print(t)


@click.command("sweep")
@click.argument("config", type=click.Path())
@click.option("--param", "params", multiple=True, required=True, metavar="NAME=VALUES",
              help="Parameter to vary (repeatable); VALUES as START:STOP:NUM, log:START:STOP:NUM, [a, b, c] or "
                   "a,b,c. " + SHORTHAND_HELP)
@click.option("--zip", "zip_", is_flag=True, help="Vary the parameters together instead of over a grid.")
@common_options
@click.option("--out", type=click.Path(), help="Write one CSV row per point (and a resumable journal FILE.partial.jsonl while running).")
@click.option("--resume", is_flag=True, help="Reuse the finished points of an interrupted sweep with the same --out.")
@click.option("--plot", type=click.Path(), help="Draw the figures to this image file (PNG, PDF, SVG).")
@click.option("--workers", type=int, default=1, show_default=True, help="Processes to use (1..1024; at most one per CPU and per point starts).")
@click.option("--force", is_flag=True, help="Replace existing --out/--plot files (and a stale journal).")
@click.option("--stop-after", type=int, default=None, hidden=True, help="Stop after N new points (tests: a stand-in for Ctrl-C).")
@handle_errors
def sweep(config, params, zip_, components, target, amplitude, sigmas, max_tension, max_depth, lengths_available,
          min_separation, no_tensions, sim_periods, write_config, reaction, sensor, hangings, rig, write_measurements,
          as_json, out, resume, plot, workers, force, stop_after):
    """Compare suspension configurations of CONFIG: predicted inertia
    uncertainty, estimator bias, mode separation, tensions and clearance per
    point; rank the feasible points and recommend one."""
    import time

    from ..config import read_yaml, scene_from_dict
    from ..errors import InputError
    from ..studies import sweep as sw
    from ..studies.shorthands import check_param, overlap_warnings, parse_param
    from ..studies.point_advice import write_point_config
    from ..studies.recommend import add_point_remedies, point_advice, reference_point, unmeasured
    from ..studies.study_inputs import resolve_study
    from ..studies.timing import check_reaction, parse_sensor

    check_workers(workers)
    if resume and not out:
        raise InputError("--resume", "needs --out FILE (the journal is FILE.partial.jsonl)")
    cfg = read_yaml(config)
    if not isinstance(cfg, dict):
        raise InputError("config", "must be a YAML mapping with keys body and rig")
    scene_from_dict(cfg, config)  # the base config must be valid itself (ConfigErrors: exit 2, every problem)
    specs = [parse_param(p) for p in params]
    for s in specs:
        check_param(cfg, s.name, s.values)
    grid = sw.build_grid(specs, zip_)
    pre = overlap_warnings([s.name for s in specs])
    for w in pre:
        click.echo(f"warning: {w}", err=True)
    reaction, sensor = check_reaction(reaction), parse_sensor(sensor)
    settings, cons, target = resolve_study(cfg, components, target, amplitude, sigmas, max_tension, max_depth,
                                           lengths_available, min_separation, no_tensions, sim_periods,
                                           [s.name for s in specs], config, rig)
    journal = None
    if out:
        journal = check_journal_path(sw.journal_path(out), [config, plot], "--out", resume=resume)
        if journal.exists() and not resume and not force:
            raise InputError("--out", f"{journal} holds an interrupted sweep; pass --resume to continue it or --force to start over")
    out_p = check_output_path(out, force, [config, journal], "--out")
    plot_p = check_output_path(plot, force, [config, out, journal], "--plot")
    wc_p = check_output_path(write_config, force, [config, out, plot, journal], "--write-config")
    wm_p = check_output_path(write_measurements, force, [config, out, plot, write_config, journal], "--write-measurements")
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
    names = [s.name for s in specs]

    def write_out() -> None:
        sw.write_points_csv(out_p, points, names, list(settings.components), rec.get("measurable"))
        journal.unlink(missing_ok=True)

    from ..studies.hangings import hangings_objectives

    rec = sw.assess(points, cons, target, hangings=(lambda ps: hangings_objectives(
        cfg, config, [p["params"] for p in ps], settings, cons.min_separation, target)) if hangings else None)
    if not rec["n_valid"]:
        # nothing to rank, draw or recommend: refuse as `plan` does; the CSV keeps every point's reason
        if out_p:
            write_out()
        raise InputError("--param", "no point of the sweep is valid: " + sw.why_invalid(points)
                         + (f"; every point's reason is in {out_p}" if out_p else ""))
    need = unmeasured(rec)  # not identifiable, or set aside: their remedies and the multi-hanging plan
    add_point_remedies(rec, need, reference_point(rec, points), cfg, config, settings)
    warnings = list(pre)
    if (w := sw.stretching_summary(points)) is not None:
        click.echo(f"warning: {w}", err=True)
        warnings.append(w)
    if rec.get("best") is not None:
        best = points[rec["best"]]
        deferred = rec["separation_guard"] == "multi_hanging"  # --min-separation left to the hangings plan
        # the hangings first: a plan that cannot meet --min-separation exits 2 before any warning or file
        warnings += recommendation_warnings(rec, cfg, config, best, settings, cons, reaction, sensor,
                                            hangings or bool(need), wm_p, "bifilar sweep",
                                            "the recommended point", deferred, hangings)
        rec.update(point_advice(best, cfg, config, settings, reaction, sensor,
                                cons.min_separation if deferred else None, rec["measurable"]))
    elif wm_p or hangings:
        raise InputError(rec["binding"] if rec["separation_guard"] == "multi_hanging" else "--hangings",
                         "no recommended point to plan the hangings at: " + rec["reason"])
    if wc_p:
        if rec.get("best") is None:
            raise InputError("--write-config", "no recommended point to write: " + rec["reason"])
        write_point_config(wc_p, cfg, config, points[rec["best"]], f"point {rec['best']} recommended by bifilar sweep")
        rec["config_written"] = str(wc_p)
    if out_p:
        write_out()
    if plot_p:
        from pathlib import Path

        from ..figures import plot_sweep
        from ..studies.sweep_output import sweep_figure_data

        plot_sweep(plot_p, sweep_figure_data(points, specs, zip_, list(settings.components), cons, rec),
                   title=f"{cfg.get('name', Path(config).stem)}: sweep of {', '.join(names)}")
    if as_json:
        emit_json({"points": points, "recommendation": rec, "settings": settings.describe(),
                   "parameters": names, "zip": zip_, "runtime_s": runtime, "warnings": warnings})
        return
    render(cfg, config, points, names, settings, cons, rec, runtime)


_ABBR = {"torsion": "tor", "swing-x": "sx", "swing-y": "sy", "bounce": "bn", "roll": "rl", "pitch": "pt"}


def _pct(x, digits=3):
    return "-" if x is None else ("inf" if x == float("inf") else f"{100 * x:.{digits}g}")


def render(cfg, config, points, names, settings, cons, rec, runtime) -> None:
    """Rich tables: the points, the recommendation and the trade-off front."""
    from pathlib import Path

    from rich.table import Table

    from ..studies.ranking import no_sigma_reason, point_separation

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
        for c in comps:
            e = p["components"][c]
            if not e["identifiable"]:
                row.append("[yellow]n/a[/yellow]")
            else:
                row.append(f"{_pct(e['rel_sigma'])} {_ABBR.get(e['mode'], e['mode'])}")
        row.append(_pct(point_separation(p, rec.get("measurable"))))
        g = p.get("guard_limits") or {"peak": p["tension"]["peak"], "depth": p["depth"]["max"]}  # the limits' figures
        pk = g["peak"] if settings.tensions else max(p["tension"]["rest"])
        row.append("-" if pk is None else f"{pk:.4g}")
        d = g["depth"] if g["depth"] is not None else p["depth"]["rest"]
        row.append(f"{d:.4g}")
        row.append(str(p["rank"]) if p["rank"] is not None else "[yellow]x[/yellow]" if p["violations"] else "-")
        if p["violations"]:
            notes.append(f"{i}: " + esc("; ".join(p["violations"])))
        unavailable = [c for c in comps if p["components"][c].get("sigma_unavailable")]
        if unavailable:  # not ranked: say why, in the point's own words (whole in the JSON's sigma_unavailable)
            why = no_sigma_reason(p["components"][unavailable[0]])
            notes.append(f"{i}: no uncertainty for {', '.join(unavailable)}" + esc(why) + "; see --json")
        t.add_row(*row)
    con.print(t)
    for line in notes[:20]:
        con.print(f"  [yellow]x[/yellow] {line}")
    if len(notes) > 20:
        con.print(f"  ... {len(notes) - 20} more (see --json or --out)")
    con.print("(n/a: no mode's period depends on that component; sep: smallest gap between a timed mode (a "
              "ranked component's) and any other mode; modes: " + ", ".join(f"{v} = {k}" for k, v in _ABBR.items()) + ")")
    con.print("identifiability" + (" at the recommended point:" if rec.get("best") is not None else ":"))
    render_identifiability(con, rec["identifiability"])
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
                    caption=f"bias: estimator vs the full model at amplitude {b['amplitude']:g}; sigma: "
                    + (f"the amplitude stated to invert (--amplitude {b['amplitude']:g}, +-10 %)"
                       if settings.tensions else "for a small amplitude (--amplitude 0)"))
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
            acc.add_row(c, f"{e['value']:.5g}", fmt(e["sigma"], 3), _pct(e["rel_sigma"]), _ABBR.get(e["mode"], e["mode"]),
                        f"{e['period']:.5g}", _pct(bias.get("small_angle")), thesis, _pct(bias.get("linear")))
        con.print(acc)
        render_rig(con, b["rig"])
        render_timing(con, rec.get("how_to_time") or [])
        render_amplitude(con, rec.get("amplitude_advice"))
        render_multi_hanging(con, rec)
        if rec.get("config_written"):
            con.print(f"config of the recommended point written to {rec['config_written']}")
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
