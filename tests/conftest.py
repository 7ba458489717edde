"""Shared fixtures: scenes of the thesis built in code (independent of the
example files, which have their own tests)."""

from __future__ import annotations

import contextlib
import os
import tempfile
from dataclasses import replace
from pathlib import Path

# One BLAS thread per test process, set before numpy is first imported (no plugin imports it earlier;
# the xdist workers and sweep's process pool inherit it; a value already in the environment is kept).
# `-n 2` runs two workers on the two cores: OpenBLAS's default of a thread per core put four threads on
# them, and its threads cost more than they gain on the signal fits' tall least-squares problems.
# Measured (suite24, session 24; CPU user+sys of one file, 1 thread / default, back to back at load 6-8):
# test_period_coverage 6.6 / 11.9 s, test_signal_quantisation 26.0 / 36.6 s, test_invert_roots 20.0 /
# 20.3 s; `bifilar period` of a KTH record: the same JSON bit for bit.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# odeint's C kernels (bifilar.models.native_kernel) built in the system's temporary directory, one per user, never
# the user's ~/.cache; kept between runs: a cold run builds ~0.06 s CPU a wire count and zero pattern (13 for
# test_point_cost.py: +0.9 s; warm -0.3 s), the same numbers bit for bit either way (ckern, session 25)
os.environ.setdefault("BIFILAR_CACHE_DIR", os.path.join(tempfile.gettempdir(), f"bifilar-tests-native-{os.getuid()}"))

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bifilar.config import scene_from_dict  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ROOT / "configs"
# the real recordings' folder (../shared, its data/ skipped where absent); BIFILAR_SHARED_DIR names another, so
# that a checkout elsewhere (a git worktree two levels down) runs the real-data tests instead of skipping them
SHARED = Path(os.environ.get("BIFILAR_SHARED_DIR") or ROOT.parent / "shared")

# thin 100 kg plate 5 m x 2.5 m: x across the attachment line, y along it, z vertical
PLATE_I = [100 * 5**2 / 12, 100 * 2.5**2 / 12, 100 * (5**2 + 2.5**2) / 12]


def trapezoid(b=10.0, bp=5.0, l1=5.0, l2=None, h=0.0, inertia=PLATE_I, mass=100.0, g=9.81):
    """Thesis-style two-wire scene: anchors b apart along y at z = 0,
    attachments b' apart, h above the CoM (h = 0.5 for the 1 m thick plate)."""
    l2 = l1 if l2 is None else l2
    return scene_from_dict({
        "gravity": g,
        "body": {"mass": mass, "inertia": {"principal": list(inertia)}},
        "rig": {"anchors": [[0, -b / 2, 0], [0, b / 2, 0]],
                "attachments": [[0, -bp / 2, h], [0, bp / 2, h]],
                "lengths": [l1, l2]},
    })


@pytest.fixture
def thesis_plate():
    return trapezoid()


def close(a, b, rel):
    return np.all(np.abs(np.asarray(a) - np.asarray(b)) <= rel * np.maximum(np.abs(b), 1e-300))


def measured_scene(truth, rng, unc):
    """The scene an experimenter writes down: every input of ``truth`` off by a
    normal error of the size in ``unc`` (m; ``mass`` relative; ``com`` a shift
    of the attachments relative to the CoM), drawn from ``rng``."""
    n = truth.n_wires
    return replace(truth, mass=truth.mass * (1 + rng.normal(0, unc["mass"])),
                   lengths=truth.lengths + rng.normal(0, unc["length"], n),
                   anchors=truth.anchors + rng.normal(0, unc["position"], (n, 3)),
                   attachments=truth.attachments + rng.normal(0, unc["position"], (n, 3))
                   - rng.normal(0, unc["com"], 3))


# the KTH trifilar table (configs/trifilar_kth.yaml, copied so that tests do not follow that file; R = 1 m,
# wires 0.995 m) with an off-centre test mass: twisted toward 2 asin(L / 2R) = 1.0424 rad its wires near
# the horizontal go slack in the motion (tests/test_cli.py, tests/test_start_pose.py)
TRIFILAR = """\
body:
  parts:
    - {shape: slender_beam, mass: 0.282667, length: 1.7320508, position: [-0.25, 0.4330127, 0.0], axis: [-0.8660254, -0.5, 0.0]}
    - {shape: slender_beam, mass: 0.282667, length: 1.7320508, position: [-0.25, -0.4330127, 0.0], axis: [0.8660254, -0.5, 0.0]}
    - {shape: slender_beam, mass: 0.282666, length: 1.7320508, position: [0.5, 0.0, 0.0], axis: [0.0, 1.0, 0.0]}
    - {shape: point_mass, mass: 0.02094, position: [0.5, 0.0, 0.0]}
rig:
  attachments_frame: parts
  anchors:     [[1.0, 0.0, 0.995], [-0.5, 0.8660254, 0.995], [-0.5, -0.8660254, 0.995]]
  attachments: [[1.0, 0.0, 0.0], [-0.5, 0.8660254, 0.0], [-0.5, -0.8660254, 0.0]]
  lengths:     [0.995, 0.995, 0.995]
"""


# audit18's 3-wire thesis plate (row H2; not a shipped config): 2.5 kg, wires 1 m on a 0.2 m circle,
# attachments 20 mm above the CoM; its torsion towards the wires' half turn at pi rad (an unstable
# equilibrium) lengthens its period as -ln(pi - A): T / T_lin 1.98 at 2.8 rad
PLATE3_YAML = """name: plate3
gravity: 9.81
body:
  mass: {mass}
  inertia: {{tensor: [[0.03, 0.0, 0.0], [0.0, 0.035, 0.0], [0.0, 0.0, 0.06]]}}
rig:
  anchors: [[0.2, 0.0, 1.02], [-0.1, 0.17320508, 1.02], [-0.1, -0.17320508, 1.02]]
  attachments: [[0.2, 0.0, 0.02], [-0.1, 0.17320508, 0.02], [-0.1, -0.17320508, 0.02]]
  lengths: [1.0, 1.0, 1.0]
"""


def plate3_yaml(mass=2.5) -> str:
    """The plate3 config text with ``body.mass`` written as ``mass`` (kg, or
    any text a test puts there)."""
    return PLATE3_YAML.format(mass=mass)


def plate3_scene(mass=2.5):
    """The plate3 :class:`~bifilar.scene.Scene` (``mass`` kg)."""
    import yaml

    sc = scene_from_dict(yaml.safe_load(plate3_yaml(mass)))
    return sc[0] if isinstance(sc, tuple) else sc


@pytest.fixture(scope="session")
def plate3_path(tmp_path_factory):
    """Path of the plate3 config (2.5 kg) written once per session."""
    path = tmp_path_factory.mktemp("plate3") / "plate3.yaml"
    path.write_text(plate3_yaml())
    return path


def two_wire_yaml(mass, principal, ys, anchor_z, attachment_z, length, name=None, gravity=None) -> str:
    """The config text (YAML) of a two-wire rig whose wires hang in the
    y-z plane: anchors at ``(0, y, anchor_z)`` (world frame, m) and
    attachments at ``(0, y, attachment_z)`` (body frame about the CoM, m)
    for each ``y`` of ``ys``, both wires ``length`` (m) long; ``mass`` (kg),
    ``principal`` moments (kg m^2), optional ``name`` and ``gravity``
    (m/s^2).  Ends with a newline, so that a test may append keys
    (``uncertainty: ...``)."""
    def vec(v):
        return "[" + ", ".join(repr(float(x)) for x in v) + "]"

    head = (f"name: {name}\n" if name else "") + (f"gravity: {gravity!r}\n" if gravity is not None else "")
    return (head + f"body:\n  mass: {mass!r}\n  inertia: {{principal: {vec(principal)}}}\nrig:\n"
            f"  anchors: [{', '.join(vec((0, y, anchor_z)) for y in ys)}]\n"
            f"  attachments: [{', '.join(vec((0, y, attachment_z)) for y in ys)}]\n"
            f"  lengths: {vec((length, length))}\n")


def one_error_line(res, field: str) -> str:
    """The CLI contract for bad input (a click ``Result``): exit 2, one
    ``error: FIELD: ...`` line on stderr besides warnings, nothing on stdout,
    no traceback; returns that line."""
    err = [ln for ln in res.stderr.splitlines() if ln.strip() and not ln.startswith("warning:")]
    assert res.exit_code == 2, (res.exit_code, res.stderr)
    assert len(err) == 1 and err[0].startswith(f"error: {field}: "), res.stderr
    assert "Traceback" not in res.stderr and res.stdout == ""
    return err[0]


@contextlib.contextmanager
def in_tmpdir():
    """Run the block in a fresh temporary directory (the working directory
    while it runs, removed after): click's ``CliRunner.isolated_filesystem``,
    which click 8.3 deprecates, for tests that invoke the CLI on relative
    file names."""
    old = os.getcwd()
    with tempfile.TemporaryDirectory() as d:
        os.chdir(d)
        try:
            yield Path(d)
        finally:
            os.chdir(old)

