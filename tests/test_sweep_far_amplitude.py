"""The sweep's stated-amplitude sigma far from the linear period
(docs/design.md, "Lead, session 19"): `sweep` predicts the std `invert
--period MODE=T --amplitude A` prints, and since sepinv (session 19)
invert budgets an amplitude whose run lies more than 20 % from the linear
period by a secant over A +- 2 s_A, and refuses one whose range reaches the
wires' half turn.  The sweep kept the first-order slope: audit18's
trifilar plate at a torsion of 2.0 rad printed 0.0077 kg m^2 where invert
prints 0.0103, and at 2.7 rad (range to 3.24 rad, past pi) a sigma where
invert refuses.  The reference is invert's own std through its own code
path (estimation/amplitude_secant: a Problem's measured factor runs, not
the sweep's batched engine), on a period from an independent `simulate`."""

from __future__ import annotations

import json
import math

import pytest
from click.testing import CliRunner

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
from bifilar.cli import main
from conftest import plate3_scene


@pytest.fixture(scope="module")
def plate3(plate3_path):
    return plate3_path


def _sweep(path, amplitude, *more):
    r = CliRunner().invoke(main, ["sweep", str(path), "--amplitude", str(amplitude), "--param", "length=1:1:1",
                                  "--json", *more])
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)["points"][0]["components"]["Izz"]


def test_sweep_sigma_far_from_linear_is_inverts_std(plate3):
    sc = plate3_scene()
    rest = rest_pose(sc)
    T = simulate(sc, "torsion", 2.0, 4, rest=rest, modes=linear_modes(sc, rest), rtol=1e-11).period
    r = CliRunner().invoke(main, ["invert", str(plate3), "--period", f"torsion={T!r}+-0.001", "--amplitude", "2.0",
                                  "--solve-for", "Izz", "--json"])
    assert r.exit_code == 0, r.output
    std = json.loads(r.stdout)["inertia"]["Izz"]["std"]
    e = _sweep(plate3, 2.0)
    # both budget the same terms (default stds, the secant over 2.0 +- 0.4 rad); they differ by the two
    # engines' run errors (~1e-7 relative in the periods) and the estimate's 1e-7 offset from the
    # config's Izz: 2 % leaves room for both and fails the first-order sigma (0.0077 against 0.0103, -25 %)
    assert e["sigma"] == pytest.approx(std, rel=0.02)
    assert e["amplitude_budget"]["amplitude_secant"] > 0


def test_sweep_gives_no_sigma_where_inverts_range_reaches_the_half_turn(plate3):
    e = _sweep(plate3, 2.7, "--periods", "10")  # 2.7 +- 2 x 0.27 reaches 3.24 rad > pi: invert exits 2
    assert e["sigma"] is None or not math.isfinite(e["sigma"])
    assert "reachable start" in e["sigma_unavailable"]
