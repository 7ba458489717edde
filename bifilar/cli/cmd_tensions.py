"""`bifilar tensions`: wire tensions by the thesis's methods beside the model's,
and moments of inertia from tensions (thesis 7.2.2)."""

from __future__ import annotations

import math

import click

from .common import (check_output_path, config_rest_pose, console, emit_json, esc, handle_errors, progress_bar,
                     warn_at_rest, write_csv)


@click.command("tensions")
@click.argument("config", type=click.Path())
@click.option("--mode", default=None, help="Mode label or 1-based index (default: torsion, else the slowest).")
@click.option("--amplitude", type=float, default=0.05, show_default=True, help="Initial displacement x mode shape.")
@click.option("--periods", type=float, default=4.0, show_default=True, help="Linear periods to simulate.")
@click.option("--motion", type=click.Path(), default=None,
              help="Use a recorded motion instead: CSV with columns t, com_x..z, q_w..q_z, tension_1..n "
                   "(the format `bifilar simulate --out` writes), e.g. load-cell rig data.")
@click.option("--solve-for", "solve_for", multiple=True,
              type=click.Choice(["Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz"]),
              help="Inertia components to estimate from the tensions (default: Ixx, Iyy, Izz).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document.")
@click.option("--out", type=click.Path(), help="CSV: time, model tensions, thesis-method tensions.")
@click.option("--force", is_flag=True, help="Replace an existing --out file.")
@handle_errors
def tensions(config, mode, amplitude, periods, motion, solve_for, as_json, out, force):
    """Tensions of CONFIG's wires during a motion by three methods (the model's
    multipliers, the thesis's symmetric formula and its general least-squares
    method), and the inertia estimated from those tensions."""
    import numpy as np

    from ..analysis.modes import linear_modes
    from ..analysis.simulate import simulate
    from ..analysis.tensions import general_tensions, symmetric_tension, wire_units
    from ..config import load_scene
    from ..estimation.from_tensions import inertia_from_tensions
    from ..estimation.motion_record import (general_noise_warning, general_tension_noise, length_mismatch,
                                            pose_noise_reason, pose_noise_warnings, product_noise_cause,
                                            product_noise_reason, read_motion, record_inertia)
    from ..models import maximal as mx
    from ..rotations import quat_to_matrix

    from .common import MAX_SIM_PERIODS, OptionChecker

    chk = OptionChecker()
    chk.finite("--amplitude", amplitude)
    if chk.positive("--periods", periods):
        chk.in_range("--periods", periods, 0, MAX_SIM_PERIODS, lo_open=True)
    chk.done()
    out_p = check_output_path(out, force, [config, motion], "--out")
    scene = load_scene(config)
    comps = tuple(solve_for) or ("Ixx", "Iyy", "Izz")
    warns: list[str] = []  # every warning printed on stderr, in order: the JSON's "warnings"

    def say(w: str) -> None:
        click.echo(f"warning: {w}", err=True)
        warns.append(w)

    if motion is None:
        rest = config_rest_pose(scene, config)
        ms = linear_modes(scene, rest)
        mode = ms.pick(mode).label
        warns += warn_at_rest(scene, rest, ms.modes, only=mode)  # as simulate's run
        with progress_bar("simulating", enabled=True) as upd:
            res = simulate(scene, mode, amplitude, periods, rest=rest, modes=ms, rtol=SIM_RTOL,
                           samples_per_period=200, progress=upd)
        t, y, T_model = res.t, res.y, res.tensions
        for w in res.warnings:  # a wire going slack: the 'tensions' after it are not physical
            say(w)
        from ..analysis.elastic_rest import loaded_scene

        P = mx.params_from_scenes(loaded_scene(scene, rest))  # the run's wires (loaded where rig.stiffness is stated)
        accel, alpha, _, _ = mx.solve_dynamics(y, P, stabilise=False)
        omega = y[:, 10:13]
        source = f"simulated mode {res.mode}, amplitude {amplitude:g}"
    else:
        rec = read_motion(motion, scene.n_wires)
        t, y, T_model, omega, accel, alpha = rec.t, rec.y, rec.tensions, rec.omega, rec.accel, rec.alpha
        source = f"recorded motion {motion}"
        # with rig.stiffness the wires hang loaded, L (1 + T / EA) at rest: the record is compared with those
        rest = config_rest_pose(scene, config) if scene.stiffness is not None else None
    R = quat_to_matrix(y[:, 3:7])
    u = wire_units(scene, y[:, 0:3], R)
    mismatch, mismatch_warning = length_mismatch(scene, y[:, 0:3], R, rest)
    if mismatch_warning:
        say(mismatch_warning)
    F_gen, resid = general_tensions(scene.mass, scene.gravity, accel, u)
    doc = {"source": source, "samples": int(len(t)),
           "model": {"min": T_model.min(axis=0), "max": T_model.max(axis=0)},
           "general": {"min": F_gen.min(axis=0), "max": F_gen.max(axis=0),
                       "max_abs_difference_to_model": np.max(np.abs(F_gen - T_model), axis=0),
                       "max_residual": float(resid.max()),
                       "determined": scene.n_wires <= 3},
           "max_wire_length_mismatch": mismatch}
    # the general tensions rest on the differentiated CoM acceleration: a record's CoM noise passes into them
    # (session 20: stated, per wire the RMS and the largest std over the samples; 0 for a simulated motion,
    # whose acceleration is the model's)
    gen_noise = general_tension_noise(rec, scene.mass, u) if motion is not None else np.zeros_like(F_gen)
    if gen_noise is not None:
        doc["general"]["noise_std"] = np.sqrt(np.mean(gen_noise ** 2, axis=0))
        doc["general"]["noise_std_max"] = gen_noise.max(axis=0)
        gw = None if motion is None else general_noise_warning(
            doc["general"]["noise_std"], T_model, math.sqrt(float(np.trace(rec.com_noise)) / 3))
        if gw:
            say(gw)
    if scene.n_wires > 3:
        doc["general"]["note"] = (f"underdetermined: {scene.n_wires} wires, 3 equations (Newton's law); the minimum-norm "
                                  "tensions balance the forces but are not the wire tensions")
    F_sym = None
    if scene.n_wires == 2:
        F_sym = symmetric_tension(scene.mass, scene.gravity, accel[:, 2], u)
        doc["symmetric"] = {"min": float(F_sym.min()), "max": float(F_sym.max()),
                            "max_abs_difference_to_model": np.max(np.abs(F_sym[:, None] - T_model), axis=0),
                            "note": "valid only for mirror-symmetric motion (thesis 7.2)"}
    # a record's rig is measured: its geometry's std is its own term, kept out of the residuals' (record_std)
    if motion is None:
        geometry = None
    else:  # the config's stated position / com std (m), which the record's torque arms and wire directions rest on
        from ..config import read_yaml
        from ..studies.settings import stated_geometry_uncertainty

        geometry = stated_geometry_uncertainty(read_yaml(config))
    noisy = []  # components the record's pose noise leaves undetermined
    if motion is None:
        est = inertia_from_tensions(scene, t, y[:, 0:3], R, omega, T_model, alpha=alpha, components=comps)
        # a simulated motion is exact only to the integrator's tolerance, which the
        # residuals (at rounding level) cannot show: the cylinder of 6.4 gave Ixx
        # 1e-12 off with a residual std of 4e-14
        std, std_inputs, interval, dof = ({c: math.hypot(est.std[c], SIM_RTOL * abs(est.values[c])) for c in comps},
                                          None, None, est.dof)
    else:
        # the rates of a record are differentiated, not known; the config's geometry is measured too
        fit = record_inertia(scene, rec, comps, geometry)
        est, std, std_inputs, interval, noisy = fit.est, fit.std, fit.std_geometry, fit.interval, fit.noise_undetermined
        dof = {c: (v if math.isfinite(v) else None) for c, v in fit.dof.items()}
        for w in pose_noise_warnings(fit):
            say(w)
    # a component the motion does not excite was fixed at the config's value in the fit: its first-pass
    # number is not determined (a vertical bifilar's Iyy came out 20.3 for 30), so none is printed
    undetermined = [c for c in comps if not std[c] == std[c] or c in est.poorly_excited]
    doc["inertia_from_tensions"] = {
        c: {"value": None if c in undetermined else est.values[c], "std": std[c],
            "dof": None if c in undetermined else dof.get(c),
            "interval_95": interval[c] if interval else est.interval95(c, std[c]),
            "config": float(scene.inertia[_idx(c)])} for c in comps}
    # why each is null, the order record_inertia decides it in: the attitude noise swamping the column, a product
    # held for the attitude noise, else not excited (session 23: the table said 'not excited' for all three)
    held = [] if motion is None else fit.products_held
    cause = {c: NOISE_SWAMPS if c in noisy else product_noise_cause(fit) if c in held else NOT_EXCITED
             for c in undetermined}
    for c in undetermined:
        doc["inertia_from_tensions"][c]["reason"] = (pose_noise_reason(fit) if c in noisy else product_noise_reason(fit)
                                                     if c in held else NOT_DETERMINED)
    if std_inputs is not None:  # the config geometry's share of std (record_std)
        for c in comps:
            doc["inertia_from_tensions"][c]["std_geometry"] = std_inputs.get(c) if c not in undetermined else None
    # a simulated motion in which a wire went slack is off the model after that (the bilateral model pulls on
    # the slack wire): an inertia fitted to it is not the body's, so none is given (session 13)
    slack = slack_reason(res.slack) if motion is None and res.slack else None
    if slack:
        for c in comps:
            doc["inertia_from_tensions"][c].update({"value": None, "std": None, "dof": None, "interval_95": None,
                                                    "reason": slack})
    # the components without a value for want of excitation (the estimator's rule, std above 1/1.96 of the
    # component's scale, also applied to a record's std with the differentiation term by record_inertia);
    # inertia_from_tensions_not_determined names every component without a value and its cause
    poor = [c for c in undetermined if cause[c] == NOT_EXCITED]
    doc["inertia_from_tensions_poorly_excited"] = poor
    doc["inertia_from_tensions_not_determined"] = {c: "a wire went slack" for c in comps} if slack else cause
    doc["inertia_from_tensions_residual_rms"] = est.residual_rms
    if out_p:
        cols = [t, *T_model.T, *F_gen.T] + ([F_sym] if F_sym is not None else [])
        hdr = ["t"] + [f"model_{i + 1}" for i in range(scene.n_wires)] + [f"general_{i + 1}" for i in range(scene.n_wires)]
        hdr += ["symmetric"] if F_sym is not None else []
        write_csv(out_p, hdr, np.column_stack(cols))
    if as_json:
        emit_json({**doc, "warnings": warns})
        return
    from rich.table import Table

    con = console()
    tab = Table(title=f"{esc(scene.name)}: tensions, {esc(source)}")
    for c in ("wire", "model min..max (N)", "thesis general min..max (N)", "max |general - model| (N)"):
        tab.add_column(c, justify="right")
    for i in range(scene.n_wires):
        tab.add_row(str(i + 1), f"{T_model[:, i].min():.6g} .. {T_model[:, i].max():.6g}",
                    f"{F_gen[:, i].min():.6g} .. {F_gen[:, i].max():.6g}", f"{np.max(np.abs(F_gen[:, i] - T_model[:, i])):.2e}")
    con.print(tab)
    if "note" in doc["general"]:
        con.print(f"thesis general method: {doc['general']['note']}")
    if F_sym is not None:
        con.print(f"thesis symmetric formula: {F_sym.min():.6g} .. {F_sym.max():.6g} N "
                  f"(max difference to the model {np.max(np.abs(F_sym[:, None] - T_model)):.3g} N; valid for symmetric motion only)")
    it = Table(title="Inertia from tensions (least squares over Euler's equations, thesis 7.2.2)")
    for c in ("component", "estimate (kg m^2)", "std", "95 % (t, dof)", "config value", "excited?"):
        it.add_column(c, justify="right")
    for c in comps:
        if slack:
            it.add_row(c, "not estimated (a wire went slack)", "n/a", "n/a", f"{scene.inertia[_idx(c)]:.8g}", "-")
            continue
        lo, hi = interval[c] if interval else est.interval95(c, std[c])
        nu = dof.get(c)
        span = f"{lo:.6g} .. {hi:.6g} ({nu:.2g})" if c not in undetermined else "n/a"
        if c not in undetermined and nu is None:
            span = f"{lo:.6g} .. {hi:.6g} (normal)"
        it.add_row(c, f"not determined ({cause[c]})" if c in undetermined else f"{est.values[c]:.8g}",
                   f"{std[c]:.2g}" if c not in undetermined else "n/a", span, f"{scene.inertia[_idx(c)]:.8g}",
                   "POORLY" if c in poor else "yes" if c not in undetermined else "held" if c in held else "swamped")
    con.print(it)
    if slack:
        con.print(f"inertia from tensions: {esc(slack)}")


def slack_reason(slack: list) -> str:
    """Why no inertia is estimated from a simulated motion in which wires went
    slack (``slack``: (wire, 1-based, t in s) as :class:`SimulationResult` lists them)."""
    first = min(slack, key=lambda wt: wt[1])
    return (f"not estimated: wire {first[0]} goes slack at t = {first[1]:.4g} s of the simulated motion, which is "
            "not physical after that (the model keeps pulling on a slack wire), so an inertia fitted to it is not "
            "the body's; reduce --amplitude until no wire goes slack")


NOT_DETERMINED = ("not determined: the motion hardly excites this component (its torque is at rounding level "
                  "or its std, with the config geometry's and the differentiation's for a record, above 1/1.96 of its "
                  "scale, the config's I_ii or sqrt(I_ii I_jj) for a product: its 95 % interval would span more "
                  "than +-the scale), so the record cannot determine it (beside better-excited components the fit "
                  "holds it at the config's value); excite a mode that turns the body about this axis")
"""The reason a component's ``value`` is ``null`` in ``inertia_from_tensions``."""

NOT_EXCITED = "not excited"
"""The short cause (``inertia_from_tensions_not_determined``, the table) of :data:`NOT_DETERMINED`."""

NOISE_SWAMPS = "attitude noise swamps the motion"
"""The short cause of :func:`~bifilar.estimation.motion_record.pose_noise_reason`."""

SIM_RTOL = 1e-11
"""Integrator tolerance of the simulated motion (relative; also the floor of
its inertia's std)."""


def _idx(c):
    return {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}[c]
