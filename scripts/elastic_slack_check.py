"""The slack tail of four or five elastic wires: drawn configs' exact rests against ``drawn_rig_risks``'
``p_slack`` (docs/design.md "elastic26b, session 26").

Every budgeted input (``elastic_split._inputs``: the points, lengths, mass, CoM and EA's factor) is drawn
from its stated std, and the drawn scene's elastic rest (``elastic_rest``, from the config's rest pose)
gives its tensions exactly; a wire at 0 N is slack.  The same draws' linear tensions (forward differences
at the config, as ``drawn_rig_risks`` took them before session 26b) are counted beside them.
``--no-ea`` leaves EA's factor out (the closed loops' draws, scripts/closed_loop_plan.py, do not draw it).

    python scripts/elastic_slack_check.py tests/data/audit24/c07_quad.yaml --ea 2000 [--length 2.5e-3]
        [--position 1e-4] [--draws 50000] [--seed 1] [--no-ea]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bifilar.analysis.elastic_rest import elastic_rest  # noqa: E402
from bifilar.analysis.equilibrium import rest_pose  # noqa: E402
from bifilar.config import read_yaml, scene_from_dict  # noqa: E402
from bifilar.estimation import elastic_split as es  # noqa: E402
from bifilar.estimation.sensitivity import perturb  # noqa: E402
from bifilar.studies import sweep as sw  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config")
    ap.add_argument("--length", type=float)
    ap.add_argument("--position", type=float)
    ap.add_argument("--draws", type=int, default=50000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--no-ea", action="store_true")
    ap.add_argument("--ea", type=float, help="rig.stiffness (N) in place of the config's")
    a = ap.parse_args()
    cfg = read_yaml(a.config)
    if a.ea is not None:
        cfg["rig"]["stiffness"] = a.ea
    if cfg["rig"].get("stiffness") is None:
        sys.exit("the config has no rig.stiffness: give --ea")
    scene = scene_from_dict(cfg, warn=False)
    unc = dict(sw.resolve_settings(cfg, tensions=False, components=["Izz"]).unc)
    unc.update({k: v for k, v in (("length", a.length), ("position", a.position)) if v is not None})
    rest = rest_pose(scene)
    names, sd = es._inputs(scene, unc)
    if a.no_ea:
        keep = np.array([n != "stiffness" for n in names])
        names, sd = [n for n, k in zip(names, keep) if k], sd[keep]
    dT = es._gradients(scene, rest, names, sd)[2]
    rng = np.random.default_rng(a.seed)
    lin = exact = failed = 0
    for _ in range(a.draws):
        z = rng.standard_normal(len(names))
        s = scene
        for name, zj, sj in zip(names, z, sd):
            s = perturb(s, name, zj * sj)
        try:
            T = elastic_rest(s, s.stiffness, rest.com, rest.R)[2]
        except Exception:  # noqa: BLE001  (a drawn scene whose rest is not found: counted apart)
            failed += 1
            continue
        exact += bool(np.any(T <= 0.0))
        lin += bool(np.any(rest.tensions + z @ dT < 0.0))
    n = a.draws - failed
    print(f"{n} drawn configs ({failed} without a rest): slack at their exact rests {exact} ({exact / n:.5f}), "
          f"by the linear tensions {lin} ({lin / n:.5f}); drawn_rig_risks' p_slack "
          f"{es.drawn_rig_risks(scene, rest, unc).p_slack:.5f}" + (" (with EA's factor)" if a.no_ea else ""))


if __name__ == "__main__":
    main()
