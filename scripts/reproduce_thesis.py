#!/usr/bin/env python
"""Reproduce every system of the thesis and write docs/thesis.md.

Regenerates ``docs/thesis.md`` and the figures ``docs/figures/thesis_*.png``
from :mod:`bifilar.studies.reproduce` (one function per thesis result: its
number, ours, a verdict and the reading of the text taken).

Usage::

    python scripts/reproduce_thesis.py [--out docs] [--fast]

``--fast`` shortens the integrations (what ``tests/test_reproduce.py`` runs);
the committed page is written without it.  Takes well under a minute.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bifilar.output import atomic_write  # noqa: E402
from bifilar.studies.reproduce import run_all, write_report  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "docs"), help="folder of thesis.md (figures go to OUT/figures)")
    ap.add_argument("--fast", action="store_true", help="short integrations (for a quick look; not for the docs)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    figdir = out / "figures"
    t0 = time.perf_counter()

    def progress(title: str, seconds: float) -> None:
        print(f"{seconds:6.1f} s  {title}", file=sys.stderr, flush=True)

    results = run_all(fast=args.fast, figdir=figdir, progress=progress)
    runtime = time.perf_counter() - t0
    text = write_report(results, out, runtime=runtime)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write(out / "thesis.md", lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))
    n = sum(len(r.rows) for r in results)
    figs = sum(len(r.figures) for r in results)
    print(f"wrote {out / 'thesis.md'} ({n} rows, {figs} figures) in {runtime:.0f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
