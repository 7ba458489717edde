"""`bifilar modes`: rest pose and linear modes."""

from __future__ import annotations

import click

from .common import (check_output_path, config_rest_pose, console, emit_json, esc, fmt, handle_errors, warn_at_rest,
                     write_csv)


def modes_document(scene, rest, ms) -> dict:
    """The JSON document of ``interface.md`` (plus extra fields); ``dof`` is
    the number of modes (6 minus the rank of the wires, not 6 - n when wires
    are dependent)."""
    from ..analysis.equilibrium import tensions_determined
    from ..analysis.wire_statics import tension_range

    return {
        "equilibrium": {
            "com": rest.com, "rotation": rest.R, "tensions": rest.tensions,
            "tensions_determined": tensions_determined(scene, rest),
            # what statics allows each wire (N): [T, T] where the tensions are determined
            "tension_range": tension_range(scene, rest),
            "lowest_point_z": rest.lowest_z, "depth_below_ceiling": rest.depth,
            "clearance_source": scene.support_source, "kkt_residual": rest.kkt_residual,
        },
        "modes": [
            {"label": m.label, "period": m.period, "shape": m.shape,
             "frequency": (1.0 / m.period) if m.period else None, "description": m.description}
            for m in ms.modes
        ],
        "scene": {"name": scene.name, "mass": scene.mass, "wires": scene.n_wires, "dof": len(ms.modes)},
        "body": body_document(scene),
    }


def body_document(scene) -> dict:
    """The body as the program sees it (SI): mass (kg), inertia tensor about
    the CoM in body axes and its principal moments (kg m^2), and for a body
    built from parts the CoM in the parts' build frame (m)."""
    import numpy as np

    return {"mass": scene.mass, "inertia": scene.inertia, "principal_moments": np.linalg.eigvalsh(scene.inertia),
            "com_in_parts_frame": scene.parts_com, "built_from": "parts" if scene.parts_com is not None else "mass+inertia"}


@click.command("modes")
@click.argument("config", type=click.Path())
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document (interface.md).")
@click.option("--out", type=click.Path(), help="Write the modes to this CSV file.")
@click.option("--force", is_flag=True, help="Replace an existing --out file.")
@handle_errors
def modes(config: str, as_json: bool, out: str | None, force: bool) -> None:
    """Rest pose and every linear mode (period, shape, label) of CONFIG."""
    from ..analysis.modes import COMPONENTS, linear_modes
    from ..config import load_scene

    out_p = check_output_path(out, force, [config], "--out")
    scene = load_scene(config)
    rest = config_rest_pose(scene, config)
    ms = linear_modes(scene, rest)
    at_rest = warn_at_rest(scene, rest, ms.modes)
    from ..analysis.close_modes import close_mode_warnings

    close = close_mode_warnings(ms.modes)
    for w in close:
        click.echo(f"warning: {w}", err=True)
    if out_p:
        rows = [[k + 1, m.period if m.period else float("nan"), *m.shape] for k, m in enumerate(ms.modes)]
        write_csv(out_p, ["index", "period_s", *[f"shape_{c}" for c in COMPONENTS]], rows)
    if as_json:
        doc = modes_document(scene, rest, ms)
        if at_rest or close:  # every warning printed on stderr, the rest pose's first
            doc["warnings"] = at_rest + close
        emit_json(doc)
        return
    from rich.table import Table

    con = console()
    con.print(f"[bold]{esc(scene.name)}[/bold]: {scene.mass:.6g} kg on {scene.n_wires} wires, {len(ms.modes)} degrees of freedom")
    body = body_document(scene)
    bt = Table(title="Body (inertia about the CoM, body axes)")
    bt.add_column("quantity")
    bt.add_column("value")
    bt.add_row("mass (kg)", f"{scene.mass:.6g}")
    if body["com_in_parts_frame"] is not None:
        bt.add_row("CoM in the parts' build frame (m)", "[" + ", ".join(f"{v:.6g}" for v in body["com_in_parts_frame"]) + "]")
    else:
        bt.add_row("CoM", "origin of the body frame (given)")
    for i, row in enumerate(scene.inertia):
        bt.add_row("" if i else "inertia (kg m^2)", "[" + ", ".join(f"{v:.6g}" for v in row) + "]")
    bt.add_row("principal moments (kg m^2)", ", ".join(f"{v:.6g}" for v in body["principal_moments"]))
    con.print(bt)
    t = Table(title="Rest pose (world frame, z up)")
    t.add_column("quantity")
    t.add_column("value")
    t.add_row("CoM (m)", "[" + ", ".join(f"{v:.6g}" for v in rest.com) + "]")
    from ..rotations import matrix_to_rotvec
    import numpy as np

    t.add_row("attitude, rotation vector (deg)", "[" + ", ".join(f"{np.degrees(v):.4g}" for v in matrix_to_rotvec(rest.R)) + "]")
    for i, T in enumerate(rest.tensions):
        t.add_row(f"tension wire {i + 1} (N)", f"{T:.6g}")
    t.add_row("lowest point z (m)", f"{rest.lowest_z:.6g} ({esc(scene.support_source)})")
    t.add_row("depth below ceiling (m)", f"{rest.depth:.6g}")
    con.print(t)
    mt = Table(title="Linear modes (slowest first)")
    for col in ("#", "label", "period (s)", "freq (Hz)", "kinetic energy", "shape (world; m, rad)"):
        mt.add_column(col, justify="right" if col in ("#", "period (s)", "freq (Hz)") else "left")
    for k, m in enumerate(ms.modes):
        shape = " ".join(f"{c}{v:+.3f}" for c, v in zip(COMPONENTS, m.shape) if abs(v) >= 5e-4)
        mt.add_row(str(k + 1), esc(m.label), fmt(m.period, 8), fmt(1 / m.period if m.period else None, 4), esc(m.description),
                   shape)
    con.print(mt)
