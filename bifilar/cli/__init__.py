"""Command-line interface (thin: parse, call the library, render).

Heavy modules (numpy, scipy, matplotlib, rich) are imported inside the
commands so that ``bifilar --help`` starts fast.
"""

from __future__ import annotations

import click

from .. import __version__
from .common import setup_logging

#: the thread-count variables of the BLAS libraries numpy and scipy may use; a user's value of any of them wins
BLAS_THREAD_VARS = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def limit_blas_threads() -> bool:
    """One BLAS thread for the command about to run: set
    ``OPENBLAS_NUM_THREADS`` and ``MKL_NUM_THREADS`` to 1 when the
    environment sets none of :data:`BLAS_THREAD_VARS` and numpy is not yet
    imported (the BLAS reads them once, when loaded; afterwards they would
    only reach child processes).  The CLI's matrices are small: on two cores
    OpenBLAS's default thread per core made `bifilar period` of a KTH record
    cost 1.98 s of CPU against 1.61 s, 4.6 s of wall against 2.9 s, the
    answers equal byte for byte (docs/performance.md, "minor25").  Called by
    the CLI's entry point only: importing bifilar changes no environment.
    Returns whether it set them; ``sweep``'s worker processes inherit them."""
    import os
    import sys

    if "numpy" in sys.modules or any(os.environ.get(v) for v in BLAS_THREAD_VARS):
        return False
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    os.environ["MKL_NUM_THREADS"] = "1"
    return True


class _LazyGroup(click.Group):
    """Commands live in submodules imported only when invoked."""

    def main(self, *args, **kwargs):
        """Click's entry point (``bifilar ...``, ``python -m bifilar``):
        :func:`limit_blas_threads` first, before any command imports numpy."""
        limit_blas_threads()
        return super().main(*args, **kwargs)

    _commands = {
        "modes": ("bifilar.cli.cmd_modes", "modes"),
        "simulate": ("bifilar.cli.cmd_simulate", "simulate"),
        "invert": ("bifilar.cli.cmd_invert", "invert"),
        "period": ("bifilar.cli.cmd_period", "period"),
        "sweep": ("bifilar.cli.cmd_sweep", "sweep"),
        "plan": ("bifilar.cli.cmd_plan", "plan"),
        "tensions": ("bifilar.cli.cmd_tensions", "tensions"),
    }

    def list_commands(self, ctx):
        import importlib.util

        return sorted(n for n, (mod, _) in self._commands.items() if importlib.util.find_spec(mod) is not None)

    def get_command(self, ctx, name):
        if name not in self._commands:
            return None
        import importlib
        import importlib.util

        mod, attr = self._commands[name]
        if importlib.util.find_spec(mod) is None:  # command not built yet in this checkout
            return None
        return getattr(importlib.import_module(mod), attr)


@click.group(cls=_LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="bifilar")
@click.option("--debug", is_flag=True, help="Show tracebacks instead of one-line errors.")
@click.option("-v", "--verbose", is_flag=True, help="Log progress to stderr.")
@click.pass_context
def main(ctx: click.Context, debug: bool, verbose: bool) -> None:
    """Plan, simulate and invert bifilar / multifilar pendulum experiments
    for measuring moments of inertia.  SI units throughout."""
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug
    setup_logging(verbose)


def register(name: str, module: str, attr: str) -> None:
    """Add a lazily imported command (used by feature modules)."""
    _LazyGroup._commands[name] = (module, attr)
