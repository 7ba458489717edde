"""Every system of the thesis, reproduced: one function per result.

Each function recomputes one result of W. Swart's thesis (sections 3 to 8)
with the library's models and returns a :class:`Result`: rows
``{key, section, quantity, thesis, ours, unit, verdict, note, stale_tol}``
(``thesis`` and ``ours`` are numbers where the thesis printed one, else a
short text), the reading of the thesis taken (markdown), the raw numbers a
test can check (``data``) and, when ``figdir`` is given, the figures written
there (``thesis_*.png``, drawn by :mod:`bifilar.figures.thesis` from the arrays
computed here).  ``fast=True`` shortens every integration (and
loosens the tolerances of the long ones) so that the whole set runs in a
test; the rows whose ``stale_tol`` is a number do not depend on that choice
(closed forms, quadratures, rest poses, periods of exactly periodic motions)
and must agree between a fast and a full run to that relative tolerance.

:func:`run_all` runs every result; :func:`write_report` turns the results
into ``docs/thesis.md`` (``scripts/reproduce_thesis.py`` does both).  The
results live by thesis chapter in :mod:`.reproduce_ch3_6` (sections 3-6.2),
:mod:`.reproduce_ch6_7` (6.3-7.1) and :mod:`.reproduce_ch7_8` (7.2, 8), their
shared parts in :mod:`.reproduce_common`; all are re-exported here.

Units are SI (m, kg, s, rad, N, kg m^2); world frame z up.  The thesis's
five angles theta1..theta5 are those of :mod:`bifilar.models.kane`; its body
axes b1, b2, b3 are the project configs' body z, x, y (the plate) -- see
``configs/thesis_*.yaml``.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Callable

from .reproduce_ch3_6 import (  # noqa: F401  (re-exported)
    constraint_loop, dumbbell, side_sway, spherical_pendulum, torsion,
)
from .reproduce_ch6_7 import (  # noqa: F401  (re-exported)
    LINEARISATIONS, _lin_verdict, _sway_angles, com_below_cd, cylinder, linearisation_table,
)
from .reproduce_ch7_8 import _study_data, solar_boat, tensions  # noqa: F401  (re-exported)
from .reproduce_common import (  # noqa: F401  (re-exported)
    CONFIGS, DATA_TAG, G, PI, ROOT, Result, THESIS, THETA_REST, _IDX, _amp_for, _figure, _figures, _invert,
    _kane_world_start, _plate_inertia, _quat_R, _scene, _times, _trapezoid, fmt, row,
)


# --------------------------------------------------------------------------
# everything


ALL: tuple[Callable[..., Result], ...] = (dumbbell, spherical_pendulum, constraint_loop, side_sway, torsion,
                                          com_below_cd, cylinder, linearisation_table, tensions, solar_boat)


def run_all(fast: bool = False, figdir: Path | None = None, progress: Callable[[str, float], None] | None = None
            ) -> list[Result]:
    """Run every result in order; ``progress(title, seconds)`` after each."""
    out = []
    for f in ALL:
        t0 = time.perf_counter()
        r = f(fast=fast, figdir=figdir)
        r.runtime = time.perf_counter() - t0
        out.append(r)
        if progress is not None:
            progress(r.title, r.runtime)
    return out


def _md_cell(x) -> str:
    return fmt(x).replace("|", "\\|") if not isinstance(x, str) else x.replace("|", "\\|")


def _has_number(x) -> bool:
    return not isinstance(x, str) or any(ch.isdigit() for ch in x)


def _thesis_cell(x) -> str:
    """The thesis's printed numbers in full (up to 10 significant digits)."""
    if isinstance(x, str) or x is None:
        return _md_cell(x)
    return _md_cell(fmt(x, 10) if 1e-3 <= abs(x) < 1e6 else f"{x:.5g}")


def write_report(results: list[Result], doc_dir: Path, runtime: float | None = None) -> str:
    """Markdown of docs/thesis.md (figure links relative to ``doc_dir``), with
    the rows machine-readable in a trailing HTML comment."""
    lines = [
        "# The thesis, reproduced",
        "",
        "Every system of W. Swart's thesis *Determining the moments of inertia using a bifilar pendulum* "
        "(`../shared/seed/bifilar-thesis.md`), recomputed with this package: its numbers beside ours, with a "
        "verdict, and its figures redrawn.  Where the text is ambiguous the reading taken is stated in the "
        "section; the known slips of the text are listed in `../shared/seed/NOTES.md`.",
        "",
        "Regenerate this page and its figures (`docs/figures/thesis_*.png`) with",
        "",
        "```bash",
        "python scripts/reproduce_thesis.py",
        "```",
        "",
        (f"It took {runtime:.0f} s on this machine.  " if runtime else "")
        + "The computations are `bifilar/studies/reproduce.py` (one function per result); `tests/test_reproduce.py` "
        "runs them with short integrations and checks them against the thesis's numbers, closed forms and this "
        "page.",
        "",
        "## Summary",
        "",
        "| section | quantity | thesis | ours | unit | verdict |",
        "|---|---|---|---|---|---|",
    ]
    for r in results:
        for w in r.rows:
            unit = w["unit"] if _has_number(w["ours"]) else ""
            lines.append(f"| {w['section']} | {_md_cell(w['quantity'])} | {_thesis_cell(w['thesis'])} | "
                         f"{_md_cell(w['ours'])} | {unit} | {_md_cell(w['verdict'])} |")
    for r in results:
        lines += ["", f"## {r.title}", "", r.reading, ""]
        lines += ["| quantity | thesis | ours | verdict | note |", "|---|---|---|---|---|"]
        for w in r.rows:
            unit = f" {w['unit']}" if w["unit"] and _has_number(w["ours"]) else ""
            lines.append(f"| {_md_cell(w['quantity'])} | {_thesis_cell(w['thesis'])} | {_md_cell(w['ours'])}{unit} | "
                         f"{_md_cell(w['verdict'])} | {_md_cell(w['note'])} |")
        for p in r.figures:
            rel = Path(p).resolve().relative_to(Path(doc_dir).resolve())
            lines += ["", f"![{r.title}]({rel.as_posix()})"]
    payload = [{k: w[k] for k in ("key", "thesis", "ours", "stale_tol")} for r in results for w in r.rows]
    lines += ["", f"<!-- {DATA_TAG}", json.dumps(payload, indent=1), "-->", ""]
    return "\n".join(lines)


def read_report_data(path: Path) -> list | None:
    """The rows written into a report by :func:`write_report` (None if absent)."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError:
        return None
    tag = f"<!-- {DATA_TAG}"
    i = text.find(tag)
    if i < 0:
        return None
    return json.loads(text[i + len(tag):text.find("-->", i)])
