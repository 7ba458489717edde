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
