"""Bearings numbered from the wrong end, judged by the machine family the model knows.

Bearing 1 is the generator's far end and 4 the exciter's; a plant numbering from the exciter end sends the train
as 4-3-2-1 with no feature out of range. :func:`numbering_check` scores a four-bearing, in-distribution
recording once more with its feature row renumbered (:func:`mirrored_row`); when that OOD score is at or below
:data:`NUMBERING_OOD_RATIO` times the recording's own, :func:`numbering_reason` gives ``bearing_numbering``
(uncertain). The verdict stays the one of the numbering given. The measurements behind it: docs/checks.md.
"""
from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from rotordiag.core.conventions import wrap_deg
from rotordiag.features import ACROSS_FEATURES, across_bearings

from .._patterns import bearing_feature, name_index
from ..status import UNCERTAIN, Reason
from . import CheckContext

__all__ = ["NUMBERING_OOD_RATIO", "mirrored_row", "numbering_reason", "has_every_bearing", "numbering_check"]

#: the other numbering's OOD score at or below this fraction of the recording's own → ``bearing_numbering``
#: (below the lowest ratio of correctly numbered recordings: docs/models-history.md, "Bearings numbered from the exciter end")
NUMBERING_OOD_RATIO = 0.95
_BEARINGS = (1, 2, 3, 4)


def has_every_bearing(names: Sequence[str], row: np.ndarray) -> bool:
    """Whether the row carries the 1X of all four bearings (``b{n}_1x_major_um_pp``)."""
    index = name_index(names)
    cols = [index.get(f"b{b}_1x_major_um_pp") for b in _BEARINGS]
    return all(j is not None and np.isfinite(row[j]) for j in cols)


def mirrored_row(names: Sequence[str], row: np.ndarray) -> np.ndarray:
    """The feature row of the same recording with every bearing ``b`` numbered ``5 − b``.

    Each per-bearing feature depends on that bearing's probes alone, so ``b{n}_…`` takes ``b{5−n}_…``'s value;
    a phase difference ``dphase_kx_bi_bj`` = wrap(φ_i − φ_j) becomes wrap(φ_{5−i} − φ_{5−j}), i.e. the wrapped
    negative of ``dphase_kx_b{5−j}_b{5−i}``; the columns across bearings are built again from the renumbered
    per-bearing columns (:func:`features.across_bearings`); the speed and the motion type do not depend on the
    numbering."""
    same, src_same, phase, src_phase, absent = _mirror_plan(tuple(names))
    row = np.asarray(row, dtype=float)
    out = np.array(row, dtype=float, copy=True)
    out[same] = row[src_same]
    out[phase] = wrap_deg(-row[src_phase])
    out[absent] = np.nan
    across_bearings(out, names)
    return out


@lru_cache(maxsize=16)
def _mirror_plan(names: tuple[str, ...]) -> tuple[np.ndarray, ...]:
    """Where :func:`mirrored_row` takes each column from, per feature-name list (built once per model):
    (columns, their per-bearing sources), (phase-difference columns, their sources), columns with no source."""
    index = {n: i for i, n in enumerate(names)}
    same: list[int] = []
    src_same: list[int] = []
    phase: list[int] = []
    src_phase: list[int] = []
    absent: list[int] = []
    for j, name in enumerate(names):
        parsed = bearing_feature(name)
        if parsed is None or name in ACROSS_FEATURES:       # built again from the per-bearing columns
            continue
        prefix, bearings, suffix = parsed
        if len(bearings) == 1:
            k = index.get(f"b{5 - bearings[0]}_{suffix}")
            dst, src = same, src_same
        else:
            k = index.get(f"{prefix}_b{5 - bearings[1]}_b{5 - bearings[0]}_{suffix}")
            dst, src = phase, src_phase
        if k is None:
            absent.append(j)
        else:
            dst.append(j)
            src.append(k)
    return tuple(np.array(a, dtype=np.intp) for a in (same, src_same, phase, src_phase, absent))


def numbering_reason(ood_score: float, other_ood_score: float, call: str, other_call: str) -> Reason | None:
    """``bearing_numbering`` when the renumbered row's OOD score is at or below :data:`NUMBERING_OOD_RATIO` of the
    row's own, else None."""
    if not (ood_score > 0 and other_ood_score <= NUMBERING_OOD_RATIO * ood_score):
        return None
    values = {"other_ood_score": other_ood_score, "ood_score": ood_score, "call": call}
    if other_call != call:
        return Reason("bearing_numbering", UNCERTAIN, {**values, "other_call": other_call})
    return Reason("bearing_numbering", UNCERTAIN, values, "same_call")


def numbering_check(ctx: CheckContext) -> list[Reason]:
    """``bearing_numbering`` for an in-distribution four-bearing row that is markedly more like the training family
    numbered from the other end: one more class and OOD pass, on the renumbered row (:func:`mirrored_row`)."""
    if ctx.ood or not has_every_bearing(ctx.names, ctx.row):
        return []
    other = mirrored_row(ctx.names, ctx.row)[None, :]
    reason = numbering_reason(ctx.ood_score, float(ctx.ood_of(other)[0]), ctx.call, ctx.classes_of(other)[0])
    return [reason] if reason is not None else []
