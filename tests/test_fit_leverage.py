"""A measured period no other measurement checks (docs/design.md, "Lead,
session 19"; audit19 row A1): among the drone's torsion, pitch and both
swings solving Izz and Iyy, the torsion alone moves Izz and the pitch alone
Iyy, so a 2 % typo in the torsion gave Izz +4 %, chi2 0 and "2 degrees of
freedom" without a word.  `invert` now notes every period whose leverage in
the timing-weighted fit exceeds 0.99.  References: the physics of a
parallel bifilar (its swings are pendulums that neither moment moves), and
the closed-form leverage of repeated timings of one mode, ``h_k = w_k /
sum w`` with ``w = 1 / s^2``."""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner

from bifilar.cli import main

DRONE = Path(__file__).resolve().parents[1] / "configs" / "drone_parallel.yaml"
PERIODS = {"torsion": 1.8800643384877211, "pitch": 0.9853502980039075, "swing-x": 2.4873718137340903,
           "swing-y": 2.456919878869915}  # the drone's linear periods, s (`bifilar modes`)


def _notes(*args: str) -> list[str]:
    r = CliRunner().invoke(main, ["invert", str(DRONE), *args, "--amplitude", "0", "--json"])
    assert r.exit_code == 0, r.stderr
    return [n for n in json.loads(r.stdout)["notes"] if "checked by no other measurement" in n]


def test_a_period_only_it_moves_an_unknown_is_named_as_unchecked():
    notes = _notes(*[f"--period={m}={T!r}+-0.001" for m, T in PERIODS.items()], "--solve-for", "Izz",
                   "--solve-for", "Iyy")
    named = {n.split("'")[1] for n in notes}
    assert named == {"torsion", "pitch"}  # the swings move neither moment: they are checked by nothing but
    # check nothing, and the fit's 2 dof are theirs


def test_leverage_of_repeated_timings_is_their_weight_share():
    T = PERIODS["torsion"]
    # stds 1 ms and 0.1 ms: the precise timing's leverage 100 / 101 = 0.990 > 0.99, named
    notes = _notes(f"--period=torsion={T!r}+-0.001", f"--period=torsion={T!r}+-0.0001", "--solve-for", "Izz")
    assert len(notes) == 1 and "'torsion#2'" in notes[0] and "leverage 0.990" in notes[0]
    # stds 1 ms and 0.11 ms: 82.6 / 83.6 = 0.988, below 0.99: none
    assert _notes(f"--period=torsion={T!r}+-0.001", f"--period=torsion={T!r}+-0.00011", "--solve-for", "Izz") == []
