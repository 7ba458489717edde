"""The config's ``uncertainty:`` block is what every command budgets.
``sweep`` and ``plan`` took it, and ``--write-config`` writes it, but
``invert CONFIG`` ignored it: the advice's invert options printed the
default 1 mm length std's figure (0.46) beside the sweep's 0.63 for a config
stating 5 mm, and a stated gravity uncertainty entered invert (session 9)
but not the sweep's sigma."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

from bifilar.cli import main

ROOT = Path(__file__).resolve().parents[1]
BOAT = ROOT / "configs" / "solar_boat.yaml"


def _cli(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _config(tmp_path, name, unc):
    cfg = yaml.safe_load(BOAT.read_text())
    if unc is None:
        cfg.pop("uncertainty", None)
    else:
        cfg["uncertainty"] = unc
    p = tmp_path / name
    p.write_text(yaml.safe_dump(cfg))
    return p


def _std(res, comp="Izz"):
    assert res.exit_code == 0, res.output
    return json.loads(res.stdout)["inertia"][comp]["std"]


PERIOD = ["--period", "torsion=2.0+-0.001", "--amplitude", "0", "--solve-for", "Izz", "--json"]


def test_invert_budgets_the_configs_uncertainty_block_below_the_flags(tmp_path):
    plain = _config(tmp_path, "plain.yaml", None)
    stated = _config(tmp_path, "stated.yaml", {"length": 0.005})
    default = _std(_cli("invert", plain, *PERIOD))
    by_flag = _std(_cli("invert", plain, *PERIOD, "--uncertainty", "length=0.005"))
    by_block = _std(_cli("invert", stated, *PERIOD))
    assert by_flag > 1.1 * default  # the length term matters here, so the test can tell
    assert by_block == pytest.approx(by_flag, rel=1e-12)
    # the flag overrides the block
    assert _std(_cli("invert", stated, *PERIOD, "--uncertainty", "length=0.001")) == pytest.approx(default, rel=1e-12)


def test_a_bad_block_value_exits_2_naming_it(tmp_path):
    bad = _config(tmp_path, "bad.yaml", {"length": -1})
    res = _cli("invert", bad, *PERIOD)
    assert res.exit_code == 2
    assert "uncertainty.length" in res.output and "Traceback" not in res.output


@pytest.mark.parametrize("unc", [{"length": 0.005}, {"gravity": 1e-3}])
def test_the_sweeps_advice_reproduces_its_sigma_with_the_written_config(tmp_path, unc):
    src = _config(tmp_path, "src.yaml", unc)
    point = tmp_path / "point.yaml"
    res = _cli("sweep", src, "--param", "spacing=2.5:2.5:1", "--component", "Izz", "--write-config", point, "--json")
    assert res.exit_code == 0, res.output
    adv = json.loads(res.stdout)["recommendation"]["amplitude_advice"]["components"]["Izz"]
    base = _config(tmp_path, "base.yaml", None)
    res0 = _cli("sweep", base, "--param", "spacing=2.5:2.5:1", "--component", "Izz", "--json")
    sigma0 = json.loads(res0.stdout)["recommendation"]["amplitude_advice"]["components"]["Izz"]["sigma"]
    assert adv["sigma"] > 1.1 * sigma0  # the stated uncertainty is in the sweep's sigma (gravity was not)
    std = _std(_cli("invert", point, *adv["invert_options"].split(), "--json"))
    # the sweep/invert equality (2e-6 at the default block) but for the inputs' amplitude-factor terms that
    # invert adds and the sweep's sigma leaves out (input_factor_terms false: 2e-4 here)
    assert std == pytest.approx(adv["sigma"], rel=1e-3)
