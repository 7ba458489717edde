"""Nearly dependent multi-wire rigs at rest (session 15, elastic).

The level table of four vertical wires (tests/test_restrank.py's ``_splayed``,
10 kg, 1 m wires) with anchors 1 and 3 splayed outwards by 1e-4 .. 3e-2 m
(what a rig measured with a tape is): the rigid model refused it ("wire 2
carries no tension at rest (-23.9 N)", or "slack by 0.017 mm") where elastic
wires of EA 1e5 .. 1e6 N hang it with every wire taut.  The independent
formulation is test_restrank's ``_elastic_rest`` (EA / L springs, Newton on
the potential, nothing of the model's statics used).
"""

from __future__ import annotations

import numpy as np
import pytest

from test_restrank import _elastic_rest, _splayed


@pytest.mark.parametrize("eps", [1e-3, 1e-2])
def test_a_refusal_the_wires_stretch_decides_names_the_stiffness(eps):
    # before: SlackWireError on rig.lengths, "wire 2 carries no tension at rest (-23.9 N)" (1e-3 m) and "wire 2
    # is slack at rest by 0.017 mm" (1e-2 m).  Elastic wires hang the table with every wire taut (the
    # independent formulation; 1 N is 4 % of a wire's 24.5 N load, far below its 22.9 .. 26.1 N), so the rigid
    # verdict is not the rig's: the refusal must name rig.stiffness and say "nearly dependent"
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.errors import StiffnessNeededError

    sc = _splayed(eps)
    assert np.min(_elastic_rest(sc, 1e5)) > 1.0
    with pytest.raises(StiffnessNeededError) as ei:
        rest_pose(sc)
    assert ei.value.field == "rig.stiffness" and "nearly dependent" in str(ei.value)
    assert "\n" not in str(ei.value)


def test_the_warning_tells_nearly_dependent_from_dependent():
    # before: "the 4 wires are dependent at rest" for both; the table splayed 1e-6 m is independent by geometry
    # (G's singular value 1.2e-7 of the largest), taken as dependent by the run's rule
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.wire_statics import indeterminate_warning

    exact, near = _splayed(0.0), _splayed(1e-6)
    w_exact = indeterminate_warning(exact, rest_pose(exact))
    w_near = indeterminate_warning(near, rest_pose(near))
    assert "wires are dependent at rest" in w_exact and "nearly" not in w_exact
    assert "wires are nearly dependent" in w_near


@pytest.mark.parametrize("value,field", [(1.0e5, None), ([1.0e5, 2.0e5, 1.0e5, 1.0e5], None), (0, "rig.stiffness"),
                                         ([1.0e5, -1.0, 1.0e5, 1.0e5], "rig.stiffness.1"),
                                         ([1.0e5, 1.0e5], "rig.stiffness")])
def test_the_stiffness_field_is_validated(value, field):
    # before: 'rig.stiffness: unknown key' for every value.  A scalar is every wire's EA, a list one per wire
    import yaml

    from bifilar.config import scene_from_dict
    from bifilar.errors import InputError
    from test_dependent_wires_messages import CORNERS, vertical

    dct = yaml.safe_load(vertical(CORNERS, [1.0] * 4))
    dct["rig"]["stiffness"] = value
    if field is None:
        sc = scene_from_dict(dct, "test", warn=False)
        np.testing.assert_array_equal(sc.stiffness, np.broadcast_to(value, (4,)))
    else:
        with pytest.raises(InputError) as ei:
            scene_from_dict(dct, "test", warn=False)
        assert str(ei.value).startswith(field + ":") and "\n" not in str(ei.value)
