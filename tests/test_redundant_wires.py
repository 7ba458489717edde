"""Rigs with 3, 4 and 5 wires all taut, vertical and leaning: the 4- and
5-wire ones are statically indeterminate (the wires are dependent at rest,
so J M^-1 J^T is singular) and run on the minimum-norm multipliers
(docs/design.md).  Checked against conservation laws (constraints, energy),
statics (tensions balance gravity, and equal the rest pose's least-squares
tensions, an independent formulation), the linear periods of ``modes`` and,
for the compiled kernel, the batched array path against the float path."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from bifilar.analysis.batch import simulate_batch
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
from bifilar.cli import main
from bifilar.config import scene_from_dict
from bifilar.models import maximal as mx
from bifilar.studies import sweep as sw

MASS, G = 10.0, 9.81


def ring_cfg(n: int, anchor_radius: float, radius: float = 0.5, length: float = 2.0) -> dict:
    """n wires on a regular polygon: attachments at ``radius`` (z = 0.1 above
    the CoM), anchors at ``anchor_radius`` (equal: vertical wires; larger: the
    wires lean outwards), every wire ``length``."""
    ang = 2 * np.pi * np.arange(n) / n
    ring = np.stack([np.cos(ang), np.sin(ang)], axis=1)
    return {
        "name": f"ring {n}",
        "gravity": G,
        "body": {"mass": MASS, "inertia": {"principal": [1.0, 2.0, 2.5]}},
        "rig": {"anchors": [[float(x), float(y), 0.0] for x, y in anchor_radius * ring],
                "attachments": [[float(x), float(y), 0.1] for x, y in radius * ring],
                "lengths": [length] * n},
    }


CASES = [(n, ra) for n in (3, 4, 5) for ra in (0.5, 0.9)]
IDS = [f"{n}wires-{'vertical' if ra == 0.5 else 'leaning'}" for n, ra in CASES]


@pytest.mark.parametrize("n, ra", CASES, ids=IDS)
def test_tensions_at_rest_balance_gravity_and_match_the_rest_pose(n, ra):
    scene = scene_from_dict(ring_cfg(n, ra), warn=False)
    rest = rest_pose(scene)
    P = mx.params_from_scenes(scene)
    y = mx.pack(rest.com, rest.q)
    T = mx.tensions(y, P)
    d = mx.kinematics(y, P)["d"]  # anchor -> attachment
    u = -d / np.linalg.norm(d, axis=1, keepdims=True)  # pull on the body
    F = (T[:, None] * u).sum(axis=0)
    np.testing.assert_allclose(F, [0, 0, MASS * G], atol=1e-9 * MASS * G)
    arm = mx.kinematics(y, P)["Rp"]
    np.testing.assert_allclose(np.cross(arm, T[:, None] * u).sum(axis=0), 0, atol=1e-9 * MASS * G)
    # the same minimum-norm tensions as the rest pose (lstsq of the equilibrium equations), equal by symmetry
    np.testing.assert_allclose(T, rest.tensions, rtol=1e-9)
    np.testing.assert_allclose(T, T.mean(), rtol=1e-9)
    # at rest nothing accelerates
    vdot, wdot, _, _ = mx.solve_dynamics(y, P)
    assert np.max(np.abs(vdot)) < 1e-9 * G and np.max(np.abs(wdot)) < 1e-9 * G


@pytest.mark.parametrize("n, ra", CASES, ids=IDS)
def test_torsion_runs_with_constraints_energy_and_period_of_modes(n, ra):
    scene = scene_from_dict(ring_cfg(n, ra), warn=False)
    res = simulate(scene, mode="torsion", amplitude=0.02, periods=3)
    L = 2.0
    assert res.max_constraint_violation < 1e-9 * L
    assert res.energy_drift < 1e-6
    # amplitude 0.02 rad: the nonlinear period differs from the linear one by ~theta^2/16 ~ 3e-5
    assert res.period == pytest.approx(res.linear_period, rel=2e-4)
    rest = rest_pose(scene)
    # the tensions stay near the rest ones (small swing) and positive
    assert np.all(res.tension_min > 0.9 * rest.tensions) and np.all(res.tension_max < 1.1 * rest.tensions)


@pytest.mark.parametrize("n", [4, 5])
def test_swing_of_parallel_wires_keeps_every_wire_at_its_length(n):
    # vertical parallel wires: a swing keeps every wire parallel, a genuine motion of the rigid-wire rig
    scene = scene_from_dict(ring_cfg(n, 0.5), warn=False)
    res = simulate(scene, mode="swing-x", amplitude=0.05, periods=2)
    assert res.max_constraint_violation < 1e-9 * 2.0
    assert res.energy_drift < 1e-6
    # a pure swing of parallel wires is a simple pendulum of length L: T = 2 pi sqrt(L/g) (1 + a^2/16 + ...),
    # a = 0.05 m / 2 m = 0.025 rad
    assert res.linear_period == pytest.approx(2 * np.pi * np.sqrt(2.0 / G), rel=1e-9)
    assert res.period == pytest.approx(res.linear_period * (1 + 0.025**2 / 16), rel=1e-5)


@pytest.mark.parametrize("n", [4, 5])
def test_batched_kernel_equals_the_float_kernel(n):
    """The array path of the minimum-norm solve (a batch of scenes) against
    the float path (one state at a time)."""
    scenes = [scene_from_dict(ring_cfg(n, ra), warn=False) for ra in (0.5, 0.7, 0.9)]
    P = mx.params_from_scenes(scenes)
    rng = np.random.default_rng(1)
    Y = []
    for s in scenes:
        r = rest_pose(s)
        Y.append(mx.pack(r.com + 1e-3 * rng.standard_normal(3), r.q, 0.01 * rng.standard_normal(3),
                         0.01 * rng.standard_normal(3)))
    Y = np.array(Y)
    batch = mx.rhs(0.0, Y, P)
    single = np.array([mx.rhs(0.0, Y[i], mx.params_from_scenes(scenes[i])) for i in range(3)])
    np.testing.assert_allclose(batch, single, rtol=1e-9, atol=1e-12)
    runs = simulate_batch(scenes, mode="torsion", amplitude=0.02, periods=2)
    for run in runs:
        assert run.period == pytest.approx(run.linear_period, rel=2e-4)
        assert run.max_constraint_violation < 1e-9 * 2.0


def cli(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.mark.parametrize("n, ra", [(4, 0.5), (5, 0.9)], ids=["4wires-vertical", "5wires-leaning"])
def test_cli_tensions_sweep_and_invert_run_on_dependent_wires(n, ra, tmp_path):
    import yaml

    cfg = ring_cfg(n, ra)
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(cfg))
    r = cli("tensions", path, "--json")
    assert r.exit_code == 0, r.output
    scene = scene_from_dict(cfg, warn=False)
    rest = rest_pose(scene)
    T_lin = linear_modes(scene, rest).get("torsion").period
    # a tiny sweep point (its sensitivities perturb one wire at a time: no broadcast error between
    # the neighbour's 2 modes and the rig's 3)
    st = sw.resolve_settings(cfg, tensions=False)
    p = sw.evaluate_point(cfg, "test", {"length": 1.9}, st)
    assert p["valid"], p["error"]
    assert p["periods"]["torsion"] > 0
    # invert the torsion period the model predicts: Izz comes back
    m = tmp_path / "m.yaml"
    m.write_text(f"config: {path}\nsolve_for: [Izz]\nmeasurements:\n  - mode: torsion\n    period: {T_lin!r} +- 0.0005\n")
    r = cli("invert", "--measurements", m, "--json", "--no-ladder")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["inertia"]["Izz"]["value"] == pytest.approx(2.5, rel=1e-6)
    # one wire's length has no derivative with rigid dependent wires: said, and left out of the budget
    assert any("dependent wires" in w and "length.1" in w for w in doc["warnings"])

