"""Bearings either side of the coupling recorded in separate acquisitions: never a confident verdict.

``features.Recording.acquisitions`` says which bearings were sampled together; between acquisitions the phase
differences are not measured (``features._acquisitions``). The phase across the coupling (bearings 2 and 3) is
one the model leans on to tell aligned from slight, so a verdict without it is at best ``uncertain``
(``separate_acquisitions``), with what to do. The phase differences between bearings 1 and 2 or 3 and 4 hardly
move the shipped model's calls (docs/robustness.md's clean base set, seed 815, with bearing 1 or bearing 4 in a take
of its own: the same class, severity and status for 237 of the 240 recordings, the Δ estimate within 0.03), so
splitting those is only the features' warning.
"""
from __future__ import annotations

from typing import Any

from rotordiag.core.conventions import COUPLING_BEARINGS
from rotordiag.features import format_acquisitions, split_pairs

from .status import UNCERTAIN, Reason

__all__ = ["acquisitions_reason"]


def acquisitions_reason(feature_result: Any) -> Reason | None:
    """``separate_acquisitions`` (uncertain) when bearings 2 and 3 are both recorded, in separate acquisitions
    (``feature_result.acquisitions``); else None."""
    acquisitions = getattr(feature_result, "acquisitions", ())
    if not split_pairs(acquisitions, [COUPLING_BEARINGS]):
        return None
    i, j = COUPLING_BEARINGS
    return Reason("separate_acquisitions", UNCERTAIN,
                  f"bearings {i} and {j} were recorded in separate acquisitions ({format_acquisitions(acquisitions)}): "
                  "the phase across the coupling is not measured, and the model tells aligned from slight partly by "
                  f"it — record bearings {i} and {j} in one acquisition (or trend this machine's 2X/1X) before acting")
