"""invert's near-hold refusal (twin26, ``invert._near_hold_refusal``) with
several hangings near the held-direction rule names every one of them, not
only the first (twin26's left item, session 27).

The rig is teeth26a's leaning 4-wire twin (near the rule in every drawn
config, none crossing it), hung twice in the same orientation (two hangings
of one body, `--rig shared`: one measured rig), its swing-x timed at 5 ms in
each: the rigid hold's bias is common to both periods, so Iyy's std is
refused, and the reason must say that both hangings come near the rule."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from test_teeth26a import _cfg, _swing_x
from conftest import in_tmpdir


@pytest.fixture(scope="module")
def refusal():
    import yaml

    from bifilar.cli import main

    _, _, T = _swing_x()
    doc = {"solve_for": ["Iyy"],
           "hangings": [{"name": name, "config": _cfg(), "rotation": "identity",
                         "measurements": [{"mode": "swing-x", "period": float(T), "std": 0.005, "amplitude": 0}]}
                        for name in ("first", "second")]}
    runner = CliRunner()
    with in_tmpdir():
        with open("m.yaml", "w") as f:
            yaml.safe_dump(doc, f)
        r = runner.invoke(main, ["invert", "--measurements", "m.yaml", "--no-ladder", "--json"])
    assert r.exit_code == 0, r.stderr
    return json.loads(r.stdout)


def test_the_refusal_names_every_hanging_near_the_rule(refusal):
    iy = refusal["inertia"]["Iyy"]
    assert iy["std"] is None, iy
    why = refusal["std_unavailable"]
    assert why and "within a factor 10 of holding" in why, why
    assert "'first'" in why and "'second'" in why, why
    assert why.startswith("hangings 'first' and 'second' (figures of 'first', the nearest): "), why
    # the quoted figures are a hanging's own (both hang alike: 100 % of the drawn configs near the rule)
    assert "in 100 % of the configs" in why, why
