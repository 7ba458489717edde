"""Estimation audit, session 19 (docs/design.md, "Estimation audit, session
19"): closed loops on cases nobody here wrote.  The audit's draws stay in
its throw-away harness; these tests pin what its findings changed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

from bifilar.cli import main

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
DRONE = CONFIGS / "drone_parallel.yaml"
T_DRONE = 1.8800643384877211  # the drone's linear torsion period, s (`bifilar modes`)
EXACT = ["--uncertainty", "length=0", "--uncertainty", "position=0", "--uncertainty", "com=0",
         "--uncertainty", "mass=0"]


def _izz(*args: str) -> tuple[dict, dict]:
    r = CliRunner().invoke(main, ["invert", str(DRONE), *args, "--solve-for", "Izz", *EXACT, "--json"])
    assert r.exit_code == 0, r.stderr
    d = json.loads(r.stdout)
    return d["inertia"]["Izz"], d["budget"]["Izz"]


def test_repeated_timings_of_one_mode_each_keep_their_own_term():
    """Audit19's row A: the drone's torsion timed twice (1 ms each, inputs
    exact), 40 draws: the printed std was 8.41e-6 kg m^2, half the one
    timing's 1.68e-5 where the mean of two independent timings has
    1/sqrt(2) of it, and the realised spread 1.28e-5; z sd 1.52, coverage
    0.775 +- 0.066.  The budget named both timing terms `timing[torsion]`,
    so the second replaced the first.  With only timing in the budget the
    answer is the weighted least-squares mean, whose std is the single
    timing's over sqrt(sum of (s_1 / s_k)^2) (independent formulation: the
    inverse-variance weights); the std is linear in the period's std here
    (the period 4e-4 relative from the truth), so 1e-6 relative covers the
    solver's tolerance."""
    one, _ = _izz(f"--period=torsion={T_DRONE}+-0.001", "--amplitude", "0")
    three, bud = _izz(f"--period=torsion={T_DRONE}+-0.001", f"--period=torsion={T_DRONE + 4e-4}+-0.002",
                      f"--period=torsion={T_DRONE - 4e-4}+-0.002", "--amplitude", "0")
    assert three["std"] == pytest.approx(one["std"] / 1.5 ** 0.5, rel=1e-6)  # 1 + 1/4 + 1/4
    assert {"timing[torsion]", "timing[torsion#2]", "timing[torsion#3]"} <= set(bud["inputs"])


def test_repeated_stopwatch_entries_and_releases_each_keep_their_own_terms(tmp_path):
    """The same in a measurements file at a stated amplitude: two stopwatch
    entries of the torsion (5 trials each) and each release's 10 %: the
    two amplitude terms are independent releases, so the amplitude group's
    std is 1/sqrt(2) of one entry's (both periods equal, so the gains are
    equal; a release's term is linear in the gain), and the timing terms
    are two with their Student dof (4 each)."""
    times = [round(10 * T_DRONE + d, 3) for d in (-0.02, 0.01, 0.0, 0.015, -0.005)]
    entry = {"mode": "torsion", "cycles": 10, "times": times, "amplitude": 0.1}
    doc = {"config": str(DRONE), "solve_for": ["Izz"],
           "uncertainty": {"length": 0, "position": 0, "com": 0, "mass": 0}}
    groups = {}
    for n in (1, 2):
        p = tmp_path / f"m{n}.yaml"
        p.write_text(yaml.safe_dump(doc | {"measurements": [entry] * n}))
        r = CliRunner().invoke(main, ["invert", "--measurements", str(p), "--json"])
        assert r.exit_code == 0, r.stderr
        b = json.loads(r.stdout)["budget"]["Izz"]
        groups[n] = b["groups"]
        if n == 2:
            assert {"timing[torsion]", "timing[torsion#2]"} <= set(b["inputs"])
    assert groups[2]["amplitude"]["std"] == pytest.approx(groups[1]["amplitude"]["std"] / 2 ** 0.5, rel=1e-3)
    assert groups[2]["timing"]["std"] == pytest.approx(groups[1]["timing"]["std"] / 2 ** 0.5, rel=1e-3)


def test_periods_that_agree_only_marginally_are_warned():
    """Audit19's row A3: the torsion timed twice at 1 ms, one timing 0.2 %
    off (a typo), inputs exact: 23 of 30 draws answered (the fit check
    refuses below p = 0.001), z +2.56, 3 of 23 within their interval, no
    word.  Now a fit accepted at p < 0.01 says so, naming the mode with the
    largest residual.  Two timings 3.76 ms apart at 1 ms each: chi2 =
    3.76^2 / 2 = 7.07 for 1 dof, p = 0.0078 (the analytic chi-square of
    two equal-std values about their mean); 1.2 ms apart (chi2 0.72, p
    0.40) is quiet."""
    out = {}
    for gap in (0.0012, 0.00376):
        r = CliRunner().invoke(main, ["invert", str(DRONE), f"--period=torsion={T_DRONE}+-0.001",
                                      f"--period=torsion={T_DRONE + gap}+-0.001", "--amplitude", "0", *EXACT, "--json"])
        assert r.exit_code == 0, r.stderr
        d = json.loads(r.stdout)
        assert d["fit"]["chi2"] == pytest.approx(gap ** 2 / 2e-6, rel=1e-3)
        out[gap] = [w for w in d["warnings"] if "agree only" in w]
    assert out[0.0012] == []
    assert len(out[0.00376]) == 1 and "p = 0.0078" in out[0.00376][0] and "'torsion" in out[0.00376][0]
