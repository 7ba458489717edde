"""The model's linear modes on four or five elastic wires against the body on
springs (docs/design.md "elastic26, session 26").

The independent formulation has no constraint at all: the rigid body hangs on
springs ``T = EA / L max(|d| - L, 0)``, its rest by Newton on the potential's
hand-written gradient with a central-difference Hessian, its modes the
eigenproblem of that Hessian (differenced again) against the body's mass.  For
each config drawn from the stated uncertainties (as scripts/closed_loop_plan.py
draws them) the model's torsion is compared with the springs' third-slowest
mode.  ``--tree`` runs another checkout's model (e.g. main's) against the same
springs and draws.

    python scripts/elastic_spring_check.py CONFIG --draws 60 [--seed 1] [--tree /work/main]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np


def spring_periods(scene, com0, R0) -> np.ndarray:
    """The six periods (s, slowest first) of ``scene``'s body on springs EA / L, from near (com0, R0)."""
    from bifilar.rotations import rotvec_to_matrix

    a, p, L = np.asarray(scene.anchors), np.asarray(scene.attachments), np.asarray(scene.lengths)
    k = np.broadcast_to(np.asarray(scene.stiffness, float), L.shape) / L
    m, g = scene.mass, scene.gravity

    def grad(c, R):
        w = p @ R.T
        d = c + w - a
        ln = np.linalg.norm(d, axis=1)
        u = d / ln[:, None]
        T = k * np.maximum(ln - L, 0.0)
        return np.concatenate([[0.0, 0.0, m * g] + T @ u, np.cross(w, u).T @ T])

    def move(c, R, x):
        return c + x[:3], rotvec_to_matrix(x[3:]) @ R

    def hess(c, R, h=1e-7):
        H = np.empty((6, 6))
        for j in range(6):
            e = np.zeros(6)
            e[j] = h
            H[:, j] = (grad(*move(c, R, e)) - grad(*move(c, R, -e))) / (2 * h)
        return 0.5 * (H + H.T)

    c, R = np.asarray(com0, float) - [0.0, 0.0, 1e-3], np.asarray(R0, float)
    for _ in range(40):
        x = -np.linalg.solve(hess(c, R), grad(c, R))
        c, R = move(c, R, x)
        if np.max(np.abs(x)) < 1e-14:
            break
    if np.max(np.abs(grad(c, R))) > 1e-9 * m * g:
        raise RuntimeError("the springs' equilibrium was not reached")
    M = np.zeros((6, 6))
    M[:3, :3] = m * np.eye(3)
    M[3:, 3:] = R @ scene.inertia @ R.T
    w2 = np.linalg.eigvals(np.linalg.solve(M, hess(c, R))).real
    return np.sort(2 * np.pi / np.sqrt(w2))[::-1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config")
    ap.add_argument("--draws", type=int, default=60)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--tree", default=str(Path(__file__).resolve().parents[1]))
    args = ap.parse_args()
    sys.path.insert(0, str(Path(args.tree) / "scripts"))  # that tree's draws and its bifilar, before any import
    sys.path.insert(0, args.tree)
    from closed_loop_plan import measured_scene

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.config import read_yaml, scene_from_dict
    from bifilar.errors import BifilarError
    from bifilar.studies import sweep as sw

    cfg = read_yaml(args.config)
    scene = scene_from_dict(cfg, warn=False)
    unc = sw.resolve_settings(cfg, tensions=False, components=["Izz"]).unc
    rng = np.random.default_rng(args.seed)
    errs, lost, refused = [], 0, 0
    for _ in range(args.draws):
        s = measured_scene(scene, rng, unc)
        try:
            rest = rest_pose(s)
        except BifilarError:
            refused += 1
            continue
        tor = [md.period for md in linear_modes(s, rest).modes if md.label == "torsion"]
        if not tor:
            lost += 1
            continue
        errs.append(tor[0] / spring_periods(s, rest.com, rest.R)[2] - 1)
    e = np.abs(errs)
    print(f"{args.tree}: {args.draws} drawn, {refused} refused at rest, {lost} without a torsion; the torsion "
          f"against the springs' (relative) max {e.max():.2e}, median {np.median(e):.2e}")


if __name__ == "__main__":
    main()
