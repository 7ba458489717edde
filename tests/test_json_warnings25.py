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
