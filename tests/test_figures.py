"""Figures (bifilar/figures/): the one package that draws.

Every figure family writes a valid file in the format its name ends in;
a failed draw leaves the user's file untouched and no temporary file behind;
the data the figures of ``invert`` and ``sweep`` are given is checked
against independent numbers; each command's ``--plot`` refuses a name it
cannot write before any work (exit 2, one line); and no module outside the
package imports matplotlib or the CLI."""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from click.testing import CliRunner

from bifilar import figures
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.cli import main
from bifilar.config import load_scene
from bifilar.estimation.invert import invert, inversion_curves
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
from bifilar.estimation.signal import fit_period
from bifilar.studies.settings import Constraints
from bifilar.studies.shorthands import ParamSpec
from bifilar.studies.sweep_output import sweep_figure_data

from conftest import CONFIGS, ROOT

PLATE = CONFIGS / "thesis_plate_rest.yaml"
LIN2 = CONFIGS / "thesis_lin2_pitch.yaml"


def valid_image(path: Path) -> bool:
    """The file is a complete image of the format its name ends in."""
    data = path.read_bytes()
    suffix = path.suffix.lower()
    if suffix == ".png":
        return data[:8] == b"\x89PNG\r\n\x1a\n" and data[-8:-4] == b"IEND"
    if suffix == ".pdf":
        return data[:5] == b"%PDF-" and data.rstrip().endswith(b"%%EOF")
    if suffix == ".svg":
        return ET.fromstring(data).tag.endswith("svg")
    raise AssertionError(suffix)


def listing(d: Path) -> list[str]:
    return sorted(p.name for p in d.iterdir())


# --------------------------------------------------------------------------- the families, each format


def damped(t, T=1.3, zeta=0.01):
    w = 2 * math.pi / T
    return 0.5 + np.exp(-zeta * w * t) * np.cos(w * t + 0.3)


def _simulation(path):
    t = np.linspace(0.0, 4.0, 401)
    res = SimpleNamespace(t=t, coordinate=0.05 * np.sin(2 * np.pi * t / 1.5), coordinate_name="rot_z",
                          crossings=np.array([0.0, 1.5, 3.0]), period=1.5, mode="torsion",
                          tensions=np.column_stack([566 + np.cos(t), 566 - np.cos(t)]))
    figures.plot_simulation(path, res, "plate")


def _signal(path):
    t = np.arange(0, 10, 0.01)
    y = damped(t) + 0.01 * np.random.default_rng(1).standard_normal(t.size)
    figures.plot_fit(path, fit_period(t, y, t_start=1.0, model="viscous"), t, y, title="synthetic")


def _inversion(path):
    x = np.linspace(250.0, 270.0, 41)
    panels = [{"x": x, "linear": np.sqrt(x / 260.0) * 1.5, "nonlinear": np.sqrt(x / 260.0) * 1.51,
               "small_angle": None, "measured": 1.5, "measured_std": 1e-3, "estimate": 260.0, "estimate_std": 0.5,
               "amplitude": 0.1, "unknown": "Izz", "unit": "kg m^2", "title": f"reference: mode {k}"}
              for k in range(4)]  # two rows of panels, two left empty
    figures.plot_inversion(path, panels)


def _sweep_data(layout):
    rng = np.random.default_rng(3)
    n = 6
    pv = {"spacing": np.repeat([4.0, 5.0], 3), "length": np.tile([3.0, 4.0, 5.0], 2)}
    params = [("spacing", "m", np.array([4.0, 5.0])), ("length", "m", np.array([3.0, 4.0, 5.0]))]
    if layout == "line":
        pv = {"spacing": np.linspace(4.0, 5.0, n)}
        params = [("spacing", "m", pv["spacing"])]
    s = {c: rng.uniform(1e-3, 1e-2, n) for c in ("Ixx", "Izz")}
    s["Ixx"][2] = np.nan  # an invalid point
    return {"layout": layout, "params": params, "param_values": pv, "components": ["Ixx", "Izz"],
            "rel_sigma": s, "bias": {c: {m: rng.normal(0, 1e-2, n) for m in ("small_angle", "thesis", "linear")}
                                     for c in ("Ixx", "Izz")},
            "separation": rng.uniform(0.05, 0.3, n), "tension_rest": np.full(n, 560.0),
            "tension_peak": np.linspace(570, 620, n), "tension_min": np.full(n, 550.0),
            "depth_rest": np.full(n, 4.0), "depth_max": np.full(n, 4.1), "objective": s["Izz"],
            "feasible": np.array([True, True, False, True, False, True]),
            "limits": {"max_tension": 600.0, "max_depth": None, "min_separation": 0.02}, "best": 1,
            "pareto_front": [0, 1], "target": "Izz"}


def _sweep(layout):
    return lambda path: figures.plot_sweep(path, _sweep_data(layout), title="synthetic sweep")


FAMILIES = {"simulation": _simulation, "signal": _signal, "inversion": _inversion,
            "sweep-line": _sweep("line"), "sweep-grid": _sweep("grid"), "sweep-points": _sweep("points")}


# every family once (the format rotating: drawing a sweep costs seconds), every format for one
CASES = [("simulation", ".png"), ("simulation", ".pdf"), ("simulation", ".svg"), ("signal", ".svg"),
         ("inversion", ".pdf"), ("sweep-line", ".png"), ("sweep-grid", ".svg"), ("sweep-points", ".pdf")]


@pytest.mark.parametrize("family, suffix", CASES)
def test_every_family_writes_a_valid_file_in_the_format_its_name_ends_in(family, suffix, tmp_path):
    out = tmp_path / f"fig{suffix}"
    FAMILIES[family](out)
    assert valid_image(out)
    assert listing(tmp_path) == [out.name]  # no temporary file left


def test_a_failed_draw_leaves_the_old_file_and_no_temporary_file(tmp_path):
    out = tmp_path / "fig.png"
    out.write_bytes(b"the user's picture")
    fig, ax = figures.new_figure()
    ax.set_title(r"$\frac{$")  # mathtext that cannot be parsed: savefig raises while drawing
    with pytest.raises(ValueError):
        figures.save(fig, out)
    assert out.read_bytes() == b"the user's picture"
    assert listing(tmp_path) == ["fig.png"]
    fig, ax = figures.new_figure()
    ax.plot([0, 1], [0, 1])
    figures.save(fig, out)  # and a good draw replaces it completely
    assert valid_image(out)


# --------------------------------------------------------------------------- the data the figures are given


def test_inversion_curves_pass_through_the_measurement_at_the_estimate():
    scene = load_scene(LIN2, warn=False)
    T = linear_modes(scene, rest_pose(scene)).get("torsion").period
    ms = MeasurementSet([Hanging("ref", scene, np.eye(3))],
                        [Measurement("torsion", T, 1e-4, "period", "--period", amplitude=0.0, cycles=10)])
    res = invert(ms, method="linear", ladder=False)
    (c,) = inversion_curves(res)
    j = res.names.index(c["unknown"])
    assert c["estimate"] == res.values[j] and c["estimate_std"] == res.std[j]
    assert c["measured"] == T and c["nonlinear"] is None  # amplitude 0: no nonlinear factor
    mid = len(c["x"]) // 2
    assert c["x"][mid] == pytest.approx(c["estimate"], rel=1e-12)
    # the model evaluated at the estimate reproduces the period it was inverted from
    assert c["linear"][mid] == pytest.approx(T, rel=1e-9)
    # and the period rises with the inertia about the torsion axis (T ~ sqrt(I) for a torsion)
    assert np.all(np.diff(c["linear"]) > 0)


def _point(spacing, rel, valid=True, feasible=True, min_t=(550.0, 551.0), depth_max=4.2):
    if not valid:
        return {"params": {"spacing": spacing}, "valid": False, "error": "slack wire"}
    return {"params": {"spacing": spacing}, "valid": True, "feasible": feasible, "objective": rel,
            "components": {"Izz": {"rel_sigma": rel, "bias": {"small_angle": 0.1, "thesis": None, "linear": 0.0}}},
            "separation": 0.25, "tension": {"rest": [560.0, 562.0], "peak": 600.0, "min": list(min_t)},
            "depth": {"rest": 4.0, "max": depth_max}}


def test_sweep_figure_data_takes_every_series_from_the_points():
    pts = [_point(4.0, 0.01), _point(4.5, 0.02, valid=False), _point(5.0, 0.03, feasible=False, min_t=(),
                                                                     depth_max=None)]
    d = sweep_figure_data(pts, [ParamSpec("spacing", (4.0, 4.5, 5.0))], False, ["Izz", "Ixx"],
                          Constraints(max_tension=610.0), {"best": 0, "target": "Izz", "pareto_front": [0]})
    nan = np.nan
    assert d["layout"] == "line" and d["params"][0][:2] == ("spacing", "m")
    np.testing.assert_array_equal(d["param_values"]["spacing"], [4.0, 4.5, 5.0])
    np.testing.assert_array_equal(d["rel_sigma"]["Izz"], [0.01, nan, 0.03])
    np.testing.assert_array_equal(d["rel_sigma"]["Ixx"], [nan, nan, nan])  # not a component of the points
    np.testing.assert_array_equal(d["bias"]["Izz"]["small_angle"], [0.1, nan, 0.1])
    np.testing.assert_array_equal(d["bias"]["Izz"]["thesis"], [nan, nan, nan])
    np.testing.assert_array_equal(d["tension_rest"], [562.0, nan, 562.0])  # the largest wire
    np.testing.assert_array_equal(d["tension_min"], [550.0, nan, nan])  # the smallest; none without a run
    np.testing.assert_array_equal(d["depth_max"], [4.2, nan, 4.0])  # the rest depth where no swing was run
    np.testing.assert_array_equal(d["feasible"], [True, False, False])
    assert d["limits"]["max_tension"] == 610.0 and d["best"] == 0 and d["target"] == "Izz"
    worst = sweep_figure_data(pts, [ParamSpec("spacing", (4.0, 4.5, 5.0))], False, ["Izz"], Constraints(),
                              {"best": None, "target": "worst of Izz"})
    assert worst["target"] is None and worst["pareto_front"] == []


# --------------------------------------------------------------------------- --plot names refused before any work


def _period_signal(tmp_path):
    t = np.arange(0, 20, 0.01)
    f = tmp_path / "sig.csv"
    np.savetxt(f, np.column_stack([t, damped(t)]), delimiter=",", header="t,gyro", comments="")
    return f


COMMANDS = {
    "simulate": lambda d: ["simulate", PLATE, "--periods", "1"],
    "period": lambda d: ["period", _period_signal(d)],
    "invert": lambda d: ["invert", LIN2, "--period", "torsion=1.7"],
    "sweep": lambda d: ["sweep", PLATE, "--param", "spacing=4:5:2", "--no-tensions"],
}


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_plot_names_that_cannot_be_written_exit_2_with_one_line(command, tmp_path):
    argv = [str(a) for a in COMMANDS[command](tmp_path)]
    before = listing(tmp_path)
    for plot, message in (("run.csv", "--plot: cannot tell the image format of 'run.csv'"),
                          ("missing/run.png", f"--plot: directory {tmp_path / 'missing'} does not exist")):
        r = CliRunner().invoke(main, [*argv, "--plot", str(tmp_path / plot)])
        lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
        assert r.exit_code == 2 and len(lines) == 1 and lines[0].startswith("error: " + message), r.stderr
        assert listing(tmp_path) == before


# --------------------------------------------------------------------------- where matplotlib may be imported


def _sources():
    return [p for p in (ROOT / "bifilar").rglob("*.py")]


def test_only_the_figures_package_imports_matplotlib():
    imp = re.compile(r"^\s*(import|from)\s+matplotlib\b", re.M)
    offenders = [str(p.relative_to(ROOT)) for p in _sources()
                 if "figures" not in p.relative_to(ROOT / "bifilar").parts and imp.search(p.read_text())]
    assert offenders == []
    assert any(imp.search(p.read_text()) for p in (ROOT / "bifilar" / "figures").glob("*.py"))  # the check sees it


def test_no_module_below_the_cli_imports_it():
    imp = re.compile(r"^\s*(from\s+(\.+cli\b|bifilar\.cli\b|\.+\s+import\s+cli\b)|import\s+bifilar\.cli\b)", re.M)
    pkg = ROOT / "bifilar"
    offenders = [str(p.relative_to(ROOT)) for p in _sources()
                 if p.relative_to(pkg).parts[0] not in ("cli", "__main__.py") and imp.search(p.read_text())]
    assert offenders == []
    assert imp.search((pkg / "__main__.py").read_text())  # the check sees an import of the CLI


def test_importing_the_figures_loads_no_matplotlib():
    # the other modules never import it (the scan above); the figures only inside their functions
    code = ("import sys, json\n"
            "import bifilar.figures, bifilar.figures.thesis\n"
            "print(json.dumps(sorted(m for m in sys.modules if m.startswith('matplotlib'))))\n")
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.strip().splitlines()[-1]) == []
