"""Mutation round 28 (docs/mutation.md, "Round 28"): tests that kill the
surviving mutants of session 27's new and changed code (label27's partner
label across an avoided crossing's gap, runs27's per-run figures, the
benchmark page's issue-14 splice).  Every expected value is worked out by
hand or by an independent formulation, never taken from the code under
test; each test's docstring names the mutants it kills (ids of
``scripts/mutate.py``'s mutants of the module at bdadd15)."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

DATA = Path(__file__).resolve().parent / "data" / "audit27"


# ---------------------------------------------------------------------------
# estimation/crossing_partner.py, estimation/roots.py (label27)
# ---------------------------------------------------------------------------

@dataclasses.dataclass(frozen=True)
class _Meas:
    """What :func:`partner_hint` reads of the measurement (its label, period s, std s, field)."""
    label: str
    period: float
    std: float
    field: str = "--period"


class _Set:
    """A mode set at one value of the unknown: the labels of its sorted modes."""

    def __init__(self, labels):
        self.modes = [type("Mode", (), {"label": lab})() for lab in labels]

    def get(self, label):
        for md in self.modes:
            if md.label == label:
                return md
        raise KeyError(label)


class _Scan:
    """A hand-made scan: its switches, mode sets at the switch's two ends and
    each label's roots (kg m^2) -- the interface partner_hint documents."""
    name = "Izz"

    def __init__(self, switches, sets, roots, m):
        self.switches, self._sets, self._roots, self.m = switches, sets, roots, m

    def attainable(self):
        return []

    def at(self, x):
        return self._sets.get(x)

    def roots(self, target):
        return list(self._roots.get(self.m.label, []))


def _descending_scan(period=1.85):
    """The label 'torsion' passes, between Izz 0.1 and 0.2 kg m^2, from sorted
    mode 2 (period 1.9 s just before) to mode 3 (1.8 s just after): its
    period jumps DOWN over 1.8 .. 1.9 s.  Mode 2 carries 'swing-x' past the
    switch (its partner); mode 3 carried 'swing-y' before it, which has no
    root.  The swing-x reading's root is 0.15 kg m^2."""
    sets = {0.1: _Set(["a", "b", "torsion", "swing-y"]), 0.2: _Set(["a", "b", "swing-x", "torsion"])}
    return _Scan([(0.1, 0.2, 2, 3, 1.9, 1.8)], sets, {"swing-x": [0.15]}, _Meas("torsion", period, 0.0005))


def test_a_gap_the_labelled_period_jumps_down_over_names_the_partner():
    """The documented rule: a target strictly between the labelled periods
    either side of a switch lies in its gap, whichever way the period jumps.
    label27's tests use a03 at a gap its torsion jumps UP over (1.8745 ->
    1.8840 s as Izz grows), so the upper bound ``max(T before, T after)`` was never
    the period before the switch.  Here it jumps down, 1.9 -> 1.8 s: 1.85 s
    lies in the gap (swing-x named, its root 0.15 kg m^2 given: exact), 1.95
    and 1.75 s do not ("").  Kills crossing_partner 9 (``max(sw[4], sw[5])
    -> max(sw[5], sw[5])``: the gap's upper end taken as 1.8 s, nothing
    named)."""
    from bifilar.estimation.crossing_partner import partner_hint

    msg = partner_hint(_descending_scan(), 1.85, exact=True)
    assert "the mode labelled 'swing-x' carries it across" in msg, msg
    assert "swing-y" not in msg  # no root: not named when another label has one
    assert "(--period swing-x=1.85+-0.0005)" in msg
    assert msg.endswith("which gives Izz = 0.15 kg m^2 (the mode labelled 'swing-x' there has period 1.85 s)")
    assert "passes 0.15 kg m^2" in msg  # the switch's midpoint, (0.1 + 0.2) / 2
    for outside in (1.95, 1.75):
        assert partner_hint(_descending_scan(outside), outside, exact=True) == ""


def _invert(*args):
    from bifilar.cli import main

    return CliRunner().invoke(main, ["invert", str(DATA / "a03_drawn.yaml"), "--solve-for", "Izz", *args])


def test_with_an_amplitude_the_partner_is_named_without_a_value():
    """With ``--amplitude 0.05`` the refused period's target is the
    linear-model period T / r (r the torsion's amplitude factor: 1.8808 s
    for 1.88117 s), not the measured one: still in a03's gap, so swing-x is
    named, but the value a swing-x reading gives is not the root at that
    target (swing-x's own amplitude factor differs: invert answers 0.10128
    kg m^2 for ``--period swing-x=1.88117+-0.0005 --amplitude 0.05``, the
    root at 1.8808 s is 0.10113), so the documented rule names none ("with
    their values when exact").  label27's tests all ran at amplitude 0 (the
    target None: exact).  Kills roots 189 (``float(target) == m.period ->
    !=``: exact whenever the target is not the period) and crossing_partner
    19 (``exact and xs -> or``)."""
    r = _invert("--period", "torsion=1.88117+-0.0005", "--amplitude", "0.05")
    assert r.exit_code == 2, r.stderr
    target = float(re.search(r"gives a period of (\S+) s", r.stderr).group(1))
    assert 1.8795 < target < 1.8815 and target != 1.88117  # T / r: r a little above 1 at 0.05 rad
    assert "the mode labelled 'swing-x' carries it across" in r.stderr, r.stderr
    assert "which gives" not in r.stderr, r.stderr


# ---------------------------------------------------------------------------
# scripts/run_benchmarks.py (the issue-14 section and its --issue14-only splice)
# ---------------------------------------------------------------------------

def _bench():
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    import run_benchmarks

    return run_benchmarks


def _i14(**over):
    """Hand-made issue-14 figures (what ``issue14()`` measures), round numbers."""
    i = {"before_rev": "abc1234", "machine": "2026-01-01 on 2 cores (cpu), load average 1.0 at the start",
         "startup": {"config": "configs/x.yaml", "repeat": 3, "modes_json_wall_s": 0.3, "modes_json_cpu_s": 0.25,
                     "import_numpy_wall_s": 0.1, "import_numpy_cpu_s": 0.1, "wall_ratio": 3.0, "cpu_ratio": 2.5,
                     "heavy_modules": []},
         "startup_before": None, "batch_before": None, "batch": [], "simulate": {"rows": []}, "sensitivity": [],
         "sweep_points": {"boat": {"point_cpu_s": 0.012, "points_per_s_cpu": 83.3, "rest_and_modes_cpu_s": 0.004,
                                   "ratio_to_rest_and_modes": 3.0}},
         "yardstick_before": {"boat": 0.006},
         "sweep_cli": {"sweep_cli_point_cpu_s": 0.02, "sweep_cli_points_per_s_cpu": 50.0},
         "plan": {"plan_cpu_s": 1.5, "plan_wall_s": 2.0, "evaluations": 40},
         "sweep_cli_before": {"sweep_cli_point_cpu_s": 0.1, "sweep_cli_points_per_s_cpu": 10.0}, "plan_before": None}
    i.update(over)
    return i


def test_the_sweep_table_sets_each_point_beside_the_old_solve_and_rows_need_both_figures():
    """The generated sweep section, from hand-made figures: a point of 12 ms
    CPU beside the old tree's rest pose + modes solve of 6 ms is 2.0x it
    (12 / 6, by hand); without the old tree's figure the row says "- | -";
    a tree's row of the CLI table needs both its sweep and its plan figures
    (the old tree's plan missing: no "before" row, no crash).  The section
    starts with its heading on a line of its own and names the machine.
    Kills run_benchmarks 80 (the heading's ``+ "\\n"``), 82 (``or {} ->
    and``: the old figures dropped, or None read), 83 (the ratio's ``+``) and
    84 (``sc and pl -> or``: the missing plan read); none of them ran
    before (the section was built only by a measuring run)."""
    rb = _bench()
    text = "\n".join(rb._issue14_section(_i14()))
    assert text.startswith(rb.I14_HEADING + "\n\nMeasured 2026-01-01 on 2 cores")
    assert "| boat | 12.0 | 83 | 4.00 | 3x | 6.00 | 2.0x |" in text
    assert "| now | 20.0 | 50 | 1.50 / 2.00 | 40 |" in text
    assert "| before |" not in text  # its plan was not measured
    text = "\n".join(rb._issue14_section(_i14(yardstick_before=None)))
    assert "| boat | 12.0 | 83 | 4.00 | 3x | - | - |" in text


def test_an_empty_issue14_section_ends_at_the_very_next_heading():
    """``splice_issue14`` replaces the section "from its heading to the next
    ``## `` heading": where that heading is the very next line (a section
    with no text of its own), the next section is kept whole.  Kills
    run_benchmarks 112 (``range(start + 1 -> start + 2, ...)``: the next
    heading skipped, its section replaced too)."""
    rb = _bench()
    old = f"# Page\n\n{rb.I14_HEADING}\n## Reproduce\n\nrun it\n"
    out = rb.splice_issue14(old, [rb.I14_HEADING + "\n", "new i14 text\n"])
    assert "## Reproduce" in out and "run it" in out
    assert out.index("new i14 text") < out.index("## Reproduce")



def test_issue14_only_measures_against_the_revision_given_and_rewrites_only_its_section(tmp_path, monkeypatch):
    """``--issue14-only --before REV``: the issue-14 figures are measured
    beside REV (``''``: none), the raw figures written to ``--json`` and the
    page's section replaced by the figures' table, the rest of the page
    kept.  The measuring is replaced by the hand-made figures (a real run
    takes minutes).  Kills run_benchmarks 117 (``args.before or None ->
    and``: REV ignored, nothing measured beside it)."""
    import json

    rb = _bench()
    page = tmp_path / "performance.md"
    page.write_text(f"# Page\n\n## Other\n\nkept\n\n{rb.I14_HEADING}\n\nold figures\n\n## Reproduce\n\nrun it\n")
    asked = []

    def measured(quick, before):
        asked.append((quick, before))
        return _i14(before_rev=before)

    monkeypatch.setattr(rb, "issue14", measured)
    monkeypatch.setattr(rb, "DOC", page)
    rb.main(["--issue14-only", "--before", "abc1234", "--json", str(tmp_path / "raw.json")])
    rb.main(["--issue14-only", "--before", ""])
    assert asked == [(False, "abc1234"), (False, None)]
    assert json.loads((tmp_path / "raw.json").read_text())["issue14"]["before_rev"] == "abc1234"
    text = page.read_text()
    assert "old figures" not in text and "| boat | 12.0 | 83 |" in text
    assert "kept" in text and "run it" in text


# ---------------------------------------------------------------------------
# integrators.py (runs27: the degree-7 Horner written out, the others' loop)
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("degree", [3, 7])
def test_few_roots_of_any_degree_are_the_analytic_ones(degree):
    """:func:`poly_root_unit` documents polynomials of any degree; every
    caller in the package passes degree 7 (8 coefficients), so runs27's
    loop for the other degrees (kept beside the written-out degree-7 Horner)
    ran in no test.  p(x) = (x - r) prod_j (x + j), j = 1 .. degree - 1, has
    the single root r in [0, 1] (the others negative); its ascending
    coefficients by numpy's ``poly`` (an independent expansion), eight roots
    r (at most SCALAR_ROOTS: the float path).  Newton from the secant guess
    ends to the last bit or two: 4e-16 asserted.  Kills integrators 206-211
    (the loop's ``v = 0.0 -> 1``, ``v * x -> v / x``, ``+ cf -> - cf``, and
    the same three of the derivative's loop: a wrong slope leaves Newton
    short of convergence in its 30 steps), uncovered before."""
    import numpy as np

    from bifilar.integrators import SCALAR_ROOTS, poly_root_unit

    r = np.array([0.03, 0.2, 0.37, 0.5, 0.61, 0.777, 0.9, 0.999])
    assert len(r) <= SCALAR_ROOTS
    P = np.array([np.poly(np.concatenate([[x], -np.arange(1.0, degree)]))[::-1] for x in r]).T  # (d + 1, k)
    v0, v1 = P[0], P.sum(axis=0)  # p(0), p(1)
    assert np.all(v0 < 0) and np.all(v1 >= 0)
    np.testing.assert_allclose(poly_root_unit(P, v0, v1), r, rtol=0, atol=4e-16)


# ---------------------------------------------------------------------------
# analysis/batch.py (runs27: a run's figures from Python floats)
# ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def plate():
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.config import read_yaml, scene_from_dict

    from conftest import CONFIGS

    sc = scene_from_dict(read_yaml(CONFIGS / "thesis_plate_rest.yaml"), "thesis_plate_rest", warn=False)
    return sc, rest_pose(sc)


@pytest.mark.parametrize("method", ["dop853", "lsoda"])
def test_a_release_too_small_to_time_has_no_drift_even_with_energy_to_refer_to(plate, method):
    """``run_accuracy.untimed``: below MIN_TIMED_ANGLE (1e-6 rad) the drift
    relative to the oscillation energy is undefined (nan), whatever that
    energy's rounding.  At 1e-9 rad (test_audit7_simulate's case) the start's
    energy is exactly zero and the ``E0 != 0`` guard alone gives nan; at
    0.5e-6 rad it is not zero (m g dz ~ 1e-12 J: the mutant gives 4e-3 /
    1e-3), so only the untimed clause does.  At 2e-6 rad (timed) the drift
    is a number.  Kills batch 166 (``E0 != 0 and not untimed -> or``),
    which test_audit7_simulate's 1e-9 rad does not."""
    import math

    from bifilar.analysis.batch import simulate_batch
    from bifilar.analysis.run_accuracy import MIN_TIMED_ANGLE

    sc, rest = plate
    amps = [0.5 * MIN_TIMED_ANGLE, 2.0 * MIN_TIMED_ANGLE]
    small, timed = simulate_batch([sc, sc], "torsion", amps, 2, rests=[rest, rest], method=method)
    assert small.error is None and math.isnan(small.energy_drift)
    assert timed.error is None and math.isfinite(timed.energy_drift)


@pytest.mark.parametrize("method", ["dop853", "lsoda"])
def test_a_body_released_at_rest_ends_at_its_rest_pose(plate, method):
    """Released at rest (amplitude 0) the body stays there: the run's final
    state is the rest pose, CoM (m, absolute: the engine integrates about
    the rest CoM and adds it back) and quaternion, to 1e-14 (found 2e-15).
    Kills batch 198 (``y_final + com_pad -> -``: the rest CoM subtracted,
    the final CoM at -com), which only the identity tests (both paths the
    same code) read."""
    import numpy as np

    from bifilar.analysis.batch import simulate_batch

    sc, rest = plate
    (r,) = simulate_batch([sc], "torsion", 0.0, 2, rests=[rest], method=method)
    assert r.error is None
    np.testing.assert_allclose(r.y_final[:3], rest.com, rtol=0, atol=1e-14)
    np.testing.assert_allclose(r.y_final[3:7], rest.q, rtol=0, atol=1e-14)


@pytest.mark.parametrize("method", ["dop853", "lsoda"])
def test_no_period_says_whether_the_run_stopped_or_was_too_short(method):
    """``no_period_warning``'s ``stopped``: a run that a slack wire stopped
    (test_stress's lopsided trifilar, wire 1 at 2.7 % of the weight, swung
    0.6 m: wire 1 slack from the start, ``on_slack="stop"``) says its
    crossings were too few "before the run stopped"; a run of 0.4 periods
    that ran to its end (0.1 m, no slack) says "integrate longer" -- by the
    run's own record (its stop warning, its slack list), not by the
    warning.  Kills batch 179 (``status == 1 -> != 1``: the two reasons
    swapped) and 180 (``== 1 -> == 2``: a stopped run told to integrate
    longer); test_audit7_simulate's stopped run has its period."""
    import numpy as np

    from bifilar.analysis.batch import simulate_batch
    from bifilar.config import scene_from_dict

    ang = np.radians([0, 120, 240])
    pts = np.c_[0.5 * np.cos(ang), 0.5 * np.sin(ang), np.zeros(3)]
    s = scene_from_dict({"body": {"mass": 3.0, "inertia": {"principal": [0.3, 0.3, 0.4]}},
                         "rig": {"anchors": pts.tolist(), "attachments": (pts + [0.23, 0, 0.1]).tolist(),
                                 "lengths": [2.0] * 3}})
    stopped, short = simulate_batch([s, s], "swing-x", [0.6, 0.1], [3, 0.4], method=method, on_slack="stop")
    assert stopped.period is None and stopped.slack and any(w.startswith("run stopped") for w in stopped.warnings)
    assert stopped.warnings[-1].startswith("fewer than two crossings of the rest value before the run stopped")
    assert short.period is None and not short.slack and not any("stopped" in w for w in short.warnings)
    assert short.warnings[-1].endswith("no period measured; integrate longer")



def test_the_violation_warning_is_for_1e_6_of_the_longest_wire_and_precedes_no_period(plate):
    """``violation_warning`` is given where a run's wires erred by more than
    1e-6 of the longest (the thesis plate: 5 m, so 5e-6 m).  DOP853 at rtol
    3e-6 over 5 torsion periods errs by ~1.3e-6 m (a factor 4 under the
    threshold, and 6 over 1e-6 / 5 m): no warning.  LSODA at rtol 1e-4 over
    0.4 periods errs by ~4e-4 m (70x over): the warning, and -- the run
    has no period -- before the no-period warning, which stays the last
    word, as on a run without a violation.  Kills batch 194 (``1e-6 * lmax
    -> / lmax``) and 196 (``len(warnings) - (period is None) -> +``: the
    violation appended after the no-period reason), uncovered before."""
    from bifilar.analysis.batch import simulate_batch

    sc, rest = plate
    Lmax = max(sc.lengths)
    (quiet,) = simulate_batch([sc], "torsion", 0.3, 5, rests=[rest], rtol=3e-6, method="dop853")
    assert 1e-6 / Lmax * 2 < quiet.max_constraint_violation < 1e-6 * Lmax / 2, quiet.max_constraint_violation
    assert quiet.period is not None and not any("constraint violation" in w for w in quiet.warnings)
    (loud,) = simulate_batch([sc], "torsion", 0.3, 0.4, rests=[rest], rtol=1e-4, method="lsoda")
    assert loud.max_constraint_violation > 10 * 1e-6 * Lmax and loud.period is None
    assert [w.split(" ")[0] for w in loud.warnings] == ["constraint", "fewer"], loud.warnings


# ---------------------------------------------------------------------------
# shortcuts whose values equal the path they skip: the path is taken
# ---------------------------------------------------------------------------

def test_edge_ratio_given_the_starts_wires_computes_none(monkeypatch):
    """start27: where the direct solve gave every start, ``edge_ratio``
    takes the starts' wires from it (``at_rest[3]``) and computes none; its
    values equal computing them again (test_start27), so only the calls
    show whether the shortcut is taken.  Over test_perf26a's CASES, each
    ``edge_ratio`` given the starts' wires: no ``_Rig.wires`` call.  Kills
    start_pose 414, 415 (``len(geo) < 4 -> <= 4``, ``< 5``: the wires
    computed again at every start)."""
    from bifilar.analysis import start_pose as spm

    from test_perf26a import CASES

    real_edge, real_wires = spm.edge_ratio, spm._Rig.wires
    taken, calls = [], []

    def counted(self, x):
        calls.append(len(x))
        return real_wires(self, x)

    def edge(rig, x, hold, at_rest=None):
        if at_rest is None or at_rest[3] is None:
            return real_edge(rig, x, hold, at_rest)
        del calls[:]
        with monkeypatch.context() as m:
            m.setattr(spm._Rig, "wires", counted)
            out = real_edge(rig, x, hold, at_rest)
        taken.append(list(calls))
        return out

    monkeypatch.setattr(spm, "edge_ratio", edge)
    for sc, r, mds, a in CASES:
        spm.start_poses([sc] * len(mds), [r] * len(mds), mds, a)
    assert taken and all(c == [] for c in taken), taken


def test_the_lowest_point_of_one_bodys_runs_skips_the_row_search(monkeypatch):
    """runs27: every run of a LowestPoint batch of one body (a sweep point's
    runs) is its support function's: ``fold`` calls it on every row without
    ``np.isin``'s search (its values the same, test_runs27), so only the
    search's absence shows the shortcut.  Three runs of the Solar Boat (a
    support function), and a batch of two bodies, which does search.
    Kills batch_health 52 (``one or every -> and``)."""
    import numpy as np

    from bifilar.analysis.batch_health import LowestPoint

    from test_runs27 import _scene

    boat, plate = _scene("solar_boat"), _scene("thesis_plate_rest")
    real_isin, searched = np.isin, []
    monkeypatch.setattr(np, "isin", lambda *a, **k: (searched.append(1), real_isin(*a, **k))[1])
    q = np.tile([1.0, 0.0, 0.0, 0.0], (6, 1))
    for scenes, search in (([boat] * 3, False), ([boat, plate, boat], True)):
        del searched[:]
        low = LowestPoint(scenes, np.zeros((3, 3)))
        low.add(np.tile(np.arange(3), 2), np.full(6, -4.0), q)
        assert np.all(np.isfinite(low.z)) and bool(searched) == search
