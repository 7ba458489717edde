"""``simulate(..., coordinate=False)`` (what ``bifilar simulate`` runs without
``--plot``): the timed coordinate is computed only on the rows the crossings'
check reads (:func:`~bifilar.analysis.run_accuracy.crossing_rows`), and every
figure the run reports is the same, bit for bit, as with the coordinate at
every sample (docs/design.md, "Session 13, perf15").

The references are independent of the shortcut: the full coordinate
(``coordinate=True``, the path every release before it took) and, for the
rows, a uniformly sampled sine whose crossings are placed at the record's
ends, where the degree-7 stencils are shifted inside the record."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from bifilar.analysis import run_accuracy as ra
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
from bifilar.cli import main
from bifilar.config import load_scene
from conftest import CONFIGS


def _windowed(t, c, crossings):
    """``c`` on :func:`crossing_rows`' rows, NaN elsewhere."""
    out = np.full(len(c), np.nan)
    for rows in ra.crossing_rows(t, crossings):
        out[rows] = c[rows]
    return out


@pytest.mark.parametrize("first, last", [(0.3, 384.3), (1.3, 385.3), (15.7, 399.7), (40.2, 232.2)])
def test_the_crossings_rows_give_the_same_error(first, last):
    # a sine (period 64 samples) whose first and last upward crossings sit `first` and `last` samples in: at
    # the record's ends the check's stencils are shifted inside it, so the rows it reads are not centred there
    dt = 0.01
    t = np.arange(401) * dt
    c = np.sin(2 * np.pi * (t / dt - first) / 64.0) + 0.01 * np.sin(2 * np.pi * 5 * (t / dt - first) / 64.0)
    tc = [first * dt, last * dt]
    full = ra.crossing_period_error(t, c, tc)
    assert np.isfinite(full) and full > 0  # (a real estimate, not the NaN of a crossing the samples miss)
    assert ra.crossing_period_error(t, _windowed(t, c, tc), tc) == full


def test_fewer_rows_would_change_the_error(monkeypatch):
    # the margin is what the check reads: with fewer rows its stencils reach past them (NaN), and the error
    # it gives is no longer the full record's: 4 rows in the middle of the record, 7 at its start, where the
    # stencils are shifted inside it
    dt = 0.01
    t = np.arange(401) * dt
    for first, last, rows in ((40.2, 232.2, 4), (0.3, 384.3, 7)):
        c = np.sin(2 * np.pi * (t / dt - first) / 64.0)
        tc = [first * dt, last * dt]
        full = ra.crossing_period_error(t, c, tc)
        monkeypatch.setattr(ra, "CROSSING_ROWS", rows)
        assert ra.crossing_period_error(t, _windowed(t, c, tc), tc) != full


def _figures(res) -> dict:
    d = {k: v for k, v in vars(res).items() if k not in ("runtime", "coordinate")}
    return {k: (np.asarray(v).tobytes() if isinstance(v, np.ndarray) else repr(v)) for k, v in d.items()}


@pytest.mark.parametrize("cfg, mode, amplitude", [("thesis_plate_rest.yaml", "torsion", 0.05),
                                                  ("solar_boat.yaml", "roll", 0.3),
                                                  ("trifilar_kth.yaml", "torsion", 0.2)])
def test_summary_run_reports_the_same_figures(cfg, mode, amplitude):
    scene = load_scene(CONFIGS / cfg)
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    kw = dict(rest=rest, modes=ms, rtol=1e-9, method="auto")
    full = simulate(scene, mode, amplitude, 6, **kw)
    summary = simulate(scene, mode, amplitude, 6, coordinate=False, **kw)
    assert summary.coordinate is None and full.coordinate is not None
    assert _figures(summary) == _figures(full)
    assert full.period_error_crossings > 0  # the crossings' check ran on the rows it reads


def test_the_cli_prints_the_full_runs_figures():
    scene = load_scene(CONFIGS / "thesis_plate_rest.yaml")
    full = simulate(scene, "torsion", 0.05, 4, rtol=1e-9, method="auto").to_json()
    out = CliRunner().invoke(main, ["simulate", str(CONFIGS / "thesis_plate_rest.yaml"), "--mode", "torsion",
                                    "--amplitude", "0.05", "--periods", "4", "--rtol", "1e-9", "--json"])
    assert out.exit_code == 0, out.output
    doc = json.loads(out.stdout)
    for d in (doc, full):
        d["integrator"].pop("runtime_s")
    assert doc == json.loads(json.dumps(full))
