"""Bad input is reported, not crashed on: the corpus of hand-written bad
configs (tests/bad_configs/, each stating its exact message on its first
lines), one-pass reporting, safe YAML, size limits, physical impossibility
with messages whose numbers are checked against geometry, and the
plausibility warnings."""

from __future__ import annotations

import logging
import os
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from bifilar.analysis.equilibrium import rest_pose
from bifilar.cli import main
from bifilar.config import (
    MAX_CONFIG_BYTES,
    _Checker,
    check_inertia_tensor,
    load_scene,
    parse_yaml,
    plausibility_warnings,
    read_yaml,
    scene_from_dict,
)
from bifilar.errors import ConfigErrors, InputError

HERE = Path(__file__).resolve().parent
CORPUS = sorted((HERE / "bad_configs").glob("*.yaml"))
CONFIGS = sorted(p for p in (HERE.parent / "configs").glob("*.yaml")
                 if isinstance(read_yaml(p), dict) and "body" in read_yaml(p))  # scenes, not measurement files


def good_cfg() -> dict:
    """A valid bifilar config (2 kg, vertical 1.5 m wires 1 m apart)."""
    return {
        "body": {"mass": 2.0, "inertia": {"principal": [0.1, 0.1, 0.2]}},
        "rig": {"anchors": [[0, -0.5, 0], [0, 0.5, 0]], "attachments": [[0, -0.5, 0.1], [0, 0.5, 0.1]],
                "lengths": [1.5, 1.5]},
    }


GOOD_YAML = """\
body: {mass: 2.0, inertia: {principal: [0.1, 0.1, 0.2]}}
rig:
  anchors:     [[0, -0.5, 0], [0, 0.5, 0]]
  attachments: [[0, -0.5, 0.1], [0, 0.5, 0.1]]
  lengths:     [1.5, 1.5]
"""


def expectations(path: Path) -> tuple[list[str], list[str]]:
    """The ``# expect:`` (errors) and ``# warning:`` lines heading a corpus file."""
    errors, warns = [], []
    for raw in path.read_bytes().split(b"\n"):
        line = raw.decode("utf-8", "replace")
        if not line.startswith("#"):
            break
        if line.startswith("# expect: "):
            errors.append(line[len("# expect: "):])
        elif line.startswith("# warning: "):
            warns.append(line[len("# warning: "):])
    return errors, warns


def run(*args: str):
    return CliRunner().invoke(main, list(args))


def stderr_lines(res) -> list[str]:
    return [ln for ln in res.stderr.splitlines() if ln.strip()]


# --------------------------------------------------------------------------- the corpus


def test_corpus_is_well_formed():
    assert len(CORPUS) >= 40
    for p in CORPUS:
        errors, warns = expectations(p)
        assert bool(errors) != bool(warns), f"{p.name}: needs '# expect:' or '# warning:' lines (not both)"
        first = p.read_bytes().split(b"\n")[0].decode()
        assert first.startswith(("# expect: ", "# warning: ")), f"{p.name}: the first line must state the message"


@pytest.mark.parametrize("path", CORPUS, ids=[p.stem for p in CORPUS])
def test_bad_config_gives_its_exact_message(path, tmp_path, monkeypatch):
    """Through the CLI (in-process): every expected line, and nothing else, on
    stderr; exit 2 for errors (nothing on stdout), 0 for warnings."""
    monkeypatch.chdir(tmp_path)  # python_object_tag.yaml would write here if its tag were ever executed
    errors, warns = expectations(path)
    res = run("modes", str(path), "--json")
    assert "Traceback" not in res.stderr
    lines = stderr_lines(res)
    if errors:
        assert res.exit_code == 2, res.stderr
        assert res.stdout == ""
        assert sorted(lines) == sorted(f"error: {e}" for e in errors)
    else:
        assert res.exit_code == 0, res.stderr
        assert sorted(lines) == sorted(f"warning: {w}" for w in warns)
        assert res.stdout.strip().startswith("{")
    assert not list(tmp_path.iterdir())


# --------------------------------------------------------------------------- one pass, one line, a field each


def test_every_problem_is_reported_in_one_pass():
    cfg = good_cfg()
    cfg["gravity"] = float("nan")
    cfg["body"]["mass"] = -1
    cfg["body"]["inertia"]["principal"][1] = float("inf")
    cfg["rig"]["lengths"][0] = "long"
    cfg["rig"]["anchors"][1] = [0, 0]
    cfg["rig"]["atachments_frame"] = "com"
    with pytest.raises(ConfigErrors) as e:
        scene_from_dict(cfg)
    fields = [x.field for x in e.value.errors]
    assert fields == ["gravity", "body.mass", "body.inertia.principal.1", "rig.atachments_frame", "rig.anchors.1",
                      "rig.lengths.0"]
    msgs = {x.field: x.message for x in e.value.errors}
    assert msgs["rig.atachments_frame"] == "unknown key; did you mean 'attachments_frame'?"
    assert msgs["rig.lengths.0"] == "must be a number, got str 'long'"
    assert msgs["body.mass"] == "must be positive, got -1"
    assert str(e.value).count("\n") == len(fields) - 1  # one line per problem


def test_messages_stay_on_one_line_for_hostile_keys_and_values():
    cfg = good_cfg()
    cfg["rig"]["bad\nkey"] = 1
    cfg["body"]["mass"] = "two\nkilograms" + "!" * 500
    with pytest.raises(ConfigErrors) as e:
        scene_from_dict(cfg)
    for err in e.value.errors:
        assert "\n" not in str(err)
        assert len(str(err)) < 300
    assert e.value.errors[0].field == "body.mass"
    assert e.value.errors[1].field == "rig.'bad\\nkey'"


def test_all_duplicate_keys_are_reported_with_their_paths():
    text = "body:\n  mass: 1\n  mass: 2\nrig:\n  lengths: [1, 1]\nrig: {}\n"
    with pytest.raises(ConfigErrors) as e:
        parse_yaml(text)
    assert [str(x) for x in e.value.errors] == [
        "body.mass: duplicate key 'mass' (lines 2 and 3); YAML would silently keep only the last",
        "rig: duplicate key 'rig' (lines 4 and 6); YAML would silently keep only the last",
    ]


def test_yaml_merge_keys_are_not_duplicates():
    data = parse_yaml("base: &b {x: 1, y: 2}\nother:\n  <<: *b\n  y: 3\n")
    assert data["other"] == {"x": 1, "y": 3}


def test_yaml_aliases_are_copies_so_one_edit_changes_one_place():
    """An anchor shared by an anchor point and an attachment point: sweeping
    the attachment must not move the anchor (PyYAML hands one list to every
    alias, and copy.deepcopy would keep the sharing)."""
    from bifilar.studies.shorthands import apply_params

    text = ("body: {mass: 2.0, inertia: {principal: [0.1, 0.1, 0.2]}}\n"
            "rig:\n  anchors: [&p0 [0, -0.5, 0.1], &p1 [0, 0.5, 0.1]]\n"
            "  attachments: [*p0, *p1]\n  lengths: [1.5, 1.5]\n")
    cfg = parse_yaml(text)
    assert cfg["rig"]["anchors"] == cfg["rig"]["attachments"]
    assert cfg["rig"]["anchors"][0] is not cfg["rig"]["attachments"][0]
    new, _ = apply_params(cfg, {"rig.attachments.0.1": -0.4})
    assert new["rig"]["attachments"][0] == [0, -0.4, 0.1]
    assert new["rig"]["anchors"][0] == [0, -0.5, 0.1]
    s = scene_from_dict(new, warn=False)
    np.testing.assert_array_equal(s.anchors[0], [0, -0.5, 0.1])


@pytest.mark.parametrize("payload", [
    "!!python/object/apply:os.system ['touch {m}']",
    "!!python/object/new:os.system ['touch {m}']",
    "!!python/name:os.system",
    "!!python/module:os",
    "!!python/tuple [1, 2]",
])
def test_python_tags_are_rejected_and_never_executed(payload, tmp_path):
    marker = tmp_path / "executed"
    cfg = tmp_path / "evil.yaml"
    cfg.write_text("name: " + payload.format(m=marker) + "\n" + GOOD_YAML)
    res = run("modes", str(cfg))
    assert res.exit_code == 2
    assert stderr_lines(res)[0].startswith("error: name: unsupported YAML tag !!python/")
    assert not marker.exists()


def test_yaml_1_2_exponent_floats_are_numbers_and_text_stays_text():
    data = parse_yaml("a: [1e0, 15E-1, -2e+1, .5e1, 1.0e+3, 7]\nb: [1e, e5, 1e3x, '1e3', 0x10, 1_000]\n")
    assert data["a"] == [1.0, 1.5, -20.0, 5.0, 1000.0, 7]
    assert isinstance(data["a"][5], int)
    assert data["b"] == ["1e", "e5", "1e3x", "1e3", 16, 1000]


def test_size_limit_on_config_files(tmp_path):
    p = tmp_path / "big.yaml"
    body = GOOD_YAML.encode()
    p.write_bytes(b"#" * (MAX_CONFIG_BYTES + 1 - len(body)) + b"\n" + body)  # MAX + 2 bytes
    res = run("modes", str(p))
    assert res.exit_code == 2
    assert stderr_lines(res) == [f"error: config: file is {MAX_CONFIG_BYTES + 2} bytes; configs are limited to "
                                 f"{MAX_CONFIG_BYTES} bytes"]


def test_unreadable_inputs(tmp_path):
    with pytest.raises(InputError, match=r"^config: file not found: "):
        read_yaml(tmp_path / "nope.yaml")
    with pytest.raises(InputError, match=r"^config: is a directory, not a config file: "):
        read_yaml(tmp_path)
    if os.path.exists("/dev/zero"):  # a device would be read forever without the regular-file check
        with pytest.raises(InputError, match=r"^config: not a regular file: /dev/zero"):
            read_yaml("/dev/zero")
    with pytest.raises(InputError, match="nested too deeply"):
        parse_yaml("a: " + "[" * 5000 + "]" * 5000)


def test_integer_too_large_for_a_float_in_parts_is_an_input_error():
    cfg = good_cfg()
    del cfg["body"]["mass"], cfg["body"]["inertia"]
    cfg["body"]["parts"] = [{"shape": "solid_sphere", "mass": 10**400, "radius": 0.1}]
    with pytest.raises(ConfigErrors) as e:
        scene_from_dict(cfg)
    assert e.value.errors[0].field.startswith("body.parts.0")


def test_check_inertia_tensor_keeps_its_signature():
    chk = _Checker()
    assert check_inertia_tensor(np.diag([1.0, 2.0, 2.5]), "I", chk) and not chk.errors
    assert not check_inertia_tensor(np.diag([1.0, 1.0, 2.5]), "I", chk)  # 1 + 1 < 2.5
    assert chk.errors[0].field == "I"


def test_geometry_checks_are_scale_free():
    # the same rig at 1/1000 scale (mm-sized) is equally valid, and the same coincidence is caught
    cfg = good_cfg()
    for key in ("anchors", "attachments"):
        cfg["rig"][key] = (np.asarray(cfg["rig"][key]) * 1e-3).tolist()
    cfg["rig"]["lengths"] = [1.5e-3, 1.5e-3]
    cfg["body"]["inertia"]["principal"] = [0.1e-6, 0.1e-6, 0.2e-6]
    s = scene_from_dict(cfg)
    assert s.lengths[0] == 1.5e-3
    # 1e-12 m apart in a 1 mm rig: closer than 1e-9 of its size -> the same point
    cfg["rig"]["attachments"][1] = [0, -0.5e-3 + 1e-12, 0.1e-3]
    with pytest.raises(ConfigErrors, match=r"rig.attachments.1: coincides with rig.attachments.0"):
        scene_from_dict(cfg)


# --------------------------------------------------------------------------- physics behind the corpus messages


def test_trifilar_reach_message_matches_geometry():
    # anchors on a circle of radius 10/sqrt(3), attachments on one of 1/sqrt(3): a level, centred body
    # (the best pose by symmetry) leaves each 4.6 m wire 9/sqrt(3) - 4.6 m short
    short = 9 / np.sqrt(3) - 4.6
    errors, _ = expectations(HERE / "bad_configs" / "trifilar_cannot_reach.yaml")
    assert f"too short by wire 1 {short:.3g} m, wire 2 {short:.3g} m, wire 3 {short:.3g} m;" in errors[0]
    # and each pair alone could reach (10 m apart vs 1 + 2 x 4.6 m): only the joint check finds it
    assert 10 < 1 + 2 * 4.6


def test_slack_message_matches_the_pose_on_the_other_wires():
    """Independent check of 'wire 3 is slack by 50 mm': hang the table on
    wires 1, 2, 4 only and measure how far attachment 3 is from anchor 3."""
    path = HERE / "bad_configs" / "slack_fourth_wire.yaml"
    cfg = read_yaml(path)
    keep = [0, 1, 3]
    three = {"body": cfg["body"], "rig": {k: [cfg["rig"][k][i] for i in keep] for k in ("anchors", "attachments", "lengths")}}
    s3 = scene_from_dict(three)
    rest = rest_pose(s3)
    a3 = np.asarray(cfg["rig"]["anchors"][2])
    p3 = rest.com + rest.R @ np.asarray(cfg["rig"]["attachments"][2])
    dist = np.linalg.norm(p3 - a3)
    # the three taut wires hold the table level 1 m below the anchors: attachment 3 is exactly 1 m from anchor 3
    assert dist == pytest.approx(1.0, abs=1e-9)  # Newton-polished rest pose: ~1e-15; 1e-9 is generous
    gap_mm = (cfg["rig"]["lengths"][2] - dist) * 1000
    errors, _ = expectations(path)
    assert f"slack at rest by {gap_mm:.3g} mm" in errors[0] and f"to {dist:.4f} m" in errors[0]


def test_unstable_message_height_matches_config():
    # the attachments sit 0.5 m below the CoM in the body frame and the body hangs level
    for name in ("unstable_com_above.yaml", "turns_over.yaml"):
        cfg = read_yaml(HERE / "bad_configs" / name)
        h = -np.mean(np.asarray(cfg["rig"]["attachments"])[:, 2])
        errors, _ = expectations(HERE / "bad_configs" / name)
        assert f"the centre of mass is {h:.3g} m above the attachment points" in errors[0]


def test_rest_pose_errors_are_input_errors_with_a_field():
    for name in ("slack_fourth_wire", "unstable_com_above", "turns_over", "trifilar_cannot_reach"):
        s = load_scene(HERE / "bad_configs" / f"{name}.yaml")
        with pytest.raises(InputError) as e:
            rest_pose(s)
        assert e.value.field in ("rig.lengths", "rig.attachments")


# --------------------------------------------------------------------------- plausibility warnings


@pytest.mark.parametrize("path", CONFIGS, ids=[p.stem for p in CONFIGS])
def test_example_configs_raise_no_plausibility_warnings(path):
    # real and thesis rigs (including 500 m wires with anchors 505 m apart) must not be flagged
    assert plausibility_warnings(load_scene(path, warn=False)) == []


def test_plausibility_thresholds_are_sharp():
    def warns(**changes):
        cfg = good_cfg()
        for dotted, value in changes.items():
            d = cfg
            *head, last = dotted.split("__")
            for k in head:
                d = d[k]
            d[last] = value
        return plausibility_warnings(scene_from_dict(cfg, warn=False))

    assert warns() == []
    assert warns(gravity=1.62) == [] and warns(gravity=24.8) == []  # Moon and Jupiter
    assert len(warns(gravity=0.9)) == 1 and len(warns(gravity=31)) == 1
    assert warns(body__mass=9e4, body__inertia={"principal": [4.5e3, 4.5e3, 9e3]}) == []
    assert warns(body__mass=2e5, body__inertia={"principal": [1e4, 1e4, 2e4]})[0].startswith("body.mass = 200000 kg")
    # wire lengths in a 1 m rig: 19.9 m is not flagged; all > 20 m reads as centimetres (a drone's 0.8 m wires
    # entered as 80: audit19), all > 100 m as millimetres
    assert warns(rig__lengths=[19.9, 19.9]) == []
    assert "centimetres" in warns(rig__lengths=[20.1, 20.1])[0] and "centimetres" in warns(rig__lengths=[99.0, 99.0])[0]
    assert "millimetres" in warns(rig__lengths=[101.0, 101.0])[0]
    # radius of gyration for the mass: k_max = 10 m (m / 1 kg)^(1/3) = 12.6 m for 2 kg, i.e. I = m k^2 = 317.5
    # (the attachments reaching 0.5 m keep the shape rule, k <= 15 m, out of the way)
    k_max2 = 2.0 * (10.0 * 2.0 ** (1 / 3)) ** 2
    assert warns(body__inertia={"principal": [0.5 * k_max2, 0.5 * k_max2, 0.99 * k_max2]}) == []
    big = warns(body__inertia={"principal": [0.6 * k_max2, 0.6 * k_max2, 1.01 * k_max2]})
    assert len(big) == 1 and "implausibly large for a 2 kg body (above 12.6 m)" in big[0]


def test_warnings_go_to_the_log_unless_disabled(caplog):
    cfg = good_cfg()
    cfg["gravity"] = 981
    with caplog.at_level(logging.WARNING, logger="bifilar"):
        scene_from_dict(cfg, warn=False)
        assert caplog.records == []
        scene_from_dict(cfg)
    assert [r.getMessage() for r in caplog.records] == [
        "gravity = 981 m/s^2 is implausible (Earth: 9.81); is it in other units?"]
