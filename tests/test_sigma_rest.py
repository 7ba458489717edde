"""The sigma points' rest poses from the base scene's pose (``rest_poses(...,
near=rest)``, session 24) against the path it replaces, ``rest_pose`` (its
global search) for each scene the batch's Newton from the start pose does
not accept.

The rig: a trifilar whose attachments are turned by -1 rad about the vertical
from its anchors, so that it hangs turned by ~1.0 rad from the start
orientation, beyond the 0.5 rad the start's Newton end may be taken at; the
"sigma points" are its attachments moved by ~2 mm (the size of a
configuration's attachment uncertainty times sqrt 3).  Without ``near``
every one goes to ``rest_pose`` (counted); with it none does, and each pose
is ``rest_pose``'s to 1e-12 m and 1e-12 in each entry of R (measured
<= 4e-16 m and 1.5e-15 on the 444 such scenes of tests/test_invert_roots.py;
here <= 3.4e-16).  A scene that cannot hang (a wire 1 m too long) keeps
``rest_pose``'s verdict: Newton from the base's pose ends turned by less
than ``NEAR_MAX_TURN`` but with a wire's tension negative, and is refused.
"""

from __future__ import annotations

import numpy as np
import pytest

import bifilar.analysis.batch_rest as br
from bifilar.analysis.equilibrium import rest_pose
from bifilar.config import scene_from_dict
from bifilar.errors import SlackWireError
from bifilar.rotations import matrix_to_rotvec
from bifilar.scene import scene_with


def _ring(r: float, z: float, phase: float) -> list:
    return [[r * np.cos(phase + k * 2 * np.pi / 3), r * np.sin(phase + k * 2 * np.pi / 3), z] for k in range(3)]


@pytest.fixture(scope="module")
def turned():
    cfg = {"gravity": 9.81, "body": {"mass": 2.0, "inertia": {"principal": [0.3, 0.25, 0.4]}},
           "rig": {"anchors": _ring(0.5, 0.0, 0.0), "attachments": _ring(0.4, 0.05, -1.0), "lengths": [1.0, 1.1, 0.9]}}
    s = scene_from_dict(cfg)
    r = rest_pose(s)
    rng = np.random.default_rng(1)
    sigma = [scene_with(s, attachments=s.attachments + rng.normal(0, 2e-3, (3, 3))) for _ in range(6)]
    return s, r, sigma


def _counting(monkeypatch) -> list:
    calls: list = []
    real = br._rest_or_error

    def counted(scene, errors, rigid=None):
        calls.append(scene)
        return real(scene, errors, rigid)

    monkeypatch.setattr(br, "_rest_or_error", counted)
    return calls


def test_turned_sigma_points_from_the_base_pose_are_rest_poses(turned, monkeypatch):
    s, r, sigma = turned
    assert np.linalg.norm(matrix_to_rotvec(r.R)) > br.NEWTON_START_MAX_TURN  # beyond the start's Newton end
    calls = _counting(monkeypatch)
    before = br.rest_poses(sigma, errors="return")
    assert len(calls) == len(sigma)  # every scene was a fallback to rest_pose: the path replaced
    got = br.rest_poses(sigma, errors="return", near=r)
    assert len(calls) == len(sigma)  # none is now
    for scene, old, new in zip(sigma, before, got):
        ref = rest_pose(scene)
        for pose in (old, new):
            assert np.max(np.abs(pose.com - ref.com)) <= 1e-12  # m
            assert np.max(np.abs(pose.R - ref.R)) <= 1e-12
            assert np.max(np.abs(pose.tensions / ref.tensions - 1)) <= 1e-12
            assert pose.lowest_z == pytest.approx(ref.lowest_z, abs=1e-12)


def test_a_scene_that_cannot_hang_keeps_its_verdict(turned, monkeypatch):
    """The base moved so that wire 1 carries 0.078 N; that wire 20 mm longer is slack
    (rest_pose), while Newton from the base's pose ends turned by only ~0.035 rad with
    its tension -0.008 N: refused by the tension check, so rest_pose decides."""
    s, r, sigma = turned
    u = s.attachments[0] / np.linalg.norm(s.attachments[0])
    base = scene_with(s, attachments=s.attachments + 0.2 * u)
    rb = rest_pose(base)
    assert 0 < rb.tensions[0] < 0.1
    slack = scene_with(base, lengths=base.lengths + np.array([0.02, 0.0, 0.0]))
    taut = scene_with(base, lengths=base.lengths + np.array([0.005, 0.0, 0.0]))
    with pytest.raises(SlackWireError):
        rest_pose(slack)
    calls = _counting(monkeypatch)
    got = br.rest_poses([taut, slack], errors="return", near=rb)
    assert isinstance(got[1], SlackWireError)
    assert calls == [slack]  # the near pass did not take it: rest_pose decided
    assert np.max(np.abs(got[0].com - rest_pose(taut).com)) <= 1e-12


def test_near_is_only_a_fallback_and_needs_a_pose_of_the_branch(turned, monkeypatch):
    """A scene the start's Newton takes is the same bits with or without
    ``near``; a ``near`` turned by more than NEAR_MAX_TURN from the scenes'
    poses is not followed (its Newton ends are refused, rest_pose decides)."""
    s, r, sigma = turned
    plain = scene_with(s, attachments=np.array(_ring(0.4, 0.05, 0.0)))  # hangs unturned
    a = br.rest_poses([plain], errors="return")[0]
    b = br.rest_poses([plain], errors="return", near=r)[0]
    assert np.array_equal(a.com, b.com) and np.array_equal(a.R, b.R)
    calls = _counting(monkeypatch)
    far = rest_pose(plain)  # a pose ~1 rad from the turned scenes'
    got = br.rest_poses(sigma[:2], errors="return", near=far)
    assert len(calls) == 2
    assert np.max(np.abs(got[0].R - rest_pose(sigma[0]).R)) <= 1e-12

