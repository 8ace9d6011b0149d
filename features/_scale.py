"""The features of a recording as if its numbers or its stated clearance were scaled: a row transform, no second
extraction.

Lengths enter the features only as factors: every ``µm`` feature scales with the recording's numbers (``µm²`` with
their square), every ``*_per_c`` feature is a length over the radial clearance c (``*_per_c2`` an area over c²), and
the shaft-centreline position ``centre_*_per_c`` is NaN when its eccentricity exceeds ``CENTRELINE_MAX_ECC`` (a raw
probe gap, not a position in the bearing); everything else — ratios, phases, orders, shares, the motion type, the
phase-noise gate — is scale-free. So the features at ``length_factor ×`` the numbers and ``clearance_factor × c``
follow from those at hand exactly; a test checks them against a second extraction. Used to ask whether a stated
clearance may be the diametral one, or the numbers half what they should be (``models.checks.clearance_check``).
"""
from __future__ import annotations

import dataclasses
import re

import numpy as np

from . import _config as cfg
from ._across import across_bearings
from ._names import FEATURE_SPECS

__all__ = ["with_scale"]

_PER_C = re.compile(r"^b(\d+)_.*_per_c$")
_PER_C2 = re.compile(r"^b(\d+)_.*_per_c2$")
_UNIT = {s.name: s.unit for s in FEATURE_SPECS}


def with_scale(fr, *, length_factor: float = 1.0, clearance_factor: float = 1.0):
    """``fr`` (a ``FeatureResult``) as extracted with every channel's numbers × ``length_factor`` and every bearing's
    stated clearance × ``clearance_factor``.

    Lengths scale with ``length_factor`` (areas with its square), per-clearance features with ``length_factor /
    clearance_factor`` (areas with its square); a centreline whose eccentricity then exceeds ``CENTRELINE_MAX_ECC``
    becomes missing, as the extraction makes it. Exact while that ratio is at least 1; below, a centreline missing
    before stays missing. The bearing details are ``fr``'s (the evidence's, not the feature vector's).
    """
    for what, f in (("length_factor", length_factor), ("clearance_factor", clearance_factor)):
        if not (np.isfinite(f) and f > 0):
            raise ValueError(f"{what}: must be a positive number, got {f!r}")
    per_c = length_factor / clearance_factor
    values = np.array(fr.values, dtype=float, copy=True)
    names = list(fr.names)
    for i, name in enumerate(names):
        unit = _UNIT.get(name, "")
        if _PER_C2.match(name):
            values[i] *= per_c * per_c
        elif _PER_C.match(name):
            values[i] *= per_c
        elif unit == "µm²":
            values[i] *= length_factor * length_factor
        elif unit.startswith("µm"):
            values[i] *= length_factor
    index = {n: i for i, n in enumerate(names)}
    for b in fr.bearings:
        ecc = index.get(f"b{b}_centre_ecc_per_c")
        if ecc is not None and not values[ecc] <= cfg.CENTRELINE_MAX_ECC:
            for key in ("x", "y", "ecc"):
                values[index[f"b{b}_centre_{key}_per_c"]] = np.nan
    across_bearings(values)
    return dataclasses.replace(fr, values=values)
