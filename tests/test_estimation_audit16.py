"""Estimation audit, session 16 (docs/design.md, "Estimation audit, session
16"): closed loops on cases nobody here wrote.  The audit's draws stay in its
throw-away harness; these tests pin what its findings changed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from bifilar.cli import main

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def _invert_file(tmp_path, entry: str):
    """``invert --measurements`` of a file with one torsion entry on the KTH
    trifilar table: (exit code, stderr, JSON or None)."""
    cfg = (CONFIGS / "trifilar_kth.yaml").resolve()
    f = tmp_path / "m.yaml"
    f.write_text(f"config: {cfg}\nmeasurements:\n  - {{mode: torsion, amplitude: 0, {entry}}}\n")
    r = CliRunner().invoke(main, ["invert", "--measurements", str(f), "--json"])
    return r.exit_code, r.stderr, (json.loads(r.stdout) if r.exit_code == 0 else None)


@pytest.mark.parametrize("entry, key", [
    # a stopwatch's trial std beside a period: the old code read the period with the default 1 ms std
    # (measurements[0].std 0.001, std_given false) however large the stated time_std (here 50x it), exit 0
    ("period: 1.2, time_std: 0.05", "time_std"),
    # a period's std beside stopwatch trials: the old code took the trials' scatter and ignored it
    ("cycles: 10, times: [12.00, 12.01], std: 0.5", "std"),
    # a recording's option beside a period: ignored
    ("period: 1.2, quantity: angle", "quantity"),
])
def test_a_key_another_way_of_giving_the_measurement_reads_is_refused(tmp_path, entry, key):
    """Audit16's bad-input row: a measurement entry's key that only another
    way of giving it (period, times, signal) reads was silently ignored, so
    a stated timing uncertainty could be dropped for the 1 ms default
    (an understated std, exit 0, no word).  Now exit 2, one line naming the
    key.  On the old code these exit 0."""
    code, err, doc = _invert_file(tmp_path, entry)
    assert code == 2, (code, doc and doc["measurements"][0])
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and f"measurements.0.{key}" in lines[0], err
    assert "Traceback" not in err


def test_a_period_with_its_own_std_is_still_read(tmp_path):
    """The control: ``std`` beside ``period`` (and ``time_std`` beside
    ``times``) are the keys those ways read, kept as given."""
    code, err, doc = _invert_file(tmp_path, "period: 1.2, std: 0.004")
    assert code == 0, err
    assert doc["measurements"][0]["std"] == pytest.approx(0.004) and doc["measurements"][0]["std_given"]


def _heavy(n: int, mass: float, stiffness: float | None, length: float = 2.0) -> dict:
    """A level n-wire rig of vertical 2 m wires on a 0.4 m circle, 20 kg m^2
    about the vertical (the audit's heavy rig)."""
    import math

    ang = [2 * math.pi * k / n + 0.3 for k in range(n)]
    pts = [[0.4 * math.cos(a), 0.4 * math.sin(a)] for a in ang]
    rig = {"anchors": [[x, y, 0.0] for x, y in pts], "attachments": [[x, y, 0.05] for x, y in pts],
           "lengths": [length] * n}
    if stiffness is not None:
        rig["stiffness"] = stiffness
    return {"name": "heavy", "body": {"mass": mass, "inertia": {"principal": [12.0, 14.0, 20.0]}}, "rig": rig}


def test_a_stated_stiffness_warns_of_what_the_model_does_not_carry():
    """Audit16's stiffness row: a 200 kg trifilar on 2 m wires of EA 1e5 N
    (each carries 654 N: 13.1 mm of stretch, strain 6.5e-3).  Session 16
    warned that the 2 and 3 wire model ignored EA and the 4-wire runs kept
    the wires unstretched; session 17 carries the stretch (test_stretch.py),
    so the warning now says what is still not carried, EA's own
    uncertainty: how far a 10 % error in it moves the loaded lengths.  The
    quiet cases stay quiet.  The stated size is checked against the model:
    the trifilar's linear torsion with every wire 13.08 mm longer is longer
    by strain / 2 (the parallel-wire law T ~ sqrt(L) for vertical wires;
    measured 0.998 of it, the 5 cm attachment offset above the CoM: 1 %
    allowed)."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.config import plausibility_warnings, scene_from_dict

    s3 = scene_from_dict(_heavy(3, 200.0, 1e5), "heavy3", warn=False)
    w3 = [w for w in plausibility_warnings(s3) if w.startswith("rig.stiffness")]
    assert len(w3) == 1 and "13.1 mm" in w3[0] and "EA's uncertainty is budgeted" in w3[0] and "1.3 mm" in w3[0], w3
    assert "do not use it" not in w3[0] and "\n" not in w3[0]
    s4 = scene_from_dict(_heavy(4, 200.0, 1e5), "heavy4", warn=False)
    w4 = [w for w in plausibility_warnings(s4) if w.startswith("rig.stiffness")]
    assert len(w4) == 1 and "9.81 mm" in w4[0] and "unstretched" not in w4[0], w4
    # a 10 kg body on the same wires stretches 0.65 mm (below a length's 1 mm std): no warning; nor without EA
    for cfg in (_heavy(3, 10.0, 1e5), _heavy(4, 10.0, 1e5), _heavy(3, 200.0, None)):
        assert not [w for w in plausibility_warnings(scene_from_dict(cfg, "h", warn=False))
                    if w.startswith("rig.stiffness")]
    # the size the warning states: the loaded rig's torsion against the rig at rig.lengths
    strain = 200.0 * 9.81 / 3 / 1e5

    def torsion(cfg):
        s = scene_from_dict(cfg, "h", warn=False)
        return linear_modes(s, rest_pose(s)).get("torsion").period

    ratio = torsion(_heavy(3, 200.0, None, 2.0 * (1 + strain))) / torsion(_heavy(3, 200.0, None))
    assert ratio - 1 == pytest.approx(strain / 2, rel=0.01)


def test_the_config_warning_reaches_the_json_warnings(tmp_path):
    """Audit16's found-not-fixed: the config layer's warnings (here the
    stretch warning above) went to stderr only, so a program reading
    ``invert --json`` saw an answer 0.65 % high with an empty ``warnings``
    list.  Now ``emit_json`` puts them at the head of the document's
    ``warnings`` (created where a command has none, as ``modes``), once
    each; a config without warnings keeps its documents as they were."""
    import yaml

    cfg = tmp_path / "heavy3.yaml"
    cfg.write_text(yaml.safe_dump(_heavy(3, 200.0, 1e5)))
    quiet = tmp_path / "quiet3.yaml"
    quiet.write_text(yaml.safe_dump(_heavy(3, 10.0, 1e5)))
    runner = CliRunner()
    for path, warned in ((cfg, True), (quiet, False)):
        r = runner.invoke(main, ["modes", str(path), "--json"])
        assert r.exit_code == 0, r.stderr
        doc = json.loads(r.stdout)
        # the config's stretch warning; json25 (session 25) put the rest pose's warnings into the JSON too,
        # among them session 17's stretch-coupling line (also "rig.stiffness: ...", the computation's, for the
        # quiet rig as well): not the config's
        mine = [w for w in doc.get("warnings", []) if w.startswith("rig.stiffness: at an equal share")]
        # (the symmetric trifilar's equal swings are warned as close modes, session 20: not the config's)
        others = [w for w in doc.get("warnings", [])
                  if "have periods within" not in w and "the wires' stretch couples with the motion" not in w]
        assert len(mine) == (1 if warned else 0) and bool(others) == warned, doc.get("warnings")
        # still logged as it arises (the config's warning; session 17's stretch-coupling warning of the modes is
        # the computation's, on stderr for the quiet rig too: its swings' elastic periods differ by 5e-6)
        assert ("warning: rig.stiffness: at an equal share" in r.stderr) == warned
        T = next(m["period"] for m in doc["modes"] if m["label"] == "torsion")
        r = runner.invoke(main, ["invert", str(path), "--period", f"torsion={T:.9f}", "--json"])
        assert r.exit_code == 0, r.stderr
        doc = json.loads(r.stdout)
        assert [w for w in doc["warnings"] if w.startswith("rig.stiffness")] == mine, doc["warnings"]
