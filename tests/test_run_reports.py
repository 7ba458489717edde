"""What a run reports about itself: the energy drift covers every sample it
returns, and a run with no period says why (no motion, stopped, too short)."""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis.batch import simulate_batch
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.simulate import simulate
from bifilar.config import load_scene
from bifilar.models import maximal as mx

from conftest import ROOT

PLATE = ROOT / "configs" / "thesis_plate_rest.yaml"
DRONE = ROOT / "configs" / "drone_parallel.yaml"


def _drift_at(scene, rest, Y):
    """max |E - E0| / |E0 - E_rest| of states Y (k, 13), from the model's energy (not the run's health code)."""
    E = mx.energy(Y, mx.params_from_scenes(scene))
    return float(np.max(np.abs(E - E[0])) / abs(E[0] - scene.mass * scene.gravity * rest.com[2]))


@pytest.mark.parametrize("path", [PLATE, DRONE])
def test_energy_drift_covers_the_returned_samples(path):
    # DOP853's dense output adds 10-20x the drift at its steps: it was reported at the steps only
    scene = load_scene(path, warn=False)
    rest = rest_pose(scene)
    res = simulate(scene, "torsion", 0.05, 4, rest=rest, method="DOP853", rtol=1e-10)
    assert res.energy_drift >= (1 - 1e-4) * _drift_at(scene, rest, res.y)
    run = simulate_batch([scene], "torsion", 0.05, 4, rtol=1e-10, samples_per_period=64, method="dop853")[0]
    assert run.energy_drift >= (1 - 1e-4) * _drift_at(scene, rest, run.y)


def test_amplitude_zero_says_there_is_no_motion_not_integrate_longer():
    scene = load_scene(PLATE, warn=False)
    for res in (simulate(scene, "torsion", 0.0, 1, method="DOP853"), simulate(scene, "torsion", 0.0, 1),
                simulate_batch([scene], "torsion", 0.0, 1)[0]):
        assert res.period is None
        assert any(w.startswith("amplitude 0: the body starts at rest") for w in res.warnings), res.warnings
        assert not any("integrate longer" in w for w in res.warnings)


def test_a_run_stopped_at_the_release_does_not_ask_for_a_longer_run():
    # the quadcopter swung by 1.48 m of its 1.5 m wires: wire 2 pushes at the release (tests/test_cli.py)
    scene = load_scene(DRONE, warn=False)
    for res in (simulate(scene, "swing-y", 1.48, 2, on_slack="stop", method="DOP853"),
                simulate(scene, "swing-y", 1.48, 2, on_slack="stop")):
        assert res.period is None and any(w.startswith("run stopped at t = 0 s") for w in res.warnings)
        assert any("before the run stopped" in w for w in res.warnings), res.warnings
        assert not any("integrate longer" in w for w in res.warnings)
