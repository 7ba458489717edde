"""A start on a symmetric subspace of a symmetric rig whose orbit is unstable
across it (docs/design.md, "symcheck, session 16").

The thesis plate's swing-y at 1.5 m, released in the plate's symmetry plane,
stays in it only up to the start's rounding (3e-16 m, another on another
BLAS kernel), which grows by 7.3 a period: over 17 periods the period moved
by 1e-6 s between kernels against a stated ``period_error`` of 5.9e-9 s, and
nothing in the run showed it.  The references here are runs from starts
moved off the plane by 1e-15 .. 1e-13 (m along x, rad about y and z: the
directions the mirror reverses, tangent to the wires there), which stand in
for other kernels: the kernels' starts differ by 3e-16 m, and a smaller
offset leaves the plane later, so these are as far as a kernel's rounding
and further.  They are made by the batched engine directly, not by the code
under test."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from bifilar.analysis import symmetry_check as sy
from bifilar.analysis.batch import run_one
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import initial_state, simulate
from bifilar.cli import main
from bifilar.config import load_scene, scene_from_dict
from bifilar.models import maximal as mx
from bifilar.rotations import quat_multiply, rotvec_to_quat
from conftest import CONFIGS, PLATE_I, trapezoid

PLATE = CONFIGS / "thesis_plate_rest.yaml"


@pytest.fixture(scope="module")
def plate():
    sc = load_scene(PLATE)
    rest = rest_pose(sc)
    return sc, rest, linear_modes(sc, rest)


def off_plane(y0, eps, a=(1.0, 0.6, -0.8)):
    """The plate's start ``y0`` moved out of its symmetry plane (x = 0): by
    eps a[0] m along x and a rotation (0, eps a[1], eps a[2]) rad."""
    y = np.array(y0, float)
    y[0] += eps * a[0]
    y[3:7] = quat_multiply(rotvec_to_quat(np.array([0.0, eps * a[1], eps * a[2]])), y[3:7])
    return y


def lopsided():
    """A plate on three wires of no pattern: no symmetry."""
    return scene_from_dict({
        "gravity": 9.81,
        "body": {"mass": 100.0, "inertia": {"principal": list(PLATE_I)}},
        "rig": {"anchors": [[0, -5, 0], [0, 5, 0], [3, 1, 0]],
                "attachments": [[0, -2.5, 0.5], [0, 2.5, 0.5], [1, 0.7, 0.5]], "lengths": [5.0, 5.0, 4.6]},
    })


def test_the_symmetries_found_are_the_models():
    """Every symmetry found on a shipped config is one of the model's own
    right-hand side, f(S y) = S f(y) at a generic state (off rest, off the
    wires, moving), to 1e-9 of the rates: the state action (quaternion's
    sign, body-axes rates) is right.  The plate has its two mirrors and the
    half turn (one anchor moved 0.3 m across keeps them, turned by 1.7
    degrees: the anchors still lie on a line through the rest CoM's
    vertical); a three-wire rig of no pattern has none."""
    rng = np.random.default_rng(3)
    for path in sorted(CONFIGS.glob("*.yaml")):
        if path.name.startswith("measurements"):
            continue
        sc = load_scene(path)
        rest = rest_pose(sc)
        f = mx.compiled_kernel(sy.shifted_params(sc, rest))
        L = float(np.max(sc.lengths))
        for s in sy.rig_symmetries(sc, rest):
            y = np.r_[0.02 * L * rng.standard_normal(3), rest.q, 0.3 * rng.standard_normal(6)]
            y[3:7] = quat_multiply(rotvec_to_quat(0.05 * rng.standard_normal(3)), rest.q)
            a, b = np.array(f(*(s.sigma @ y).tolist())), s.sigma @ np.array(f(*y.tolist()))
            assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(b)), (path.name, s.name)
        if path == PLATE:
            assert sorted(s.name.split()[1] for s in sy.rig_symmetries(sc, rest)) == ["mirror", "mirror", "turn"]
    lop = lopsided()
    assert sy.rig_symmetries(lop, rest_pose(lop)) == []
    turned = trapezoid()
    turned.anchors[0, 0] = 0.3
    assert sorted(s.name for s in sy.rig_symmetries(turned, rest_pose(turned))) == [
        "the mirror across the vertical plane normal to 1.718 deg from x",
        "the mirror across the vertical plane normal to 91.72 deg from x", "the turn by 180 deg about the vertical"]


def test_the_multiplier_is_the_growth_of_an_offset(plate):
    """The Floquet multiplier across the plane (from the run's own samples
    over one period) against the nonlinear motion from a start 1e-12 off:
    the offset's largest size over a period grows by it, period after
    period (7.34 from the 3rd to the 5th; 1 % covers the sampled maxima)."""
    sc, rest, ms = plate
    r = simulate(sc, "swing-y", 1.5, 6, rest=rest, modes=ms, method="DOP853", rtol=1e-11, check=False)
    assert r.period_symmetry is None  # check=False: nothing computed
    com = np.r_[rest.com, np.zeros(10)]
    tr = sy.start_symmetry(sy.rig_symmetries(sc, rest), r.y[0] - com, np.ones(13))
    sizes = sy.natural_sizes(5.0, 2 * np.pi / ms.get("swing-y").period)
    step = 1e-7 * (np.abs(tr.basis.T) @ sizes)
    rho = np.max(np.abs(sy.transverse_growth(sy.shifted_params(sc, rest), r.t, r.y - com, r.period, tr.basis, step)))
    p = simulate(sc, "swing-y", 1.5, 6, rest=rest, modes=ms, y0=off_plane(r.y[0], 1e-12), method="DOP853",
                 rtol=1e-11, check=False)
    across = [0, 5, 6, 7, 11, 12]  # x, q_y, q_z, v_x, w_y, w_z: what the mirror reverses, in natural units
    rel = np.max(np.abs((p.y - com)[:, across] / sizes[across]), axis=1)
    size = [np.max(rel[(p.t >= k * r.period) & (p.t < (k + 1) * r.period)]) for k in range(5)]
    assert rho == pytest.approx(7.33, rel=0.01)
    for k in (3, 4):
        assert size[k] / size[k - 1] == pytest.approx(rho, rel=0.01)


@pytest.mark.parametrize("periods", [16, 17])
def test_an_unstable_symmetric_orbit_states_what_other_starts_give(plate, periods):
    """17 periods: the task's case (before: period_error 5.9e-9 s, no
    warning, while starts 1e-15 .. 1e-13 off, as other kernels', moved the
    period by up to 4e-3 s).  Now period_error covers every reference (0.6 of it at
    most), and one line says the run is reproducible over its first 11
    periods and names --periods 10 (test below: no warning there).  16 and
    17: the two means' difference alone (the check run's period) misses the
    references by 0.2 % and 4 %, and at 16 the sum of its cycles'
    differences too (offset_error's last term, one cycle's difference)."""
    sc, rest, ms = plate
    md = ms.get("swing-y")
    args = ["simulate", str(PLATE), "--mode", "swing-y", "--amplitude", "1.5", "--periods", str(periods), "--json"]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    y0 = initial_state(sc, rest, md, 1.5)
    diffs = [abs(run_one(sc, rest, md, 1.5, periods, 1e-10, samples_per_period=64, y0=off_plane(y0, e, a)).period
                 - doc["period"]) for e in (1e-15, -1e-15, 1e-14, 1e-13, -1e-13) for a in ((1.0, 0.6, -0.8),
                                                                                       (-0.3, 1.0, 0.5))]
    model = 15 * 1e-10 * doc["period"] + doc["period_error_drift"] + doc["period_error_crossings"]
    assert max(diffs) > 1e4 * model  # the old bound (the model's: 5.9e-9 s) fails by far
    assert max(diffs) <= doc["period_error"]
    assert doc["period_error"] == doc["period_error_symmetry"]
    sym = doc["period_symmetry"]
    assert sym["multiplier"] == pytest.approx(7.33, rel=0.01) and sym["growth"] > 1e12
    assert sym["check"]["offset"] == 1e-12 and sym["check"]["cycles"] == doc["cycles"]
    w = [x for x in doc["warnings"] if "unstable symmetric orbit" in x]
    assert len(w) == 1 and "\n" not in w[0] and "(--periods 10)" in w[0]
    assert "reproducible over the first 11 of" in w[0]


def test_stable_or_short_symmetric_runs_are_left_alone(plate):
    """Must not cry wolf.  The plate's default runs (0.05, 10 periods) start
    on symmetric subspaces too: the torsion's and the swing-x's orbits are
    stable (largest multiplier 1 within 1e-4), the swing-y's grows by 1.055
    a period (1.7 over the run): no check run, no warning, period_error and
    the run itself as without the check.  The swing-y at 1.5 m over 10
    periods grows an offset by 1e9: checked, and its check agrees (starts
    1e-15 .. 1e-13 off move its period by 4e-13 s at most, 1e-4 of the
    bound): nothing added either."""
    sc, rest, ms = plate
    for mode, amp, periods in (("torsion", 0.05, 10), ("swing-x", 0.05, 10), ("swing-y", 0.05, 10),
                               ("swing-y", 1.5, 10)):
        r = simulate(sc, mode, amp, periods, rest=rest, modes=ms, method="auto")
        bare = simulate(sc, mode, amp, periods, rest=rest, modes=ms, method="auto", check=False)
        sym = r.period_symmetry
        assert sym is not None and r.nfev == bare.nfev and r.period == bare.period
        assert r.period_error == bare.period_error and r.period_error_symmetry == 0.0
        assert r.warnings == bare.warnings
        if amp == 0.05:
            assert sym["check"] is None and sym["growth"] < 2.0
            assert abs(sym["multiplier"] - 1.0) < (1e-4 if mode != "swing-y" else 0.06)
        else:
            assert sym["growth"] > 1e6 and sym["check"]["difference"] < 1e-3 * r.period_error
            assert sym["check"]["error"] == 0.0


def test_an_asymmetric_rig_is_not_checked():
    """A rig with no symmetry: nothing computed; the JSON says so (null, 0)."""
    lop = trapezoid()
    lop.anchors[0, 0] = 0.3
    r = simulate(lop, "swing-y", 0.5, 3, method="auto")
    assert r.period_symmetry is None
    doc = r.to_json()
    assert doc["period_symmetry"] is None and doc["period_error_symmetry"] == 0.0


def test_an_explicit_start_without_a_mode_is_checked(plate):
    """An explicit start state without a mode (session 17: the library's
    ``simulate(y0=..., mode=None)``; before, not checked): the plate's
    swing-y start at 1.5 m given as a state, over 15 swing periods, timed on
    the coordinate that moves most (y).  Before: period_error 1.3e-9 s,
    while starts 1e-13 off the plane move the period by 2.5e-3 s (the
    references: the batched engine from those starts, timed on y); now the
    check's 7e-3 s covers them, and its check run times the same
    coordinate over as many cycles."""
    sc, rest, ms = plate
    md = ms.get("swing-y")
    y0 = initial_state(sc, rest, md, 1.5)
    r = simulate(sc, None, 1.5, 1, rest=rest, modes=ms, y0=y0, t_end=15 * md.period)
    assert r.mode is None and r.coordinate_name == "y"
    diffs = [abs(run_one(sc, rest, md, 1.5, 15, 1e-10, samples_per_period=64, y0=off_plane(y0, e)).period - r.period)
             for e in (1e-13, -1e-13)]
    assert max(diffs) > 1e3 * 1.3e-9  # the old statement (the integration's error model alone)
    assert max(diffs) <= r.period_error == r.period_error_symmetry
    assert r.period_symmetry["check"]["cycles"] == len(r.crossings) - 1
    assert len([w for w in r.warnings if "unstable symmetric orbit" in w]) == 1


def test_a_kane_start_given_as_angles_is_checked(plate):
    """``--model kane --theta`` without ``--mode`` (session 17): the plate
    released at theta2 = 1.0198877 rad in its plane (the swing-y at 1.5 m:
    theta1 = theta4 = 0, theta3 = pi/2), 23.2 torsion periods (the unit of
    --periods without a mode), 13 swing cycles timed on y.  Before:
    period_error 2.6e-9 s and no warning, while starts 1e-13 off the plane
    move the period by 5e-8 s (the default model's batched engine from the
    same start, its angles mapped to a state, and from starts 1e-13 off);
    now covered."""
    sc, rest, ms = plate
    md = ms.get("swing-y")
    theta = "0,1.0198877388915517,1.5707963267948966,0"
    periods = 13 * md.period / ms.get("torsion").period + 0.2
    args = ["simulate", str(PLATE), "--model", "kane", "--theta", theta, "--periods", f"{periods:.4f}", "--json"]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    assert doc["mode"] is None and doc["timed_coordinate"] == "y" and doc["cycles"] == 13
    y0 = initial_state(sc, rest, md, 1.5)
    diffs = [abs(run_one(sc, rest, md, 1.5, 13, 1e-10, samples_per_period=64, y0=off_plane(y0, e)).period
                 - doc["period"]) for e in (1e-13, -1e-13)]
    assert max(diffs) > 5.0 * 2.6e-9
    assert max(diffs) <= doc["period_error"] == doc["period_error_symmetry"]
    assert doc["period_symmetry"]["check"]["cycles"] == doc["cycles"]


def test_a_sweep_point_warns_of_an_unstable_symmetric_run(plate):
    """A sweep point's runs (the batched engine, session 17): at the
    default 3 periods nothing is computed (a growth of 1e6 would need a
    multiplier of 100); the plate's swing-y at 1.5 m over 15 periods grows
    an offset by 7.33^15 = 1e13, and the point now says so in one line
    naming the --periods below the gate (before: nothing, while the point's
    nonlinear period moved between BLAS kernels beyond its period_error, and
    starts 1e-13 off the plane move it by ~2e-3 s against 6e-7 s)."""
    from bifilar.config import read_yaml
    from bifilar.studies import sweep as sw

    sc, rest, ms = plate
    md = ms.get("swing-y")
    cfg = read_yaml(PLATE)
    params = {"body.mass": 100.0}
    pts = {p: sw.evaluate_point(cfg, str(PLATE), params, sw.resolve_settings(cfg, components=["Ixx"], amplitude=1.5,
                                                                              periods=p)) for p in (3.0, 15.0)}
    said = {p: [w for w in pt["warnings"] if "released symmetric" in w] for p, pt in pts.items()}
    assert said[3.0] == []
    assert len(said[15.0]) == 1 and said[15.0][0].startswith("swing-y: ") and "(--periods 6)" in said[15.0][0]
    run = pts[15.0]["runs"]["swing-y"]
    y0 = initial_state(sc, rest, md, 1.5)
    diffs = [abs(run_one(sc, rest, md, 1.5, 15, 1e-8, y0=off_plane(y0, e)).period - run["period"])
             for e in (1e-13, -1e-13)]
    assert max(diffs) > 100 * run["period_error"]  # what the warning is for
