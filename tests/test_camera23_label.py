"""The residual check's label for a peak beside a fitted mode (camera23).

A KTH-like camera record (docs/real_data.md) holds the swing's 2nd harmonic
``2 f2`` ~1.01 Hz beside the torsion's ``f1`` ~0.96 Hz; on a 10 s record
(``1/T_record`` = 0.1 Hz) the two are unresolved.  The residual check used
to label that peak "harmonics 1f ... of the oscillation; orthogonal to the
fundamental, they hardly bias the period", which is false: over the record
it is far from orthogonal to the fundamental's frequency column.  Now only
true harmonics (k >= 2) get the "orthogonal" note; a peak within
``1.5/T_record`` of a fitted mode gets its own note naming that mode.
"""

from __future__ import annotations

import math
import re

import numpy as np

from bifilar.estimation.signal import fit_period

F1, F2, DUR = 0.96, 0.505, 10.0  # torsion, swing (Hz); record length (s)


def _record():
    t = np.arange(0.0, DUR, 1 / 240.0)
    g = np.random.default_rng(1)
    y = (100 * np.cos(2 * math.pi * F1 * t + 0.3) + 2 * np.cos(4 * math.pi * F1 * t + 1.0)
         + 6 * np.cos(2 * math.pi * F2 * t + 2.0) + 1.2 * np.cos(4 * math.pi * F2 * t + 0.5)
         + 0.2 * g.standard_normal(t.size) + 620.0)
    return t, y


def _corr(a, b):
    return abs(float(a @ b)) / math.sqrt(float(a @ a) * float(b @ b))


def test_the_wording_is_true_of_this_record():
    # independent of the reader: the fundamental's frequency column d/dw cos(w t + p) = -t sin(w t + p)
    # is nearly orthogonal to the 2nd harmonic 2 f1 (|cos| 0.033: ~1/(2 pi x 9.6 cycles)) but not to 2 f2,
    # 0.05 Hz (half a cycle over 10 s) away (0.64)
    t, _ = _record()
    dcol = t * np.sin(2 * math.pi * F1 * t + 0.3)
    c_h = max(_corr(dcol, np.cos(4 * math.pi * F1 * t + p)) for p in np.linspace(0, math.pi, 8))
    c_2f2 = max(_corr(dcol, np.cos(4 * math.pi * F2 * t + p)) for p in np.linspace(0, math.pi, 8))
    assert c_h < 0.05 and c_2f2 > 0.5, (c_h, c_2f2)


def test_a_peak_beside_the_torsion_is_not_called_an_orthogonal_harmonic():
    t, y = _record()
    fit = fit_period(t, y, "two_mode")
    band = 1.5 / DUR
    beside = [pk for pk in fit.residual_check["peaks"] if pk["harmonic"] == 1]
    # the periodogram's bins are 1/T_record = 0.1 Hz: the 2 f2 = 1.01 Hz peak lands within one bin of it
    assert any(abs(pk["frequency"] - 2 * F2) <= 1 / DUR + 1e-9 for pk in beside), fit.residual_check["peaks"]
    notes = fit.notes
    # the true harmonic (2 f1) keeps its "orthogonal" note, without "1f" in it
    harm = [n for n in notes if n.startswith("residuals keep harmonics")]
    assert len(harm) == 1 and "2f" in harm[0] and "1f" not in harm[0], harm
    # the peak beside the torsion gets its own note, naming the torsion (within 1/T_record of F1), not
    # the swing, and not claiming orthogonality
    own = [n for n in notes if "1.5/T_record" in n]
    assert len(own) == len(beside) >= 1, own
    named = [float(n.split("fitted mode at ")[1].split(" Hz")[0]) for n in own]
    assert any(abs(f - F1) <= 1 / DUR for f in named), named
    assert all("not orthogonal" in n for n in own), own
    assert not any("1f" in n and "orthogonal to the fundamental" in n for n in notes), notes


def test_the_period_table_does_not_print_1f(tmp_path):
    from click.testing import CliRunner

    from bifilar.cli import main

    t, y = _record()
    p = tmp_path / "dot.csv"
    np.savetxt(p, np.column_stack([t, y]), delimiter=",", header="t,x", comments="")
    r = CliRunner().invoke(main, ["period", str(p), "--model", "two_mode"])
    assert r.exit_code == 0, r.output
    flat = re.sub(r"[\s\u2502\u2503]+", " ", r.output)  # the table's cells may wrap: drop the rules and breaks
    assert re.search(r"1\.[01] Hz \(beside a fitted mode\)", flat) and "1.9 Hz (2f)" in flat, r.output
    assert "(1f)" not in flat, r.output
