"""The checks that doubt a verdict, one module each: each gives reasons (``models.status.Reason``) from a recording's
features, its verdict and what else it needs, handed in (a :data:`Scorer` for a second reading), never the predictor.

Why a folder: the verdict's doubts are read in one place, and a check cannot reach back into ``models.predict``
(``tests/test_architecture.py`` enforces it). ``bearing_sets`` (the probe set the model reads), ``acquisitions``
(bearings 2 and 3 recorded apart), ``numbering`` (bearings numbered from the other end), ``reverse_2x`` (a coupling
2X whirling backward), ``common_mode`` (a 1X / 2X common to every probe), ``clearance_check`` (a diametral
clearance). What each was measured to do: docs/checks.md.
"""
from __future__ import annotations

from collections.abc import Callable

from rotordiag.features import FeatureResult

__all__ = ["Scorer"]

#: a recording's features to (OOD score, class name) with the active model: ``models.predict.ood_score_and_class``
#: bound to its bundle
Scorer = Callable[[FeatureResult], "tuple[float, str]"]
