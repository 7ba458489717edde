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


def _independent_modes(cfg: dict):
    """Audit17 row A's independent formulation (no bifilar import): the
    rest pose by SLSQP on m g z with |d_i| <= L_i, the tensions from the
    KKT conditions at it, and the linear periods from a central-difference
    Hessian of the Lagrangian m g z + T . (|d| - L) on the wires' tangent
    space, mass matrix diag(m, R I R^T) (small world-frame rotation vector)."""
    import numpy as np
    from scipy.linalg import eigh, null_space
    from scipy.optimize import minimize
    from scipy.spatial.transform import Rotation

    m, g = cfg["body"]["mass"], cfg["gravity"]
    inertia = np.array(cfg["body"]["inertia"]["tensor"], float)
    A, P, L = (np.array(cfg["rig"][k], float) for k in ("anchors", "attachments", "lengths"))

    def pose(q, R0):
        return q[:3], Rotation.from_rotvec(q[3:]).as_matrix() @ R0

    def gaps(q, R0):
        c, R = pose(q, R0)
        return np.linalg.norm(A - (c + P @ R.T), axis=1) - L

    x0 = np.r_[A.mean(0) - [0.0, 0.0, L.mean()], 0.0, 0.0, 0.0]
    res = minimize(lambda q: m * g * q[2], x0, method="SLSQP", options={"ftol": 1e-15, "maxiter": 1000},
                   constraints=[{"type": "ineq", "fun": lambda q: -gaps(q, np.eye(3))}])
    c, R = pose(res.x, np.eye(3))
    q0 = np.r_[c, 0.0, 0.0, 0.0]
    E = np.eye(6)
    J = np.array([(gaps(q0 + 1e-6 * e, R) - gaps(q0 - 1e-6 * e, R)) / 2e-6 for e in E]).T
    T = np.linalg.lstsq(J.T, -np.array([0, 0, m * g, 0, 0, 0.0]), rcond=None)[0]

    def lag(q):
        return m * g * q[2] + T @ gaps(q, R)

    h = 2e-4
    H = np.array([[(lag(q0 + h * (E[i] + E[j])) - lag(q0 + h * (E[i] - E[j])) - lag(q0 - h * (E[i] - E[j]))
                    + lag(q0 - h * (E[i] + E[j]))) / (4 * h * h) for j in range(6)] for i in range(6)])
    M = np.zeros((6, 6))
    M[:3, :3] = m * np.eye(3)
    M[3:, 3:] = R @ inertia @ R.T
    N = null_space(J)
    w2 = eigh(N.T @ (H + H.T) / 2 @ N, N.T @ M @ N, eigvals_only=True)
    return c, T, sorted(2 * np.pi / np.sqrt(w2))


#: audit17 row A: a trifilar on a sloped ceiling, wires 0.8 / 1.1 / 0.9199 m (the third as the slack refusal
#: advised), the CoM 0.6 m below the attachments and off the wires' centre (rest tilted), a full tensor;
#: and one with the CoM 0.15 m ABOVE its attachment plane, wires converging upward (stable)
_TENSOR = [[0.9, 0.05, -0.08], [0.05, 1.3, 0.11], [-0.08, 0.11, 1.7]]
_RIGS = {
    "tilted": {"gravity": 9.81, "body": {"mass": 7.0, "inertia": {"tensor": _TENSOR}},
               "rig": {"anchors": [[0.5, 0.0, 2.0], [-0.3, 0.45, 2.15], [-0.25, -0.5, 1.9]],
                       "attachments": [[0.35, 0.05, 0.6], [-0.2, 0.3, 0.6], [-0.15, -0.32, 0.6]],
                       "lengths": [0.8, 1.1, 0.9199]}},
    "com_above": {"gravity": 9.81, "body": {"mass": 3.0, "inertia": {"tensor": _TENSOR}},
                  "rig": {"anchors": [[0.15, 0.0, 1.5], [-0.075, 0.13, 1.5], [-0.075, -0.13, 1.5]],
                          "attachments": [[0.4, 0.02, -0.15], [-0.2, 0.35, -0.15], [-0.22, -0.33, -0.15]],
                          "lengths": [1.0, 1.05, 0.97]}},
}


@pytest.mark.parametrize("name", sorted(_RIGS))
def test_modes_on_unseen_trifilars_match_an_independent_formulation(name, tmp_path):
    """``modes --json`` against audit17's independent model.  Tolerances:
    the Hessian's central differences (step 2e-4) err by ~h^2 (4e-8) plus
    rounding eps V / h^2 (~2e-7 of the stiffness), so periods within 1e-6
    relative (the audit measured 5e-9 .. 4e-8); SLSQP's KKT residual is
    ~2e-6 N, so tensions within 1e-5 relative and the CoM within 1e-6 m."""
    import numpy as np
    import yaml

    cfg = _RIGS[name]
    p = tmp_path / "rig.yaml"
    p.write_text(yaml.safe_dump(cfg))
    r = CliRunner().invoke(main, ["modes", str(p), "--json"])
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    com, T, periods = _independent_modes(cfg)
    assert np.allclose(doc["equilibrium"]["com"], com, atol=1e-6)
    assert np.allclose(doc["equilibrium"]["tensions"], T, rtol=1e-5)
    got = sorted(md["period"] for md in doc["modes"])
    assert np.allclose(got, periods, rtol=1e-6), (got, periods)
