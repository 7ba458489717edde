"""The body's inertia in a config: ``tensor`` or ``principal``, components
marked unknown (``null``) for ``bifilar invert``, and what a real body's
tensor must be (symmetric, positive definite, the triangle inequality with
the allowance :data:`~bifilar.scene.TRIANGLE_SLACK` that invert's physical
set shares; a radius of gyration within :data:`~bifilar.config.fields.LIMITS`).
Part of :mod:`bifilar.config`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..scene import obeys_triangle
from .fields import INERTIA_KEYS, LIMITS, _Checker, _describe, _fmt

INERTIA_NAMES = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}


def null_components(cfg: Any) -> list[str]:
    """Inertia components the config marks unknown with ``null`` (a config
    mapping or a :class:`Scene` built from one), e.g. ``tensor: [[215, 0, 0],
    [0, 52.08, 0], [0, 0, null]]`` or ``principal: [1, 2, null]``: ``Izz``."""
    cfg = getattr(cfg, "config", cfg)
    try:
        spec = cfg["body"]["inertia"]
    except (KeyError, TypeError):
        return []
    out = []
    if not isinstance(spec, dict):
        return out
    if isinstance(spec.get("principal"), (list, tuple)):
        out = [n for n, (i, j) in INERTIA_NAMES.items() if i == j and i < len(spec["principal"])
               and spec["principal"][i] is None]
    rows = spec.get("tensor")
    if isinstance(rows, (list, tuple)) and len(rows) == 3 and all(isinstance(r, (list, tuple)) and len(r) == 3
                                                                  for r in rows):
        out = [n for n, (i, j) in INERTIA_NAMES.items() if rows[i][j] is None or rows[j][i] is None]
    return out


def check_inertia_tensor(I: np.ndarray, path: str, chk: _Checker) -> bool:
    """Symmetric, positive definite, principal moments obey the triangle
    inequality (kg m^2, any axes).  Problems go to ``chk`` under ``path``."""
    scale = float(np.max(np.abs(I))) or 1.0
    if not _check_symmetric(I, path, chk):
        return False
    ev = np.linalg.eigvalsh(I)
    if ev[0] <= 1e-12 * scale:
        chk.error(path, f"inertia tensor must be positive definite; principal moments are {_fmt(ev)} kg m^2")
        return False
    # the allowance for rounded values (TRIANGLE_SLACK) is the one invert's admissible set uses
    if not obeys_triangle(ev):
        chk.error(
            path,
            f"principal moments {_fmt(ev)} kg m^2 break the triangle inequality I1 + I2 >= I3 "
            "(no real mass distribution has them)",
        )
        return False
    return True


def _inertia(spec: Any, chk: _Checker, unknown: tuple | None = None) -> np.ndarray | None:
    if not chk.keys("body.inertia", spec, INERTIA_KEYS):
        return None
    nulls = null_components({"body": {"inertia": spec}})
    if nulls:
        if unknown is None:
            chk.error("body.inertia", f"{', '.join(nulls)} is null (unknown): only `bifilar invert` accepts an unknown "
                                      "component (it solves for it); give its value")
            return None
        return _inertia_with_nulls(spec, nulls, chk)
    present = [k for k in ("tensor", "principal") if k in spec]
    if len(present) != 1:
        chk.error("body.inertia", "give exactly one of 'tensor' (3x3) or 'principal' ([I1, I2, I3]), "
                                  f"got {' and '.join(present) or 'neither'}")
        return None
    if "principal" in spec:
        v = chk.vector("body.inertia.principal", spec["principal"], positive=True)
        if v is None:
            return None
        I = np.diag(v)
        path = "body.inertia.principal"
    else:
        rows = spec["tensor"]
        if not isinstance(rows, (list, tuple)) or len(rows) != 3:
            chk.error("body.inertia.tensor", f"must be a 3x3 list of lists, got {_describe(rows)}")
            return None
        vals = [chk.vector(f"body.inertia.tensor.{i}", r) for i, r in enumerate(rows)]
        if any(v is None for v in vals):
            return None
        I = np.asarray(vals)
        path = "body.inertia.tensor"
    if unknown and set(unknown) & set(INERTIA_NAMES):
        # the components solved for are starting guesses: only the tensor's shape is checked here
        return I if _check_symmetric(I, path, chk) else None
    return I if check_inertia_tensor(I, path, chk) else None


def _check_symmetric(I: np.ndarray, path: str, chk: _Checker) -> bool:
    scale = float(np.max(np.abs(I))) or 1.0
    if np.max(np.abs(I - I.T)) > 1e-9 * scale:
        i, j = np.unravel_index(int(np.argmax(np.abs(I - I.T))), I.shape)
        chk.error(path, f"inertia tensor must be symmetric; row {i}, column {j} is {I[i, j]:.6g} but "
                        f"row {j}, column {i} is {I[j, i]:.6g}")
        return False
    return True


def _inertia_with_nulls(spec: dict, nulls: list, chk: _Checker) -> np.ndarray | None:
    """The tensor with placeholders for the null components (diagonal: the
    mean of the known moments, products: 0); the known moments must be
    positive numbers, the known products numbers."""
    key = "principal" if "principal" in spec else "tensor"
    path = f"body.inertia.{key}"
    if key == "principal" and len(spec[key]) != 3:
        chk.error(path, f"must be a list of 3 numbers (or null for an unknown one), got {_describe(spec[key])}")
        return None
    unknown_at = {INERTIA_NAMES[n] for n in nulls} | {INERTIA_NAMES[n][::-1] for n in nulls}
    I = np.zeros((3, 3))
    ok = True
    for i in range(3):
        for j in range(3):
            if (i, j) in unknown_at or (key == "principal" and i != j):
                continue
            v = spec[key][i] if key == "principal" else spec[key][i][j]
            x = chk.number(f"{path}.{i}" if key == "principal" else f"{path}.{i}.{j}", v, positive=(i == j))
            ok = ok and x is not None
            I[i, j] = x if x is not None else 0.0
    if not ok:
        return None
    known = [I[i, i] for i in range(3) if (i, i) not in unknown_at]
    for i in range(3):
        if (i, i) in unknown_at:
            I[i, i] = float(np.mean(known)) if known else 1.0
    return I if _check_symmetric(I, path, chk) else None


def _check_gyration(mass: float, I: np.ndarray, path: str, chk: _Checker) -> None:
    """Radius of gyration sqrt(I/m) within :data:`LIMITS` (mass and inertia in consistent units)."""
    lo, hi = LIMITS["gyration"]
    ev = np.linalg.eigvalsh(I)
    k_min, k_max = math.sqrt(max(ev[0], 0.0) / mass), math.sqrt(ev[-1] / mass)
    if k_max > hi or k_min < lo:
        k = k_max if k_max > hi else k_min
        chk.error(path, f"radius of gyration sqrt(I/m) = {k:.3g} m is outside {lo:g} .. {hi:g} m "
                        f"(principal moments {_fmt(ev)} kg m^2, mass {mass:g} kg): are the units kg and m?")
