"""A misalignment call whose coupling 2X whirls backward: never confident.

In the training family a coupling's 2X whirls forward; a 2X that is not shaft motion (pickup with its own phase
on each cable) is reverse as often as forward, and the model reads a strong 2X as misalignment. So a misalignment
call whose coupling bearing with a sizeable 2X (at least half the larger coupling bearing's) whirls backward with
reverse ≥ :data:`REVERSE_2X_MIN_RATIO` × forward is ``uncertain`` (``reverse_2x``): a doubt, never a finding.
The measurements behind it: docs/checks.md.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rotordiag.core.conventions import COUPLING_BEARINGS

from .._patterns import name_index
from ..status import UNCERTAIN, Reason
from . import CheckContext

__all__ = ["REVERSE_2X_MIN_RATIO", "REVERSE_2X_MIN_SHARE", "coupling_reverse_2x", "reverse_2x_reason", "reverse_2x_check"]

#: a coupling bearing's 2X reverse/forward ratio from which a misalignment call is doubted (held-out plants' 99th
#: percentile 1.6–1.9)
REVERSE_2X_MIN_RATIO = 2.0
#: a coupling bearing's 2X is judged when its orbit's major axis is at least this share of the larger one's (a 2X
#: near the noise has a direction of chance)
REVERSE_2X_MIN_SHARE = 0.5


def coupling_reverse_2x(names: Sequence[str], row: np.ndarray) -> tuple[int, float] | None:
    """The coupling bearing whose sizeable 2X whirls backward the most and its reverse/forward ratio, when that
    ratio is at least :data:`REVERSE_2X_MIN_RATIO`; else None (also when the 2X is not measured)."""
    index = name_index(names)
    major: dict[int, float] = {}
    ratio: dict[int, float] = {}
    for b in COUPLING_BEARINGS:
        i, j = index.get(f"b{b}_2x_major_um_pp"), index.get(f"b{b}_2x_rev_fwd_ratio")
        if i is None or j is None or not (np.isfinite(row[i]) and np.isfinite(row[j])):
            continue
        major[b], ratio[b] = float(row[i]), float(row[j])
    if not major or not max(major.values()) > 0:
        return None
    judged = [b for b in major if major[b] >= REVERSE_2X_MIN_SHARE * max(major.values())]
    b = max(judged, key=lambda k: ratio[k])
    return (b, ratio[b]) if ratio[b] >= REVERSE_2X_MIN_RATIO else None


def reverse_2x_reason(names: Sequence[str], row: np.ndarray, misaligned_call: bool) -> Reason | None:
    """``reverse_2x`` (uncertain) for a misalignment call whose coupling 2X whirls backward
    (:func:`coupling_reverse_2x`); else None."""
    if not misaligned_call:
        return None
    found = coupling_reverse_2x(names, row)
    if found is None:
        return None
    b, r = found
    return Reason("reverse_2x", UNCERTAIN, {"bearing": b, "reverse_per_forward": r})


def reverse_2x_check(ctx: CheckContext) -> list[Reason]:
    """``reverse_2x`` (:func:`reverse_2x_reason`) for a misalignment call on a coupling 2X that whirls backward."""
    reason = reverse_2x_reason(ctx.names, ctx.row, ctx.call != ctx.aligned_band)
    return [reason] if reason is not None else []
