"""The library functions the CLI's sweep and invert moved out of cli/
(docs/design.md, "thincli, session 19"), called directly, as a notebook
would; each checked against values written out by hand here, not against
the functions' own output.  Cheap: no run, one config load."""

from __future__ import annotations

import pytest

from bifilar.errors import InputError
from conftest import CONFIGS


def test_parse_sigmas_reads_key_value_pairs_and_names_the_option():
    from bifilar.studies.study_inputs import parse_sigmas

    # spaces stripped, a later key replaces an earlier one
    assert parse_sigmas([" timing = 0.002", "com=1e-3", "timing=0.003"]) == {"timing": 0.003, "com": 0.001}
    for bad in ("timing", "timing=abc"):
        with pytest.raises(InputError) as e:
            parse_sigmas([bad])
        assert e.value.field == "--sigma"


def test_measurement_set_gives_an_unsigned_period_the_stated_timing_and_a_labelled_amplitude():
    from bifilar.estimation.measurements import DEFAULT_CYCLES
    from bifilar.estimation.stated_inputs import measurement_set

    ms = measurement_set(CONFIGS / "thesis_lin1_torsion.yaml", None, unc={"timing": 0.004},
                         periods=[("torsion", 2.3, None), ("torsion", 2.31, 0.002)],
                         amps={"torsion": (0.05, 0.01)})
    a, b = ms.measurements
    assert (a.period, a.std, a.std_given) == (2.3, 0.004, False)  # the stated --uncertainty timing
    assert (b.period, b.std, b.std_given) == (2.31, 0.002, True)  # its own +-SIGMA
    assert a.cycles == b.cycles == DEFAULT_CYCLES
    assert (a.amplitude, a.amplitude_std) == (0.05, 0.01)  # a period, not a record: as stated
    with pytest.raises(InputError) as e:  # a label nothing measured
        measurement_set(CONFIGS / "thesis_lin1_torsion.yaml", None, periods=[("torsion", 2.3, None)],
                        amps={"swing-x": (0.05, None)})
    assert e.value.field == "--amplitude"
    with pytest.raises(InputError) as e:  # nothing at all
        measurement_set(CONFIGS / "thesis_lin1_torsion.yaml", None)
    assert e.value.field == "--period"
