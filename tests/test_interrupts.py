"""A Ctrl-C (SIGINT) or SIGTERM cannot be lost (bifilar.interrupts).

Python raises a signal's exception at the next bytecode of the main thread;
inside a finaliser (``__del__``, a generator closed by the garbage collector,
a ``gc`` callback) that exception is printed as "Exception ignored" and
dropped.  ``tests/test_cli.py::test_signal_during_a_run_exits_cleanly`` saw
it: a 10 000-period simulation signalled once ran to the end and exited 0.
The handlers now remember the request, and progress updates, the atomic
writer and the command wrapper raise it again."""

from __future__ import annotations

import gc
import os
import signal

import pytest
from click.testing import CliRunner

from bifilar import interrupts
from bifilar.cli import main
from bifilar.output import Terminated, atomic_write
from conftest import CONFIGS

PLATE = CONFIGS / "thesis_plate_rest.yaml"


class _Swallower:
    """Signals itself inside ``__del__``: the handler's exception is raised
    there and dropped by the interpreter, as a finaliser's always is."""

    def __init__(self, sig: int):
        self.sig = sig

    def __del__(self):
        os.kill(os.getpid(), self.sig)
        for _ in range(100):  # bytecodes: the pending handler runs here
            pass


def _swallow(sig: int) -> None:
    obj = _Swallower(sig)
    del obj
    gc.collect()


pytestmark = pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")


@pytest.mark.parametrize("sig, exc", [(signal.SIGINT, KeyboardInterrupt), (signal.SIGTERM, Terminated)])
def test_a_stop_swallowed_by_a_finaliser_is_remembered_and_raised_again(sig, exc):
    before = signal.getsignal(sig)
    with interrupts.stop_handlers():
        _swallow(sig)  # no exception reaches us: the finaliser ate it
        assert interrupts.stop_requested() is exc
        with pytest.raises(exc) as info:
            interrupts.raise_if_stop_requested()
        assert (sig == signal.SIGTERM) == interrupts.is_terminated(info.value)
    # leaving restores the handlers and forgets the request
    assert signal.getsignal(sig) is before
    assert interrupts.stop_requested() is None
    interrupts.raise_if_stop_requested()


def test_without_a_signal_nothing_is_raised():
    with interrupts.stop_handlers():
        interrupts.raise_if_stop_requested()
        assert interrupts.stop_requested() is None


def test_atomic_write_does_not_land_a_file_after_a_swallowed_stop(tmp_path):
    path = tmp_path / "out.csv"
    path.write_text("the user's old file\n")
    with interrupts.stop_handlers():
        _swallow(signal.SIGINT)
        with pytest.raises(KeyboardInterrupt):
            atomic_write(path, lambda tmp: open(tmp, "w").write("new\n"))
    assert path.read_text() == "the user's old file\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv"]  # no temporary file left


def test_a_command_whose_stop_was_swallowed_exits_130_without_output(tmp_path, monkeypatch):
    """The run finishes (its stop eaten by a finaliser, no progress step
    after it): the command still exits 130, says so, writes no file."""
    import bifilar.analysis.simulate as cs

    real = cs.simulate

    def run_then_swallow(*args, **kwargs):
        res = real(*args, **kwargs)
        _swallow(signal.SIGINT)
        return res

    monkeypatch.setattr(cs, "simulate", run_then_swallow)
    out = tmp_path / "run.csv"
    r = CliRunner().invoke(main, ["simulate", str(PLATE), "--periods", "2", "--out", str(out)])
    assert r.exit_code == 130, r.output
    assert "interrupted" in r.output and "Traceback" not in r.output
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_a_swallowed_stop_ends_the_run_at_its_next_progress_step(tmp_path, monkeypatch):
    """A stop eaten early in a long run stops it at the next progress update
    instead of letting it run to the end."""
    import bifilar.analysis.simulate as cs

    calls = []
    real = cs.simulate

    def run_swallowing_early(*args, progress=None, **kwargs):
        def upd(done, total):
            calls.append(done)
            if len(calls) == 2:
                _swallow(signal.SIGINT)
            progress(done, total)

        return real(*args, progress=upd, **kwargs)

    monkeypatch.setattr(cs, "simulate", run_swallowing_early)
    r = CliRunner().invoke(main, ["simulate", str(PLATE), "--periods", "200", "--out", str(tmp_path / "r.csv")])
    assert r.exit_code == 130, r.output
    assert len(calls) == 2  # the second update raised: no step after it
    assert list(tmp_path.iterdir()) == []


def test_an_interrupt_raised_in_exec_of_a_string_still_exits_130(tmp_path):
    """A KeyboardInterrupt leaving ``exec`` of a string (as when Ctrl-C lands
    while a dataclass is built during a lazy import) sets CPython's
    'unhandled KeyboardInterrupt' flag even though the command catches it;
    the process then died by SIGINT (status -2) instead of exiting 130."""
    import subprocess
    import sys

    code = ("import bifilar.analysis.simulate as s\n"
            "def boom(*a, **k):\n"
            "    exec('raise KeyboardInterrupt')\n"
            "s.simulate = boom\n"
            "from bifilar.cli import main\n"
            f"main(['simulate', {str(PLATE)!r}, '--periods', '2'])\n")
    # run as `python -m` (as `python -m bifilar` is): a SystemExit there returns to Py_RunMain, which
    # consults the flag (`python -c` exits inside PyErr_Print and never looks)
    (tmp_path / "runner").mkdir()
    (tmp_path / "runner" / "__main__.py").write_text(code)
    r = subprocess.run([sys.executable, "-m", "runner"], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert r.returncode == 130, (r.returncode, r.stderr[-500:])
    assert "interrupted" in r.stderr and "Traceback" not in r.stderr
