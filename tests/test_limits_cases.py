"""The limits of what a body can be and what a study can give: the triangle
inequality's one allowance for rounded moments (config loader = invert's
admissible set), 95 % intervals cut at the physical limit, and a sweep
with no valid point.  Expected values come from forward computations
(``linear_modes`` of the stated tensor) and closed-form limits, never from
the code under test."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.config import scene_from_dict
from bifilar.errors import ConfigErrors
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
from bifilar.estimation.problem import admissible, admissible_interval

_IDX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}

#: the README's plate, moments rounded to 2 decimals: 208.33 + 52.08 = 260.41
#: < 260.42 by rounding only (3.8e-5 of I3), hung with its CoM 0.5 m below
#: the attachment line (so that every input has a derivative)
README_PLATE = [208.33, 52.08, 260.42]


def plate(principal=README_PLATE, h=0.5):
    return scene_from_dict({
        "gravity": 9.81,
        "body": {"mass": 100.0, "inertia": {"principal": list(principal)}},
        "rig": {"anchors": [[0, -5, 0], [0, 5, 0]], "attachments": [[0, -2.5, h], [0, 2.5, h]],
                "lengths": [5.0, 5.0]},
    }, warn=False)


def with_component(scene, comp, x):
    I = scene.inertia.copy()
    i, j = _IDX[comp]
    I[i, j] = I[j, i] = x
    return replace(scene, inertia=I)


def period_of(scene, label):
    return linear_modes(scene, rest_pose(scene)).get(label).period


def one(scene, label, T, std, amplitude=0.0):
    return MeasurementSet([Hanging("h", scene, np.eye(3))],
                          [Measurement(label, float(T), std, "period", "--period", amplitude=amplitude)])


# --------------------------------------------------------------------------- 2. one triangle rule


def _loader_accepts(principal) -> bool:
    try:
        plate(principal)
    except ConfigErrors:
        return False
    return True


@pytest.mark.parametrize("excess", [0.0, 3e-5, 9e-5, 1.1e-4, 3e-4, 1e-2])
def test_loader_and_invert_share_one_triangle_rule(excess):
    """A tensor the config loader accepts is admissible to invert, and one
    it refuses is not (both sides of the allowance, for rounding of
    5-digit moments: I1 + I2 may fall short of I3 by up to ~1e-4 of I3)."""
    I3 = 260.0
    principal = [200.0, 60.0 - excess * I3, I3]  # I1 + I2 = (1 - excess) I3
    assert _loader_accepts(principal) == admissible(np.diag(principal))
    assert _loader_accepts(principal) == (excess <= 1e-4)


def test_admissible_interval_ends_where_admissible_does():
    """The closed form of the admissible interval (a 3x3 pencil) ends
    exactly where the eigenvalue test changes its mind (the positive-definite
    end of a product, Ixy here, is open: a singular tensor is no body)."""
    I = np.diag(README_PLATE)
    for comp in ("Ixx", "Iyy", "Izz", "Ixy"):
        lo, hi = admissible_interval(I, comp)
        i, j = _IDX[comp]
        w = hi - lo
        for x, inside in ((lo + 1e-9 * w, True), (hi - 1e-9 * w, True), (lo - 1e-6 * w, False), (hi + 1e-6 * w, False)):
            J = I.copy()
            J[i, j] = J[j, i] = x
            assert admissible(J) == inside, (comp, x)


@pytest.mark.parametrize("label,comp", [("pitch", "Iyy"), ("torsion", "Izz")])
def test_config_at_the_loaders_allowance_inverts_without_being_inadmissible(label, comp):
    """The README plate's own period gives back the README plate's moment:
    it was refused for Iyy ('no physical Iyy gives a period of 1.91239 s':
    invert's set ended 1e-6 from the limit, at Iyy = 52.0895) and answered
    at an 'edge of the physical set' for Izz (260.4105 instead of 260.42)."""
    s = plate()
    x_true = float(s.inertia[_IDX[comp]])
    T = period_of(s, label)
    res = invert(one(s, label, T, std=1e-5), solve_for=[comp], ladder=False)
    assert res.value(comp) == pytest.approx(x_true, rel=1e-7)
    assert not res.roots[0]["edge"]
    assert not any("triangle" in w or "edge of the physical set" in w for w in res.warnings), res.warnings


# --------------------------------------------------------------------------- 1. intervals cut at the physical limit


def test_interval_at_the_triangle_edge_is_cut_there_and_says_so(tmp_path):
    """The README plate's Iyy from its own pitch period: Izz = Ixx + Iyy
    (to rounding), so Iyy cannot be below (1 - s) Izz - Ixx (closed form,
    s = TRIANGLE_SLACK) with the other moments as given; the budget's
    interval (value +- 1.96 std) reached 51.57, past it."""
    import json

    from click.testing import CliRunner

    from bifilar.cli import main
    from bifilar.scene import TRIANGLE_SLACK

    s = plate()
    T = period_of(s, "pitch")
    res = invert(one(s, "pitch", T, std=1e-3), solve_for=["Iyy"], ladder=False)
    limit = (1 - TRIANGLE_SLACK) * README_PLATE[2] - README_PLATE[0]
    v, sd = res.value("Iyy"), res.sigma("Iyy")
    lo_raw, hi_raw = res.interval_unclipped[0]
    assert lo_raw < limit  # the case: the uncut interval crosses the limit
    z = 1.959963984540054  # the normal's 97.5 % quantile
    assert lo_raw == pytest.approx(v - z * sd, rel=1e-12) and hi_raw == pytest.approx(v + z * sd, rel=1e-12)
    assert res.interval[0, 0] == pytest.approx(limit, rel=1e-12) and res.interval[0, 1] == hi_raw
    assert res.interval_clipped == ["triangle"]
    assert admissible(with_component(s, "Iyy", res.interval[0, 0]).inertia)
    assert v == pytest.approx(README_PLATE[1], rel=1e-9)  # value and std untouched by the cut

    cfg = tmp_path / "plate.yaml"
    cfg.write_text(f"body: {{mass: 100.0, inertia: {{principal: {README_PLATE}}}}}\n"
                   "rig: {anchors: [[0,-5,0],[0,5,0]], attachments: [[0,-2.5,0.5],[0,2.5,0.5]], lengths: [5.0,5.0]}\n")
    r = CliRunner().invoke(main, ["invert", str(cfg), "--period", f"pitch={T!r}+-0.001", "--amplitude", "0", "--json"])
    assert r.exit_code == 0, r.stderr
    d = json.loads(r.stdout)["inertia"]["Iyy"]
    assert d["interval_clipped"] == "triangle"
    assert d["interval_95"][0] == pytest.approx(limit, rel=1e-12)
    assert d["interval_95_unclipped"][0] == pytest.approx(lo_raw, rel=1e-9)
    assert d["value"] == pytest.approx(v, rel=1e-12) and d["std"] == pytest.approx(sd, rel=1e-12)
    r = CliRunner().invoke(main, ["invert", str(cfg), "--period", f"pitch={T!r}+-0.001", "--amplitude", "0"],
                           env={"COLUMNS": "200"})
    assert r.exit_code == 0 and "cut at the triangle limit" in r.stdout


def test_interval_near_zero_is_cut_at_zero_by_definiteness():
    """A thin rod along y (Iyy = 0.002 beside Ixx = Izz = 1 kg m^2) on two
    wires, CoM 5 cm below them: its pitch about its own axis timed with a
    coarse 50 ms gives Iyy +- 80 %, and value - t < 0.  The triangle bound
    (1 - s) Izz - Ixx is negative here, so the limit is definiteness: 0."""
    s = scene_from_dict({"body": {"mass": 10.0, "inertia": {"principal": [1.0, 0.002, 1.0]}},
                         "rig": {"anchors": [[0, -0.5, 0], [0, 0.5, 0]], "attachments": [[0, -0.5, 0.05], [0, 0.5, 0.05]],
                                 "lengths": [1.5, 1.5]}}, warn=False)
    res = invert(one(s, "pitch", period_of(s, "pitch"), std=0.05), solve_for=["Iyy"], ladder=False)
    assert res.interval_unclipped[0, 0] < 0 < res.value("Iyy")
    assert abs(res.interval[0, 0]) <= 1e-12 and res.interval[0, 1] == res.interval_unclipped[0, 1]
    assert res.interval_clipped == ["positive definite"]


def test_monte_carlo_quantiles_are_cut_at_the_same_limit():
    """The Monte Carlo check re-solves each draw within definiteness only,
    so its 2.5 % quantile of the README plate's Iyy fell past the triangle
    limit as the budget's did (51.56 < 52.064); it is cut there too."""
    from bifilar.scene import TRIANGLE_SLACK

    s = plate()
    T = period_of(s, "pitch")
    res = invert(one(s, "pitch", T, std=1e-3), solve_for=["Iyy"], ladder=False, monte_carlo=40, seed=3)
    limit = (1 - TRIANGLE_SLACK) * README_PLATE[2] - README_PLATE[0]
    mc = res.monte_carlo
    assert mc.n_ok > 30 and np.min(mc.samples[:, 0]) < limit  # draws do land past the limit
    assert mc.low[0] == pytest.approx(limit, rel=1e-12) and mc.high[0] > res.value("Iyy")


def test_cut_interval_covers_the_truth_as_often_as_the_uncut_one():
    """Coverage by simulation at the edge: a thin plate (Izz = Ixx + Iyy
    exactly, the truth on the limit), 40 experiments whose true mass is off
    by its stated 0.1 % and whose torsion period is timed with its stated
    1 ms (the other inputs stated exact, so the budget is those two).  The
    truth is physical, so it lies inside the limits: the cut interval holds
    it exactly when the uncut one does (checked per experiment), while the
    cut removes the part no body can have (nearly every experiment)."""
    from bifilar.scene import TRIANGLE_SLACK

    s = plate([100 * 5**2 / 12, 100 * 2.5**2 / 12, 100 * (5**2 + 2.5**2) / 12])
    truth = float(s.inertia[2, 2])
    edge = (s.inertia[0, 0] + s.inertia[1, 1]) / (1 - TRIANGLE_SLACK)
    rng = np.random.default_rng(7)
    exact = {"length": 0.0, "position": 0.0, "com": 0.0}
    covered_raw = covered_cut = n_cut = n_done = 0
    for _ in range(40):
        world = replace(s, mass=s.mass * (1 + 1e-3 * rng.standard_normal()))
        T = period_of(world, "torsion") + 1e-3 * rng.standard_normal()
        ms = replace(one(s, "torsion", T, std=1e-3), uncertainty=exact)
        try:
            res = invert(ms, solve_for=["Izz"], ladder=False)
        except Exception as exc:  # a period > 2 sigma beyond the edge is refused: no interval to judge
            assert "no physical Izz" in str(exc)
            continue
        n_done += 1
        raw, cut = res.interval_unclipped[0], res.interval[0]
        in_raw, in_cut = raw[0] <= truth <= raw[1], cut[0] <= truth <= cut[1]
        assert in_raw == in_cut
        assert raw[0] <= cut[0] <= cut[1] <= raw[1] and cut[1] <= edge * (1 + 1e-12)
        covered_raw += in_raw
        covered_cut += in_cut
        n_cut += res.interval_clipped[0] == "triangle"
    assert n_done >= 35 and covered_cut == covered_raw >= 0.8 * n_done and n_cut >= 10


def _random_body(rng):
    """A physical tensor: principal moments obeying the triangle inequality
    (some on the limit), turned by a random rotation."""
    from bifilar.rotations import rotvec_to_matrix

    a, b = rng.uniform(0.1, 1.0, 2)
    c = rng.uniform(abs(a - b), a + b) if rng.uniform() < 0.7 else a + b
    R = rotvec_to_matrix(rng.normal(size=3))
    return R @ np.diag([a, b, c]) @ R.T


def test_physical_limits_hold_for_every_body_whatever_the_other_unknowns_are():
    """The limits with other unknowns free use only the fixed components and
    hold for every real body (so a cut never uncovers a truth whose other
    components are estimated too); with none free they are the admissible
    interval.  Checked on 60 random bodies against their own components."""
    from itertools import combinations

    from bifilar.estimation.problem import physical_limits

    rng = np.random.default_rng(3)
    names = list(_IDX)
    for _ in range(60):
        I = _random_body(rng)
        sc = float(np.trace(I))
        for name in names:
            lo, hi = admissible_interval(I, name)
            (l0, _), (h0, _) = physical_limits(I, name)
            assert (l0, h0) == (lo, hi)
            for k in (1, 2):
                for free in combinations([n for n in names if n != name], k):
                    (l, _), (h, _) = physical_limits(I, name, free)
                    x = I[_IDX[name]]
                    assert l - 1e-12 * sc <= x <= h + 1e-12 * sc, (name, free, l, x, h)
                    assert l <= lo + 1e-12 * sc and h >= hi - 1e-12 * sc  # never tighter than the exact interval
                    # the free components' values are not used
                    J = I.copy()
                    for f in free:
                        J[_IDX[f]] = J[_IDX[f][::-1]] = rng.normal()
                    assert physical_limits(J, name, free) == physical_limits(I, name, free)


# --------------------------------------------------------------------------- 3. a sweep with no valid point


def test_sweep_with_no_point_that_can_hang_exits_2_with_the_common_reason(tmp_path):
    """The thesis plate's anchors are 10 m apart and its attachments 5 m:
    wires of L < 2.5 m cannot span the 5 m between them (closed form), so
    no point of length = 0.5 .. 1.5 m can hang.  The sweep exited 0 with a
    table of invalid rows; it now refuses as `plan` does, one line, nothing
    on stdout, and still writes the per-point CSV."""
    import csv

    from click.testing import CliRunner

    from bifilar.cli import main
    from conftest import CONFIGS

    lengths = [0.5, 1.0, 1.5]
    assert all(2 * L + 5.0 < 10.0 for L in lengths)
    out = tmp_path / "s.csv"
    r = CliRunner().invoke(main, ["sweep", str(CONFIGS / "thesis_plate_rest.yaml"), "--param", "length=0.5:1.5:3",
                                  "--no-tensions", "--json", "--out", str(out)])
    assert r.exit_code == 2 and r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: --param: no point of the sweep is valid"), r.stderr
    assert "3 of 3 points" in lines[0] and "cannot reach" in lines[0] and str(out) in lines[0]
    rows = list(csv.DictReader(out.open()))
    assert [float(x["length"]) for x in rows] == lengths
    assert all(x["valid"] == "False" and "cannot reach" in x["error"] for x in rows)
    assert not (tmp_path / "s.csv.partial.jsonl").exists()
    # one valid point is enough for the sweep to answer (exit 0)
    r = CliRunner().invoke(main, ["sweep", str(CONFIGS / "thesis_plate_rest.yaml"), "--param", "length=1.0,5.0",
                                  "--no-tensions", "--json"])
    assert r.exit_code == 0, r.stderr


def test_most_common_reason_groups_wordings_and_breaks_ties_in_grid_order():
    from bifilar.studies.ranking import why_invalid

    slack = "rig.lengths: wire {} is slack at rest by {} m; shorten it"
    reach = "rig.lengths: wires 1 and 2 cannot reach: they span {} m"
    pts = [{"params": {"length": 1.0}, "valid": False, "error": reach.format(6)},
           {"params": {"length": 2.0}, "valid": False, "error": slack.format(2, 0.1)},
           {"params": {"length": 3.0}, "valid": True},
           {"params": {"length": 4.0}, "valid": False, "error": slack.format(3, 1.5e-3)},
           {"params": {"length": 5.0}, "valid": False, "error": reach.format(7.5)}]
    msg = why_invalid(pts[:4])  # slack twice (other wires, other amounts), reach once
    assert "(2 of 4 points, e.g. at length = 2)" in msg and slack.format(2, 0.1) in msg
    assert "1 other reason(s)" in msg
    msg = why_invalid(pts)  # 2 against 2: the reason met first on the grid
    assert "(2 of 5 points, e.g. at length = 1)" in msg and reach.format(6) in msg
