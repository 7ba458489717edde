"""Every figure the package draws, and the parts they share.

This package is the only place in :mod:`bifilar` that imports matplotlib,
and it does so inside functions (importing :mod:`bifilar.figures` loads no
matplotlib, so the CLI starts fast).  A figure function takes plain data
(arrays, result objects, the sweep's point dictionaries) and a path, draws,
and writes the file; it computes nothing a test would want to check (the
model curves of an inversion, say, come from :mod:`bifilar.estimation`).
It imports nothing from the rest of :mod:`bifilar` but :mod:`bifilar.output`,
so any layer may call it; no module below :mod:`bifilar.cli` imports the CLI.

The shared parts, owned here once:

* **backend**: a :class:`matplotlib.figure.Figure` on an Agg canvas
  (:func:`new_figure`), never pyplot's global state, so drawing works without
  a display, in threads, and leaves a user's interactive backend alone;
* **saving** (:func:`save`): through :func:`bifilar.output.atomic_write`, so a
  file is either complete or untouched (a failed or interrupted draw leaves
  no half-written image); the format is the file name's ending (``.png``,
  ``.pdf``, ``.svg``, ... -- :data:`bifilar.output.PLOT_SUFFIXES`; the CLI
  checks the name, ``--force`` and the directory before any work);
* **style**: matplotlib's defaults, :data:`DPI` for raster images.

Figure families (one module each):

* :mod:`.simulation` -- ``simulate --plot``: the timed coordinate and tensions;
* :mod:`.signal` -- ``period --plot`` and ``invert --plot`` (one per recording):
  a period fit;
* :mod:`.inversion` -- ``invert --plot``: period against each unknown;
* :mod:`.sweep` -- ``sweep --plot``: every figure of a sweep in one image;
* :mod:`.thesis` -- the figures of ``docs/thesis.md``
  (:mod:`bifilar.studies.reproduce`).
"""

from __future__ import annotations

from pathlib import Path

DPI = 110
"""Resolution (dots per inch) of raster figures."""


def new_figure(nrows: int = 1, ncols: int = 1, *, size: tuple[float, float] = (8.0, 5.0), axes: bool = True,
               layout: str | None = None, **subplot_kw):
    """A figure of ``size`` (inches) on an Agg canvas and, with ``axes``, its
    ``nrows`` x ``ncols`` axes (``fig.subplots``: one Axes or an array;
    ``subplot_kw`` passed on, e.g. ``sharex=True``).  Returns ``(fig, axes)``
    or ``fig`` when ``axes`` is False.  ``layout``: ``"constrained"`` or None
    (call ``fig.tight_layout()`` instead)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout=layout)
    FigureCanvasAgg(fig)
    if not axes:
        return fig
    return fig, fig.subplots(nrows, ncols, **subplot_kw)


def save(fig, path, *, dpi: int = DPI, tight: bool = False) -> Path:
    """Write ``fig`` to ``path`` atomically (:func:`bifilar.output.atomic_write`)
    in the format its ending names (png when it has none); ``tight``: crop to
    the drawn content.  The figure is released afterwards, also on failure.
    Returns ``path``."""
    from ..output import atomic_write

    path = Path(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    kw = {"bbox_inches": "tight"} if tight else {}
    try:
        atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=dpi, format=fmt, **kw))
    finally:
        fig.clear()
    return path


# the figure families (numpy only at import; matplotlib when a figure is drawn)
from .inversion import plot_inversion
from .signal import plot_fit
from .simulation import plot_simulation
from .sweep import plot_sweep

__all__ = ["DPI", "new_figure", "plot_fit", "plot_inversion", "plot_simulation", "plot_sweep", "save"]
