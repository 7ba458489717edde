"""Forward-model and CLI audit, session 12 (docs/design.md, "Forward-model and
CLI audit, session 12"): modes, simulate and tensions on scenes none of the
shipped configs resembles, each against a formulation of its own, and the
command line on broken inputs."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
from bifilar.cli import main
from bifilar.config import scene_from_dict
from bifilar.models.reduced import TorsionParams, torsion_period
from conftest import one_error_line

G = 9.81


def bifilar(mass, principal, anchor_half, att_half, att_z, length, anchor_z=0.0):
    """Two wires in the x-z plane: anchors at (+-anchor_half, 0, anchor_z),
    attachments at (+-att_half, 0, att_z) in body axes (CoM origin)."""
    return scene_from_dict({
        "gravity": G,
        "body": {"mass": mass, "inertia": {"principal": list(principal)}},
        "rig": {"anchors": [[-anchor_half, 0, anchor_z], [anchor_half, 0, anchor_z]],
                "attachments": [[-att_half, 0, att_z], [att_half, 0, att_z]],
                "lengths": [length, length]},
    }, warn=False)


def trifilar(mass, principal, r, length, att_z=0.0, anchor_z=0.0):
    ang = np.deg2rad([0.0, 120.0, 240.0])
    pts = np.c_[r * np.cos(ang), r * np.sin(ang), np.zeros(3)]
    return scene_from_dict({
        "gravity": G,
        "body": {"mass": mass, "inertia": {"principal": list(principal)}},
        "rig": {"anchors": (pts + [0, 0, anchor_z]).tolist(), "attachments": (pts + [0, 0, att_z]).tolist(),
                "lengths": [length] * 3},
    }, warn=False)


def modes_of(scene):
    rest = rest_pose(scene)
    return rest, linear_modes(scene, rest)


# ---------------------------------------------------------------------------
# clearance: the CoM is part of the body
# ---------------------------------------------------------------------------

def test_clearance_without_a_shape_reaches_the_centre_of_mass():
    """A body given by mass and inertia only, its CoM 1.5 m below its two
    attachments: the lowest point was the attachments' (z = 0, depth 1 m)
    while the CoM, which lies inside the convex hull of the body's mass,
    hangs at z = -1.5; `sweep --max-depth` held that 1 m against its limit.
    The lowest point is now at most the CoM's height, at rest and over a
    run (both engines)."""
    sc = bifilar(2.0, [0.5, 0.52, 0.05], 0.2, 0.2, 1.5, 1.0, anchor_z=1.0)
    rest = rest_pose(sc)
    assert rest.com[2] == pytest.approx(-1.5, abs=1e-12)
    assert rest.lowest_z <= rest.com[2] + 1e-12
    assert rest.depth >= sc.ceiling_z - rest.com[2] - 1e-12
    for method in ("auto", "DOP853"):
        r = simulate(sc, "swing-y", 0.05, 2, method=method)
        assert r.lowest_z_min <= float(np.min(r.y[:, 2])) + 1e-12, method


def test_clearance_of_a_heavy_body_below_its_attachment_plane_in_the_json():
    """300 kg on three vertical 2.5 m wires, attachments 0.1 m above the CoM:
    `modes --json` put the lowest point at the attachments (0.5 m) above the
    CoM (0.4 m)."""
    res = CliRunner().invoke(main, ["modes", _write_heavy(), "--json"])
    assert res.exit_code == 0, res.stderr
    eq = json.loads(res.stdout)["equilibrium"]
    assert eq["lowest_point_z"] <= eq["com"][2] + 1e-12
    assert eq["depth_below_ceiling"] == pytest.approx(3.0 - eq["com"][2], abs=1e-12)


def _write_heavy(tmp=[]):
    import tempfile

    if not tmp:
        f = tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False)
        ang = np.deg2rad([0.0, 120.0, 240.0])
        pts = np.c_[0.6 * np.cos(ang), 0.6 * np.sin(ang), np.zeros(3)]
        f.write(json.dumps({"body": {"mass": 300.0, "inertia": {"principal": [40.0, 40.0, 75.0]}},
                            "rig": {"anchors": (pts + [0, 0, 3.0]).tolist(),
                                    "attachments": (pts + [0, 0, 0.1]).tolist(), "lengths": [2.5] * 3}}))
        f.close()
        tmp.append(f.name)
    return tmp[0]


# ---------------------------------------------------------------------------
# the period's error bound: crossings located between samples
# ---------------------------------------------------------------------------

def deep_com_bifilar():
    """2 kg on two vertical 1 m wires 0.4 m apart, its CoM 1.5 m below them:
    the roll about the attachment line and the sideways swing are a double
    pendulum."""
    return bifilar(2.0, [0.5, 0.52, 0.05], 0.2, 0.2, 1.5, 1.0, anchor_z=1.0)


def test_interpolation_error_estimate_bounds_the_true_error():
    """The shifted-stencil estimate against an analytic signal with a strong
    7th harmonic (roots found on the function itself by brentq): it covers
    the true error of every crossing and is not looser than 50x."""
    from scipy.optimize import brentq

    from bifilar import integrators as itg

    def sig(t):
        return np.sin(t) + 0.2 * np.sin(7 * t + 0.3)

    dt = 2 * np.pi / 24  # 24 samples per fundamental period: ~3.4 per cycle of the harmonic
    t = np.arange(0, 40, dt)
    c = sig(t)
    col, tx, k = itg.sampled_crossings(c[:, None], dt)
    est = itg.crossing_interpolation_error(c, k, dt)
    true = np.array([abs(x - brentq(sig, t[j], t[j + 1], xtol=1e-15)) for x, j in zip(tx, k)])
    assert len(true) >= 5 and np.all(np.isfinite(est))
    assert np.all(est >= true)
    assert np.all(est <= 50 * true + 1e-13)


def test_period_error_covers_crossings_between_samples():
    """The double pendulum's roll at 0.3 rad is strongly anharmonic (tension
    1.8 .. 56 N, harmonics to ~20 times the fundamental): the default run
    (auto: LSODA, crossings on 64 samples per linear period) was 1.08e-7 s
    off the converged period while it stated +- 1e-8 s; its own check run
    at rtol 1e-12 shares the samples and agreed to 4e-9.  The crossings'
    interpolation error is now estimated, the run taken again with 4x the
    samples where it exceeds a tenth of the error model's bound, and what
    remains added to period_error.  The converged reference: DOP853 at rtol
    1e-13, crossings on its own continuous solution, 9e-12 from LSODA's."""
    sc = deep_com_bifilar()
    rest, ms = modes_of(sc)
    ref = simulate(sc, "roll", 0.3, 10, rest=rest, modes=ms, method="DOP853", rtol=1e-13, check=False)
    run = simulate(sc, "roll", 0.3, 10, rest=rest, modes=ms, method="auto")  # the CLI's default
    true = abs(run.period - ref.period)
    assert ref.period_error < 0.01 * run.period_error
    assert true <= run.period_error, (true, run.period_error)
    assert run.to_json()["period_error_crossings"] == run.period_error_crossings >= 0


# ---------------------------------------------------------------------------
# a body that reaches through the ceiling
# ---------------------------------------------------------------------------

THROUGH_CEILING = {
    "body": {"mass": 2.0, "inertia": {"principal": [0.05, 0.06, 0.08]},
             "bounding_box": {"min": [-0.3, -0.1, -0.1], "max": [0.3, 0.1, 0.9]}},
    "rig": {"anchors": [[-0.2, 0, 0.5], [0.2, 0, 0.5]], "attachments": [[-0.2, 0, 0.05], [0.2, 0, 0.05]],
            "lengths": [0.5, 0.5]},
}


@pytest.mark.parametrize("command", [["modes"], ["simulate", "--periods", "1", "--amplitude", "0.01"],
                                     ["tensions", "--periods", "1", "--amplitude", "0.01"]])
def test_a_body_through_the_ceiling_is_reported(tmp_path, command):
    """The CoM hangs at z = -0.05 and the box reaches 0.9 m above it, 0.35 m
    through the ceiling (the anchors at z = 0.5): every command ran silently
    (exit 0, no word); now one warning line naming body.bounding_box, and the
    JSON document as before."""
    f = tmp_path / "c.yaml"
    f.write_text(json.dumps(THROUGH_CEILING))
    res = CliRunner().invoke(main, [command[0], str(f), "--json", *command[1:]])
    assert res.exit_code == 0, res.stderr
    json.loads(res.stdout)
    lines = [ln for ln in res.stderr.splitlines() if "ceiling" in ln]
    assert len(lines) == 1 and lines[0].startswith("warning: body: ") and "body.bounding_box" in lines[0]
    assert "0.35 m above" in lines[0]
    # the same box 0.5 m lower stays below the ceiling: no warning
    low = json.loads(json.dumps(THROUGH_CEILING))
    low["body"]["bounding_box"]["max"][2] = 0.4
    f.write_text(json.dumps(low))
    res = CliRunner().invoke(main, [command[0], str(f), "--json", *command[1:]])
    assert res.exit_code == 0 and "ceiling" not in res.stderr, res.stderr
