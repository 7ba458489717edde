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


# a four-wire rig (tests/test_invert_roots.py's random_scene, seed 4002, rounded; the lengths those of the
# pose with the body frame on the world's, so that it hangs on all four wires): a sigma point of a wire's
# length or end leaves one wire slack (either sign), rest_pose's verdict
FOUR = {"body": {"mass": 38.352, "inertia": {"tensor": [[0.86539, -0.38382, -0.07823], [-0.38382, 1.04141, -0.12847],
                                                         [-0.07823, -0.12847, 1.13014]]}},
        "rig": {"anchors": [[0.1873, -0.6237, 1.6939], [0.6052, 0.2403, 1.6292], [-0.3582, 0.5438, 1.6276],
                            [-0.5687, -0.3172, 1.7553]],
                "attachments": [[0.1302, -0.4335, 0.1836], [0.4207, 0.167, 0.1836], [-0.249, 0.378, 0.1836],
                                [-0.3953, -0.2205, 0.1836]]}}
FOUR["rig"]["lengths"] = np.linalg.norm(np.subtract(FOUR["rig"]["anchors"], FOUR["rig"]["attachments"]), axis=1).tolist()


def _settle_all(points, jobs, rests, res):
    """second_order._settle's path before (session 24): every deferred rest pose decided."""
    from bifilar.analysis.batch_rest import Deferred

    for rs in rests.values():
        for q, r in enumerate(rs):
            if isinstance(r, Deferred):
                rs[q] = r.settle("return")


def test_a_sigma_point_whose_other_one_cannot_hang_is_not_searched(monkeypatch):
    """second_order fails an input when either sigma point cannot hang, so the
    other's global search (rest_pose, ~7 ms) is skipped when the first is
    known to fail; against deciding every one (the path before): the same
    budgets bit for bit and the same failed inputs, with fewer searches."""
    import bifilar.estimation.second_order as so
    from bifilar.estimation.honest import honest_stds

    scene = scene_from_dict(FOUR, warn=False)
    seen: list = []
    real = so.second_order

    def recording(*a, **k):
        budget, failed = real(*a, **k)
        seen.append((budget.covariance.tobytes(), sorted(budget.contributions), list(failed)))
        return budget, failed

    monkeypatch.setattr(so, "second_order", recording)
    import bifilar.estimation.invert as inv
    monkeypatch.setattr(inv, "second_order", recording)
    calls = _counting(monkeypatch)
    requests = [("Izz", "torsion"), ("Ixx", 2)]
    got = honest_stds(scene, requests, {}, fallbacks=[1.0, 1.0])
    got_seen, n_got = list(seen), len(calls)
    seen.clear(), calls.clear()
    monkeypatch.setattr(so, "_settle", _settle_all)
    ref = honest_stds(scene, requests, {}, fallbacks=[1.0, 1.0])
    assert got == ref and got_seen == seen
    failed = seen[0][2]
    assert any(k.startswith("length") for k in failed) and "mass" not in failed  # some inputs fail, some not
    assert n_got + len(failed) // 2 <= len(calls)  # measured: 29 searches against 53


def test_settle_decides_exactly_the_verdicts_that_are_read():
    """_settle on stubs: a deferred sigma point is searched unless its point
    already fails (a hanging of it, or its cached result) or its input's
    other sigma point does; other points (a pair's corner) only by the
    first rule; in the order of the points."""
    import bifilar.estimation.second_order as so
    from bifilar.analysis.batch_rest import Deferred

    order: list = []

    class Stub(Deferred):
        def __init__(self, name, hangs):
            self.name, self.hangs = name, hangs

        def settle(self, errors="raise"):
            order.append(self.name)
            return self.name if self.hangs else SlackWireError("rig.lengths", "slack")

    pose = object()
    points = {pid: None for pid in [("a", 1), ("a", -1), ("b", 1), ("b", -1), ("c", 1), ("c", -1), ("d", 1),
                                    ("d", -1), ("a", "b", 1, 1), ("a", "b", -1, 1)]}
    jobs = {0: [(pid, None, None) for pid in [("b", -1), ("a", 1), ("a", -1), ("b", 1), ("a", "b", 1, 1),
                                              ("a", "b", -1, 1)]],
            1: [(pid, None, None) for pid in [("c", 1), ("c", -1), ("d", -1), ("a", "b", -1, 1)]]}
    rests = {0: [Stub("b-", False), Stub("a+", False), Stub("a-", True), Stub("b+", True), Stub("ab++", True),
                 Stub("ab-+", True)],
             1: [SlackWireError("rig.lengths", "slack"), Stub("c-", True), Stub("d-", True), pose]}
    res = {pid: {} for pid in points}
    res[("d", 1)] = {1: None}  # cached: cannot hang
    res[("a", "b", -1, 1)] = {2: None}
    so._settle(points, jobs, rests, res)
    assert order == ["a+", "b+", "b-", "ab++"]
    assert rests[0][2] is so.SKIPPED and rests[1][1] is so.SKIPPED and rests[1][2] is so.SKIPPED
    assert rests[0][5] is so.SKIPPED and rests[1][3] is pose
    assert rests[0][3] == "b+" and isinstance(rests[0][0], SlackWireError)
