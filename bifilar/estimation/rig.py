"""Which measured inputs several hangings share: one rig measured once.

A body hung several times (``bifilar invert --measurements`` with
``hangings``, the multi-hanging plan) is usually hung on the same rig
without measuring it again, and from the same body points where they are
the same.  An input measured once has one error, common to every hanging
that uses it: its effects on their periods add before squaring.

Model ``shared`` (the default; docs/design.md, "Several hangings on one
rig"):

* a *rig* is the wires' ceiling points and lengths: hangings whose configs
  give the same anchors and lengths (every wire, in order, within
  :data:`SAME_TOL` of the longest wire) hang on one rig measured once:
  ``length.i`` and ``anchor.i.a`` (world frame) are one input each for all
  of them;
* a *body point* is an attachment's position relative to the CoM in the
  reference body frame (``R_h^T a_h``): attachments of several hangings at
  the same body point (within the same tolerance) are one point measured
  once, its error a vector fixed in the body, seen in hanging ``h`` as
  ``R_h R_g^T e`` (``g`` the first hanging using it, in whose frame the
  input is named).

Model ``separate``: every hanging's wire lengths, anchors and attachments
measured for it (independent errors; the model before session 10).

The body's own inputs (mass, gravity, CoM) are shared in either model.

Input keys: one hanging: the plain names (``length.1``); several hangings:
``<hanging>:length.1`` for an input of one hanging, ``<h1>+<h2>:length.1``
for one shared by hangings ``h1`` and ``h2`` (a shared attachment's axes
are those of the first of them).  SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: the models of several hangings' rig inputs
RIG_MODELS = ("shared", "separate")
#: entries equal within this fraction of the longest wire are the same measurement
SAME_TOL = 1e-9
#: a shared attachment's coefficient below this is left out (the rotation's rounding)
_COEF_TINY = 1e-12

_AX = "xyz"


@dataclass
class RigLinks:
    """The inputs of the hangings' rigs as independent measured quantities.

    keys : {key: {hanging index: [(per-hanging input name, coefficient)]}}:
        a unit change of the input ``key`` changes each listed input of
        hanging ``h`` by the coefficient (1 for lengths and anchors, the
        rotation's entries for a shared body point).
    shared : the groups of hangings that share inputs, for the output:
        [{"hangings": [...names], "inputs": "lengths and anchors" | ...}].
    model : ``shared`` or ``separate``.
    """

    keys: dict
    model: str
    shared: list = field(default_factory=list)
    _of: dict = field(default_factory=dict, repr=False)

    def of(self, h: int, name: str) -> list:
        """[(key, coefficient)] of hanging ``h``'s input ``name`` (a rig or
        attachment input): its change per unit change of each key."""
        if not self._of:
            for key, per in self.keys.items():
                for g, moves in per.items():
                    for n, c in moves:
                        self._of.setdefault((g, n), []).append((key, c))
        return self._of.get((h, name), [])

    def moves(self, key: str, h: int) -> list:
        """[(per-hanging input name, coefficient)] of ``key`` in hanging ``h`` ([] if none)."""
        return self.keys.get(key, {}).get(h, [])

    def hangings(self, key: str) -> list:
        """Indices of the hangings input ``key`` acts on."""
        return sorted(self.keys.get(key, {}))

    def to_json(self) -> dict:
        return {"model": self.model, "shared": list(self.shared)}


def rig_links(names: list, scenes: list, rotations: list, model: str = "shared") -> RigLinks:
    """:class:`RigLinks` of the hangings ``names`` with ``scenes`` and
    ``rotations`` (reference -> hanging body frame) under ``model`` (module
    docstring).  The configs' geometry decides, not the unknowns: pass the
    scenes as the configs give them."""
    if model not in RIG_MODELS:
        raise ValueError(f"rig model {model!r}")
    H = len(scenes)
    multi = H > 1
    names = [str(n) for n in names]
    Rs = [np.asarray(R, float) for R in rotations]
    tol = SAME_TOL * max(float(np.max(s.lengths)) for s in scenes)

    def same(a, b) -> bool:
        a, b = np.asarray(a, float), np.asarray(b, float)
        return a.shape == b.shape and bool(np.all(np.abs(a - b) <= tol))

    # rigs: groups of hangings with the same anchors and lengths
    rig_of = list(range(H))
    if model == "shared":
        for h in range(H):
            for g in range(h):
                if rig_of[g] == g and same(scenes[g].anchors, scenes[h].anchors) \
                        and same(scenes[g].lengths, scenes[h].lengths):
                    rig_of[h] = g
                    break
    # body points: (hanging, attachment index) grouped by their reference-frame position
    point_of = {(h, i): (h, i) for h in range(H) for i in range(scenes[h].n_wires)}
    if model == "shared":
        ref = [scenes[h].attachments @ Rs[h] for h in range(H)]  # rows R_h^T a_i
        for h in range(H):
            for i in range(scenes[h].n_wires):
                for g in range(h):
                    hit = next((j for j in range(scenes[g].n_wires)
                                if point_of[(g, j)] == (g, j) and same(ref[g][j], ref[h][i])), None)
                    if hit is not None:
                        point_of[(h, i)] = (g, hit)
                        break

    def prefix(group: list) -> str:
        return ("+".join(names[g] for g in group) + ":") if multi else ""

    keys: dict = {}
    shared: list = []
    for r in sorted(set(rig_of)):
        group = [h for h in range(H) if rig_of[h] == r]
        pre = prefix(group)
        n = scenes[r].n_wires
        for i in range(n):
            keys[f"{pre}length.{i + 1}"] = {h: [(f"length.{i + 1}", 1.0)] for h in group}
            for a in _AX:
                keys[f"{pre}anchor.{i + 1}.{a}"] = {h: [(f"anchor.{i + 1}.{a}", 1.0)] for h in group}
        if len(group) > 1:
            shared.append({"hangings": [names[h] for h in group], "inputs": "wire lengths and anchors"})
    points: dict = {}
    for (h, i), root in point_of.items():
        points.setdefault(root, []).append((h, i))
    for (g, j), members in sorted(points.items()):
        group = sorted({h for h, _ in members})
        pre = prefix(group)
        for b, ab in enumerate(_AX):
            per: dict = {}
            for h, i in members:
                M = np.eye(3) if h == g else Rs[h] @ Rs[g].T  # g's frame -> h's frame
                per.setdefault(h, []).extend((f"attachment.{i + 1}.{a}", float(M[ai, b]))
                                             for ai, a in enumerate(_AX) if abs(M[ai, b]) > _COEF_TINY)
            keys[f"{pre}attachment.{j + 1}.{ab}"] = per
        if len(group) > 1:
            shared.append({"hangings": [names[h] for h in group],
                           "inputs": f"attachment {j + 1} of '{names[g]}' (one body point)"})
    return RigLinks(keys, model, shared)
