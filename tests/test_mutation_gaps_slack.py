"""Tests written to kill surviving mutants of the slack-wire advice
(``bifilar/analysis/slack_advice.py``; see docs/mutation.md).  The advice's
numbers are checked against independent rest-pose solves of the rig with
the printed lengths (and finite differences of them), and against the
documented aim (1/4 of m g / n for a shortened wire) -- never against
output of the code under test.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from bifilar.analysis.equilibrium import rest_pose
from bifilar.config import scene_from_dict
from bifilar.errors import SlackWireError

from test_slack_advice import CASES, G, MASS, _run, _write

#: documented (docs/errors.md, tests/test_slack_advice.py): a shortened wire is aimed at 1/4 of an equal
#: share of the weight, and the advice is an amount only if every wire then carries at least 1/8 of it
AIM_SHARE, FLOOR_SHARE = 0.25, 0.125

ADVICE = re.compile(r"wire (\d+) [^;]*?shorten it by [\d.]+ mm, to ([\d.]+) m\b")


def _scene(rig):
    anchors, att, L = rig
    return scene_from_dict({"gravity": G, "body": {"mass": MASS, "inertia": {"principal": [1.2, 1.5, 2.4]}},
                            "rig": {"anchors": anchors, "attachments": att, "lengths": list(map(float, L))}},
                           warn=False)


def _advice(tmp_path, rig):
    """(message, {wire (1-based): advised length string})."""
    cfg = tmp_path / "rig.yaml"
    _write(cfg, rig)
    r = _run("modes", cfg, "--json")
    assert r.exit_code == 2 and "slack" in r.stderr, r.stderr
    return r.stderr, dict((int(w), x) for w, x in ADVICE.findall(r.stderr))


def _with(rig, lengths: dict):
    L = list(rig[2])
    for w, x in lengths.items():
        L[w - 1] = float(x)
    return rig[0], rig[1], L


def _tensions(rig):
    return rest_pose(_scene(rig)).tensions


def _own_slope(rig, w, h=1e-4):
    """dT_w / d(-L_w) (N per m of shortening) of wire ``w`` by central differences of rest poses."""
    L = rig[2][w - 1]
    Tp = _tensions(_with(rig, {w: L - h}))[w - 1]
    Tm = _tensions(_with(rig, {w: L + h}))[w - 1]
    return (Tp - Tm) / (2 * h)


@pytest.mark.parametrize("name", ["3-wire", "4-wire"])
def test_advised_wire_carries_the_documented_share_and_the_printed_slope_is_its_own(tmp_path, name):
    """Kills ``ADVISED_SHARE`` 0.25 -> 0.5 (the old tests only asked for
    1/8 of m g / n) and the printed slope's ``* 1e-3`` (N per m -> per mm)
    changed to ``/ 1e-3`` or ``* 2e-3``.  Truth: rest poses of the rig with
    the printed lengths.  Each shortened wire carries 1/4 of m g / n within
    the advice's 1 % and what rounding the length to its printed digit (half
    a unit of it) moves, at the wire's own slope found by central
    differences of rest poses; the printed "~X N per mm" is the largest such
    slope within 10 % (the advice's slope is from its last Newton step, one
    step from the printed length)."""
    rig = CASES[name]
    msg, adv = _advice(tmp_path, rig)
    assert adv, msg
    new = _with(rig, adv)
    T = _tensions(new)
    n = len(rig[2])
    aim = AIM_SHARE * MASS * G / n
    slopes = {}
    for w, x in adv.items():
        slopes[w] = _own_slope(new, w)
        half_digit = 0.5 * 10.0 ** -len(x.split(".")[1])
        assert abs(T[w - 1] - aim) <= 0.01 * aim + abs(slopes[w]) * half_digit, (w, T[w - 1], aim)
    printed = float(re.search(r"changes by ~([\d.e+-]+) N per mm", msg).group(1))
    assert printed == pytest.approx(max(abs(s) for s in slopes.values()) * 1e-3, rel=0.1)


def test_finer_lengths_only_where_the_rig_needs_them(tmp_path):
    """Kills ``res < 1e-4 -> <=`` and ``-> < 2e-4`` (the 'cut it to' note
    on advice at 0.1 mm) and the finer resolutions ``1e-5 -> 2e-5``.  The
    documented rule: lengths to 0.1 mm, finer only where the rig needs it,
    and then the note names the printed resolution.  Truth: on the stiff
    five-wire ring (~900 N per mm) the printed lengths are at 0.01 mm, and
    the same lengths rounded to 0.1 mm give a rig (solved here) on which a
    wire carries less than 1/8 of m g / n or is slack; on the trifilar
    (~0.7 N per mm) 0.1 mm is enough and no note is printed."""
    msg, adv = _advice(tmp_path, CASES["3-wire"])
    assert {len(x.split(".")[1]) for x in adv.values()} == {4}
    assert "so cut" not in msg, msg
    rig = CASES["5-wire, two slack"]
    msg, adv = _advice(tmp_path, rig)
    digits = {len(x.split(".")[1]) for x in adv.values()}
    assert digits == {5}, msg
    assert re.search(r"so cut them to ([\d.]+) mm", msg).group(1) == "0.01"
    share = MASS * G / len(rig[2])
    assert _tensions(_with(rig, adv)).min() >= FLOOR_SHARE * share
    coarse = _with(rig, {w: round(float(x), 4) for w, x in adv.items()})
    try:
        T = _tensions(coarse)
    except SlackWireError:
        return
    assert T.min() < FLOOR_SHARE * share
