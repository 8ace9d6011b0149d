"""The features of a recording as if its stated clearance were another: a row transform, no second extraction.

The clearance enters the features only as a divisor: every ``*_per_c`` feature is a length over the radial
clearance c, ``orbit12_area_per_c2`` an area over c², and the shaft-centreline position ``centre_*_per_c`` is NaN
when its eccentricity exceeds ``CENTRELINE_MAX_ECC`` (a raw probe gap, not a position in the bearing). So the
features at ``factor × c`` follow from those at c exactly; a test checks them against a second extraction. Used to
ask whether a stated clearance may be the diametral one (``models.clearance_check``).
"""
from __future__ import annotations

import dataclasses
import re

import numpy as np

from . import _config as cfg

__all__ = ["with_clearance_scaled"]

_PER_C = re.compile(r"^b(\d+)_.*_per_c$")
_PER_C2 = re.compile(r"^b(\d+)_.*_per_c2$")


def with_clearance_scaled(fr, factor: float):
    """``fr`` (a ``FeatureResult``) as extracted with every bearing's clearance multiplied by ``factor``.

    The per-clearance features are divided by ``factor`` (areas by its square); a centreline whose eccentricity then
    exceeds ``CENTRELINE_MAX_ECC`` becomes missing, as the extraction makes it. Exact for ``factor <= 1``; above 1 a
    centreline missing at the stated clearance stays missing. The bearing details keep the stated clearance (the
    evidence's, not the feature vector's).
    """
    if not (np.isfinite(factor) and factor > 0):
        raise ValueError(f"factor: must be a positive number, got {factor!r}")
    values = np.array(fr.values, dtype=float, copy=True)
    names = list(fr.names)
    for i, name in enumerate(names):
        if _PER_C2.match(name):
            values[i] /= factor * factor
        elif _PER_C.match(name):
            values[i] /= factor
    index = {n: i for i, n in enumerate(names)}
    for b in fr.bearings:
        ecc = index.get(f"b{b}_centre_ecc_per_c")
        if ecc is not None and not values[ecc] <= cfg.CENTRELINE_MAX_ECC:
            for key in ("x", "y", "ecc"):
                values[index[f"b{b}_centre_{key}_per_c"]] = np.nan
    return dataclasses.replace(fr, values=values)
