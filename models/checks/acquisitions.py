"""Bearings either side of the coupling recorded in separate acquisitions: never a confident verdict.

Between acquisitions (``features.Recording.acquisitions``) the phase differences are not measured, and the phase
across the coupling (bearings 2 and 3) is one the model leans on; such a verdict is at best ``uncertain``
(``separate_acquisitions``). The reason gives the model's two readings with that phase put in — in phase (0°) and
in anti-phase (180°) — so that an engineer who knows the phase from elsewhere knows which applies. Splitting
bearings 1-2 or 3-4 is only the features' warning. The measurements behind it: docs/checks.md.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rotordiag.core.conventions import COUPLING_BEARINGS
from rotordiag.features import format_acquisitions, split_pairs

from ..status import UNCERTAIN, Reason
from . import CheckContext

__all__ = ["COUPLING_PHASES_DEG", "coupling_split", "coupling_phase_rows", "acquisitions_reason", "acquisitions_check"]

#: the phases across the coupling the model reads a recording at when it was not measured: in phase, anti-phase
COUPLING_PHASES_DEG = (0.0, 180.0)


def coupling_split(feature_result: Any) -> bool:
    """Whether bearings 2 and 3 are both recorded, in separate acquisitions (``feature_result.acquisitions``)."""
    return bool(split_pairs(getattr(feature_result, "acquisitions", ()), [COUPLING_BEARINGS]))


def coupling_phase_rows(names: Sequence[str], row: np.ndarray) -> np.ndarray | None:
    """``row`` with the 1X and 2X phase differences across the coupling (x and y) set to each of
    :data:`COUPLING_PHASES_DEG`, shape (2, n_features); None when the model does not read those features."""
    i, j = COUPLING_BEARINGS
    index = {n: k for k, n in enumerate(names)}
    found = [index.get(f"dphase_{k}x_b{i}_b{j}_{d}_deg") for k in (1, 2) for d in ("x", "y")]
    cols = [c for c in found if c is not None]
    if len(cols) < len(found):
        return None
    rows = np.repeat(np.asarray(row, dtype=float)[None, :], len(COUPLING_PHASES_DEG), axis=0)
    for r, phase in enumerate(COUPLING_PHASES_DEG):
        rows[r, cols] = phase
    return rows


def acquisitions_reason(feature_result: Any, readings: Sequence[str] | None = None) -> Reason | None:
    """``separate_acquisitions`` (uncertain) when :func:`coupling_split`; else None. ``readings``: the model's class
    at each of :data:`COUPLING_PHASES_DEG` (:func:`coupling_phase_rows`), said in the message."""
    if not coupling_split(feature_result):
        return None
    i, j = COUPLING_BEARINGS
    values = {"bearing_a": i, "bearing_b": j, "acquisitions": format_acquisitions(feature_result.acquisitions)}
    if readings is None or len(readings) != len(COUPLING_PHASES_DEG):
        return Reason("separate_acquisitions", UNCERTAIN, values)
    in_phase, anti = readings
    return Reason("separate_acquisitions", UNCERTAIN, {**values, "in_phase": in_phase, "anti_phase": anti},
                  "phase_read_same" if in_phase == anti else "phase_read")


def acquisitions_check(ctx: CheckContext) -> list[Reason]:
    """``separate_acquisitions`` with the model's class at each phase across the coupling (:func:`acquisitions_reason`)
    when bearings 2 and 3 were recorded apart, else none."""
    if not coupling_split(ctx.fr):
        return []
    rows = coupling_phase_rows(ctx.names, ctx.row)
    reason = acquisitions_reason(ctx.fr, None if rows is None else ctx.classes_of(rows))
    return [reason] if reason is not None else []
