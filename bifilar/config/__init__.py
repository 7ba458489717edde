"""Config files (YAML) -> validated :class:`~bifilar.scene.Scene`.

The format is fixed in ``../shared/interface.md``; this module adds:

* ``body.parts``: a composite body of primitives (see :mod:`bifilar.parts`);
  with parts, ``rig.attachments_frame: parts`` lets attachments be given in
  the parts' build frame instead of relative to the (computed) CoM.
* ``body.bounding_box: {min: [x, y, z], max: [x, y, z]}``: body frame (CoM
  origin) box used for the clearance when there are no parts.

Validation reports every problem in one pass (:class:`~bifilar.errors.ConfigErrors`),
one line each: the field's dotted path (``rig.lengths.1``, counting list
items from 0), the value found and what was expected.  Values that are
valid but implausible (a 5 km wire, a 1000 t body, wire lengths that look
like millimetres) are logged as warnings on stderr and do not fail; see
:func:`plausibility_warnings`.

Reading is defensive (:func:`read_yaml`, :func:`parse_yaml`): a
``SafeLoader`` subclass (no Python object construction: ``!!python/...``
tags are an error), duplicate keys rejected (plain PyYAML silently keeps the
last one), files limited to :data:`MAX_CONFIG_BYTES`, alias expansion
("billion laughs") limited to :data:`MAX_YAML_VALUES` values, recursive
aliases and absurd nesting rejected.  Exponent floats without a dot or an
exponent sign (``1e-3``, ``2E5``), which YAML 1.1 reads as text, are read
as numbers (YAML 1.2).

Hard limits (errors, not warnings) keep the numbers inside the range the
solvers handle in double precision: see :data:`LIMITS`.

The package is split by concern; every public name (and the validation
helpers the tests use) is importable from ``bifilar.config`` as before:

* :mod:`.yaml_safe`: reading YAML safely (:func:`read_yaml`, :func:`parse_yaml`);
* :mod:`.fields`: the schema, the hard limits and the field checks
  (:class:`_Checker`), the rig's geometry;
* :mod:`.inertia`: the body's inertia (:func:`check_inertia_tensor`,
  :func:`null_components`);
* :mod:`.plausibility`: warnings for valid but implausible values
  (:func:`plausibility_warnings`);
* :mod:`.build`: the :class:`~bifilar.scene.Scene` (:func:`scene_from_dict`,
  :func:`load_scene`).
"""

from __future__ import annotations

from .build import load_scene, log, scene_from_dict  # noqa: F401
from .fields import (BODY_KEYS, INERTIA_KEYS, LIMITS, MAX_WIRES, RIG_KEYS, SCALE_RATIO, TOP_KEYS,  # noqa: F401
                     _Checker, _check_geometry, _clip, _describe, _fmt, _join, _key, _one_line)
from .inertia import (INERTIA_NAMES, _check_gyration, _check_symmetric, _inertia, _inertia_with_nulls,  # noqa: F401
                      check_inertia_tensor, null_components)
from .plausibility import PLAUSIBLE, plausibility_warnings  # noqa: F401
from .yaml_safe import (MAX_CONFIG_BYTES, MAX_YAML_VALUES, _scan_nodes, _unshare, _UniqueKeyLoader,  # noqa: F401
                        parse_yaml, read_yaml)
