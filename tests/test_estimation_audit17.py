"""Estimation audit, session 17 (docs/design.md, "Estimation audit, session
17"): closed loops on cases nobody here wrote.  The audit's draws stay in
its throw-away harness; these tests pin what its findings changed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from bifilar.cli import main
from bifilar.studies.shorthands import apply_params, overlap_warnings

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
DRONE = CONFIGS / "drone_parallel.yaml"


def test_a_swept_path_a_shorthand_moves_afterwards_is_warned_of():
    """Audit17's bad-input row: ``sweep --param length=... --param
    rig.lengths.0=...`` labelled each point with the rig.lengths.0 it set,
    while ``length`` (applied after every dotted path) then shifted that
    wire: the point labelled ``rig.lengths.0: 1.2`` at ``length: 1.0`` had
    wire 1 at 0.85 m (its ``lengths``), without a word.  Now one warning
    line naming both parameters, on stderr and in the JSON's warnings.  On
    the old code: exit 0, no such warning."""
    r = CliRunner().invoke(main, ["sweep", str(DRONE), "--no-tensions", "--component", "Izz",
                                  "--param", "length=1.0", "--param", "rig.lengths.0=1.2", "--json"])
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    (p,) = doc["points"]
    # the mislabel itself, from the config's own numbers: wires 1.5 and 1.5 m; wire 1 set to 1.2 (mean 1.35),
    # then length 1.0 shifts both by -0.35: 0.85 and 1.15, not the 1.2 the point's params name
    assert p["params"]["rig.lengths.0"] == pytest.approx(1.2)
    assert p["lengths"] == pytest.approx([0.85, 1.15], abs=1e-12)
    hits = [w for w in doc["warnings"] if w.startswith("--param: rig.lengths.0 is set before length")]
    assert len(hits) == 1, doc["warnings"]
    assert sum("rig.lengths.0 is set before length" in ln for ln in r.stderr.splitlines()) == 1


@pytest.mark.parametrize("names, hit", [
    (["rig.lengths.1", "length_offset"], "rig.lengths.1 is set before length_offset"),
    (["spacing", "rig.attachments.0.1"], "rig.attachments.0.1 is set before spacing"),
    (["height", "rig.attachments.1.2"], "rig.attachments.1.2 is set before height"),
    (["rig.anchors.0.0", "ceiling_spacing"], "rig.anchors.0.0 is set before ceiling_spacing"),
])
def test_each_shorthand_that_moves_a_swept_path_is_named(names, hit):
    """Each pair where the shorthand moves the path's value (checked on the
    drone config by apply_params itself: the built value differs from the
    one set), named in one line."""
    from bifilar.config import read_yaml
    from bifilar.studies.shorthands import get_path

    cfg = read_yaml(DRONE)
    path = next(n for n in names if "." in n)
    short = next(n for n in names if "." not in n)
    base = {"length_offset": 0.1, "spacing": 0.4, "height": 0.1, "ceiling_spacing": 0.4}[short]
    built, _ = apply_params(cfg, {path: 0.123, short: base})
    assert get_path(built, path) != pytest.approx(0.123, abs=1e-6)  # the shorthand did move it
    (w,) = overlap_warnings(names)
    assert hit in w


@pytest.mark.parametrize("names", [
    ["spacing", "rig.lengths.0"],            # test_sweep's two-parameter sweep: separate entries
    ["height", "rig.attachments.0.0"],       # height moves z only
    ["spacing", "rig.attachments.0.2"],      # spacing scales x and y only
    ["length", "body.mass", "rig.anchors.1.2"],
])
def test_paths_no_shorthand_moves_are_quiet(names):
    """The control: a dotted path whose value the swept shorthands leave
    as set gets no warning."""
    assert overlap_warnings(names) == []
