"""Two independent formulations of the same physics: the thesis's five-angle Kane
model and the default maximal-coordinate model agree on the thesis's cases."""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.kane_run import from_world, kane_map, simulate_kane, to_world
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
from bifilar.config import load_scene
from bifilar.errors import InputError
from bifilar.models import kane as kn
from bifilar.models import maximal as mx

from conftest import CONFIGS, trapezoid


def _compare(scene, rk, rm, L):
    # positions to 1e-8 of the wire length and quaternions to 1e-8 (issue: 1e-8 over several periods)
    assert np.max(np.abs(rk.y[:, 0:3] - rm.y[:, 0:3])) < 1e-8 * L
    dq = np.minimum(np.abs(rk.y[:, 3:7] - rm.y[:, 3:7]).max(axis=1), np.abs(rk.y[:, 3:7] + rm.y[:, 3:7]).max(axis=1))
    assert np.max(dq) < 1e-8
    np.testing.assert_allclose(rk.tensions, rm.tensions, rtol=1e-7)


def test_mapping_roundtrip_at_rest():
    s = load_scene(CONFIGS / "thesis_lin2_pitch.yaml")
    rest = rest_pose(s)
    km = kane_map(s)
    y13 = mx.pack(rest.com, rest.q)
    th = from_world(km, y13)
    # the rest pose of the thesis: theta = [0, pi/6, pi/2, 0, 0]
    np.testing.assert_allclose(th[:5], [0, np.pi / 6, np.pi / 2, 0, 0], atol=1e-12)
    # NOTES.md: CoM 0.5 below the middle of CD, lambda = arccos((b'/2)/r)
    r = np.hypot(2.5, 0.5)
    assert km.p.r == pytest.approx(r, rel=1e-14)
    assert km.p.lam == pytest.approx(np.arccos(2.5 / r), rel=1e-12)
    np.testing.assert_allclose(to_world(km, th)[0], y13, atol=1e-13)


@pytest.mark.parametrize("cfg", ["thesis_plate_rest.yaml", "thesis_lin2_pitch.yaml"])
@pytest.mark.parametrize("mode", ["torsion", "swing-y", "swing-x"])
def test_trajectories_agree_over_three_periods(cfg, mode):
    s = load_scene(CONFIGS / cfg)
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    rk = simulate_kane(s, rest, ms, mode=mode, amplitude=0.05, periods=3, rtol=1e-12)
    rm = simulate(s, mode, 0.05, 3, rest=rest, modes=ms, rtol=1e-12)
    _compare(s, rk, rm, 5.0)
    assert rk.period == pytest.approx(rm.period, rel=1e-10)
    assert rk.max_constraint_violation < 1e-10  # thesis: 3.9e-5


def test_cylinder_of_kane_and_tseng_6_4_both_models():
    """Thesis 6.4: l = 2b, l' = 1.8b, b = b' = g; the thesis's initial angles; both models."""
    s = load_scene(CONFIGS / "thesis_cylinder_6_4.yaml")
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    th0 = [0.0, np.arcsin(0.5 * np.sin(np.pi / 8)), 7 * np.pi / 8, np.pi / 4]
    rk = simulate_kane(s, rest, ms, theta=th0, periods=2, rtol=1e-12)
    km = kane_map(s)
    y0 = to_world(km, kn.complete_initial_state(np.array(th0), np.zeros(4), km.p))[0]
    rm = simulate(s, None, float("nan"), 2, rest=rest, modes=ms, y0=y0, t_end=rk.t[-1], rtol=1e-12)
    _compare(s, rk, rm, 19.62)
    assert rk.energy_drift < 1e-9 and rm.energy_drift < 1e-9
    # the rotation about the vertical (theta4) starts at pi/4 and the unequal wires tilt the body
    # (theta1, Fig 6.4.2): both swing through zero within the run
    assert np.ptp(rk.theta[:, 3]) > 1.0 and np.ptp(rk.theta[:, 0]) > 1e-3


def test_vertical_wires_are_singular_for_kane_not_for_default():
    s = trapezoid(b=5.0, bp=5.0)  # parallel wires: theta2 = 0 at rest
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    # refused up front as an input error (the rig hangs where the thesis's chart is singular) ...
    with pytest.raises(InputError, match="singular"):
        simulate_kane(s, rest, ms, mode="torsion", amplitude=0.05, periods=1)
    # ... and the model itself raises its own error at theta2 = 0
    km = kane_map(s)
    with pytest.raises(kn.KaneSingularityError, match="vertical wires"):
        kn.rhs(0.0, np.r_[0.0, 0.0, np.pi / 2, 0.0, 0.0, np.zeros(5)], km.p)
    r = simulate(s, "torsion", 0.05, 3, rest=rest, modes=ms, rtol=1e-11)
    assert r.max_constraint_violation < 1e-10 and r.period is not None
