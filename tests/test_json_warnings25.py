"""The rest pose's warnings reach the JSON (docs/design.md "json25, session 25").

`modes`, `simulate` and `tensions` printed the rest pose's warnings
(:func:`bifilar.analysis.rest_warnings.rest_warnings`) on stderr only, so a
program reading `--json` never learnt that audit24's trifilar (wire 3 0.3 m
longer, tests/test_rest_turn_warning.py's M5) hangs turned 74.13 deg.  Each
document's ``warnings`` now holds every line the command printed about the
rest pose, word for word, first; a shipped config gets none of them.
"""

from __future__ import annotations

import json

from click.testing import CliRunner

from bifilar.analysis.rest_warnings import TURN_WARNING_HEAD
from bifilar.cli import main
from conftest import CONFIGS
from test_rest_turn_warning import M5

# half a period: the warnings are the rest pose's, the run's length does not matter (0.02 s a run)
RUNS = {"modes": [], "simulate": ["--periods", "0.5"], "tensions": ["--periods", "0.5"]}


def _run(cmd, cfg):
    r = CliRunner().invoke(main, [cmd, str(cfg), "--json", *RUNS[cmd]])
    assert r.exit_code == 0, r.output
    printed = [ln[len("warning: "):] for ln in r.stderr.splitlines() if ln.startswith("warning: ")]
    return json.loads(r.stdout), printed


def test_the_74_degree_trifilar_says_it_in_every_json(tmp_path):
    cfg = tmp_path / "m5.yaml"
    cfg.write_text(json.dumps(M5))
    for cmd in RUNS:
        doc, printed = _run(cmd, cfg)
        turned = [w for w in printed if w.startswith(f"{TURN_WARNING_HEAD} 74.13 deg")]
        assert len(turned) == 1, (cmd, printed)
        # the stderr line word for word, and every warning printed in the document (none dropped)
        assert turned[0] in doc["warnings"], (cmd, doc.get("warnings"))
        assert set(printed) <= set(doc["warnings"]), (cmd, printed, doc["warnings"])


def test_a_shipped_config_gives_none_of_it():
    for cmd in RUNS:
        doc, printed = _run(cmd, CONFIGS / "thesis_plate_rest.yaml")
        assert not any(w.startswith(TURN_WARNING_HEAD) for w in doc.get("warnings", []) + printed), cmd
        assert set(printed) <= set(doc.get("warnings", [])), (cmd, printed)


# ---------------------------------------------------------------------------
# the sweep's binding-limit message of a feasible point whose sigma is inf (json25 (b))
# ---------------------------------------------------------------------------

def test_a_feasible_point_with_an_inf_sigma_is_named_as_a_none_one_is():
    """tests/test_mutation_gaps25.py's points: the middle one meets every
    limit but its Izz sigma is inf (a stated amplitude whose range reaches
    the half turn: ``sigma_unavailable``); the other two break
    --min-separation 0.02.  audit24's rule, written for a None sigma, left
    the message "no configuration meets --min-separation 0.02" of a point
    the same document counts feasible; an inf is now named as a None is,
    word for word as tests/test_sweep_audit24.py's None case, and (rank26)
    with the point's own reason for it.  A component
    set aside by rank25's rule (best relative sigma 0.9 > 50 %, inf at the
    feasible point) stays out of the message."""
    import math

    from bifilar.studies import sweep as sw
    from bifilar.studies.ranking import binding_constraint
    from test_mutation_gaps25 import _point

    c = sw.Constraints(min_separation=0.02)
    half = {"Izz": "the amplitude range reaches the half turn"}
    pts = [_point(0.04, 0.0118, {"Ixx": 0.004, "Izz": 0.003}),
           _point(0.06, 0.299, {"Ixx": 0.004, "Izz": math.inf}, half),
           _point(0.08, 0.0033, {"Ixx": 0.004, "Izz": 0.003})]
    want = ("no configuration that measures Ixx, Izz meets --min-separation 0.02: the best mode separation found is "
            "0.0118; 1 point(s) meet every limit but give no uncertainty for Izz (e.g. at spacing = 0.06; Izz: the "
            "amplitude range reaches the half turn): leave Izz "
            "out of --component, or add --hangings")
    assert binding_constraint(pts, c, None, ["Ixx", "Izz"]) == ("--min-separation", want)
    rec = sw.assess(pts, c, None)  # the document: the point feasible, no recommendation, that reason
    assert rec["best"] is None and rec["n_feasible"] == 1 and rec["reason"] == want, rec
    # with Iyy set aside (0.9 at two points, inf at the feasible one), the same message: Iyy is not ranked by
    for p, v in zip(pts, (0.9, math.inf, 0.9)):
        p["components"]["Iyy"] = {**p["components"]["Ixx"], "rel_sigma": v}
    rec = sw.assess(pts, c, None)
    assert [a["component"] for a in rec["set_aside"]] == ["Iyy"] and rec["reason"] == want, rec
