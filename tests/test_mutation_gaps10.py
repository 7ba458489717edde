"""Tests written to kill surviving mutants of round 10 (docs/mutation.md,
"Round 10"): session 9's code -- the decaying record's amplitude law
(``bifilar/estimation/signal_law.py``), the period's error bound and the
irregular-motion check (``bifilar/analysis/run_accuracy.py``), a sweep
point's stated-amplitude budget (``bifilar/studies/point_amplitude.py``),
the Monte Carlo factor following dr/dp (``bifilar/estimation/montecarlo.py``),
the barely determined unknowns (``bifilar/estimation/roots.py``) and the
config's uncertainty block (``bifilar/estimation/measurements.py``).

Truths: closed forms worked out in the comments (a least-squares std from a
diagonal Jacobian, the documented bounds and rules of the module
docstrings), records written here from their own laws -- never output of
the code under test pasted in.  Each test runs in well under 2 s.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bifilar.estimation.roots import loosely_determined

# ---------------------------------------------------------------------------
# roots.py: the unknowns the periods barely determine
# ---------------------------------------------------------------------------


class _LinearProblem:
    """A stand-in for :class:`~bifilar.estimation.problem.Problem` with a
    diagonal Jacobian: unknown ``j`` moves only period ``j``, by ``slopes[j]``
    s per unit, timed to ``sigmas[j]`` s, so its timing-only least-squares std
    is ``sigmas[j] / |slopes[j]|`` (J^T J diagonal)."""

    def __init__(self, names, slopes, sigmas, scales):
        self.unknowns = list(names)
        self.measurements = [SimpleNamespace(std=s) for s in sigmas]
        self._J = np.diag(np.asarray(slopes, float))
        self._scales = np.asarray(scales, float)

    def jacobian(self, p):
        return self._J.copy()

    def scales(self):
        return self._scales.copy()


def test_an_unknown_is_loose_above_a_tenth_of_its_scale():
    # stds 1e-3 / slope: 0.09 and 0.11 of the unit scale (the documented tenth, LOOSE_UNKNOWN);
    # only the second is named, with its std
    pb = _LinearProblem(["Izz", "Ixx"], [1e-3 / 0.09, 1e-3 / 0.11], [1e-3, 1e-3], [1.0, 1.0])
    loose = loosely_determined(pb, [0.0, 0.0])
    assert [n for n, _ in loose] == ["Ixx"]
    assert loose[0][1] == pytest.approx(0.11, rel=1e-9)
    # the same stds against a scale of 0.5: 0.18 and 0.22 of it, both named
    pb = _LinearProblem(["Izz", "Ixx"], [1e-3 / 0.09, 1e-3 / 0.11], [1e-3, 1e-3], [0.5, 0.5])
    assert {n for n, _ in loosely_determined(pb, [0.0, 0.0])} == {"Izz", "Ixx"}


def test_loose_unknowns_come_largest_relative_std_first():
    # com.x: std 0.5 m on a scale of 1 m (0.5 of it); com.y: std 0.3 m on 0.1 m (3 of it).  By the
    # std relative to the scale com.y comes first, though its std is the smaller (by std alone, or by
    # std times scale -- 0.5 against 0.03 -- com.x would)
    pb = _LinearProblem(["com.x", "com.y"], [1e-3 / 0.5, 1e-3 / 0.3], [1e-3, 1e-3], [1.0, 0.1])
    loose = loosely_determined(pb, [0.0, 0.0])
    assert [n for n, _ in loose] == ["com.y", "com.x"]
    assert [s for _, s in loose] == pytest.approx([0.3, 0.5], rel=1e-9)


# ---------------------------------------------------------------------------
# measurements.py / cmd_invert: the config's uncertainty block under invert
# ---------------------------------------------------------------------------


def _boat_config(tmp_path, name, unc):
    import yaml

    from conftest import CONFIGS

    cfg = yaml.safe_load((CONFIGS / "solar_boat.yaml").read_text())
    cfg.pop("uncertainty", None)
    if unc is not None:
        cfg["uncertainty"] = unc
    p = tmp_path / name
    p.write_text(yaml.safe_dump(cfg))
    return p


def _invert_cli(*args):
    from click.testing import CliRunner

    from bifilar.cli import main

    return CliRunner().invoke(main, ["invert", *map(str, args)])


INVERT_IZZ = ["--amplitude", "0", "--solve-for", "Izz", "--json"]


@pytest.mark.parametrize("block", [0.001, [0.001, 0.002], "timing=0.001"])
def test_an_uncertainty_block_that_is_no_mapping_exits_2_naming_it(tmp_path, block):
    # docs/errors.md: one line naming the field, exit 2 (without the check: exit 1, "internal error
    # (TypeError ...)" for a number, another field's wording for a list)
    res = _invert_cli(_boat_config(tmp_path, "c.yaml", block), "--period", "torsion=2.0+-0.001", *INVERT_IZZ)
    assert res.exit_code == 2, res.output
    assert "error: uncertainty: must be a mapping" in res.output and "Traceback" not in res.output


def test_the_timing_flag_overrides_the_blocks_for_a_period_without_its_std(tmp_path):
    # the block states timing 5 ms, --uncertainty timing=0.001: a --period without +- takes the flag's
    # 1 ms (README: invert budgets the block *below* its --uncertainty flags), so Izz's std is the one of
    # the period given with +-0.001 on a config without a block
    import json

    stated = _boat_config(tmp_path, "stated.yaml", {"timing": 0.005})
    plain = _boat_config(tmp_path, "plain.yaml", None)
    a = _invert_cli(stated, "--period", "torsion=2.0", "--uncertainty", "timing=0.001", *INVERT_IZZ)
    b = _invert_cli(plain, "--period", "torsion=2.0+-0.001", *INVERT_IZZ)
    c = _invert_cli(stated, "--period", "torsion=2.0", *INVERT_IZZ)
    assert a.exit_code == b.exit_code == c.exit_code == 0, (a.output, b.output, c.output)
    sa, sb, sc = (json.loads(r.stdout)["inertia"]["Izz"]["std"] for r in (a, b, c))
    assert sa == pytest.approx(sb, rel=1e-9)
    assert sc > 3 * sb  # the block's 5 ms itself is used without the flag (the test can tell)
