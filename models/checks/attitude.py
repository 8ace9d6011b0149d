"""The journals' attitude angles when the clearance is not stated: evidence that needs no clearance, judged anyway.

Without the clearance every per-clearance feature is missing, the shaft centreline with them, and the OOD scorer
and the training envelope judge the recording on what is left. But the *direction* of the shaft centreline in its
bearing — the attitude angle from the load line — does not depend on the clearance: it is the angle of the DC
position, whatever c it is divided by. :func:`attitude_reason` puts that direction at a defined eccentricity and
asks the model's training envelope (``MisalignmentModel.envelope_findings``, ``b{n}_attitude_deg``) whether a
machine it was trained on held its journal so; a direction outside makes a ``confident`` verdict ``uncertain``
(``attitude_outside_training``): a bearing unlike the training's plain cylindrical ones (a tilting-pad or a
lightly loaded bearing holds its journal near the load line), or DC readings not referenced to the bearing centre.
The measurements behind it: docs/train-verdict.md and docs/robustness.md.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from rotordiag.features import FeatureResult

from .._patterns import name_index
from ..status import CONFIDENT, UNCERTAIN, Reason
from . import CheckContext

__all__ = ["ATTITUDE_PROBE_ECC", "attitude_reason", "attitude_check"]

#: the eccentricity (per clearance) the centreline's direction is put at for the envelope: inside the range where
#: the attitude angle is defined (``ATTITUDE_MIN_ECC``–1); the angle does not depend on it
ATTITUDE_PROBE_ECC = 0.5


def attitude_reason(names: Sequence[str], row: np.ndarray, fr: FeatureResult, status: str | None,
                    envelope_of: Callable[[np.ndarray], list[list[dict]]] | None) -> Reason | None:
    """``attitude_outside_training`` (uncertain) for a confident verdict whose recording states no clearance and
    whose journals' DC directions lie outside the training envelope's ``b{n}_attitude_deg``; else None."""
    if status != CONFIDENT or envelope_of is None:
        return None
    index = name_index(names)
    probe = np.array(row, dtype=float, copy=True)
    judged = 0
    for b, d in (getattr(fr, "bearings", None) or {}).items():   # features given without their bearings' DC: none
        cx, cy = index.get(f"b{b}_centre_x_per_c"), index.get(f"b{b}_centre_y_per_c")
        if cx is None or cy is None or np.isfinite(row[cx]) or getattr(d, "dc_removed", False):
            continue                                 # not read by the model, stated with a clearance, or no DC
        if np.isfinite(getattr(d, "clearance_um", np.nan)):
            continue
        mx, my = (float(v) for v in d.mean_um)
        e = float(np.hypot(mx, my))
        if not (np.isfinite(e) and e > 0):
            continue
        probe[cx], probe[cy] = ATTITUDE_PROBE_ECC * mx / e, ATTITUDE_PROBE_ECC * my / e
        judged += 1
    if not judged:
        return None
    found = [f for f in envelope_of(probe[None, :])[0]
             if f["feature"].endswith("_attitude_deg") and not f["feature"].endswith("_offset_deg")]
    if not found:
        return None
    where = ", ".join(f"{f['feature'].split('_')[0].replace('b', 'bearing ')} {f['value']:.0f}° (trained "
                      f"{f['train_min']:.0f}–{f['train_max']:.0f}°)" for f in found)
    return Reason("attitude_outside_training", UNCERTAIN, {"where": where})


def attitude_check(ctx: CheckContext) -> list[Reason]:
    """:func:`attitude_reason` of the context's row, features, status before the doubts and the model's envelope."""
    reason = attitude_reason(ctx.names, ctx.row, ctx.fr, ctx.status, ctx.envelope_of)
    return [reason] if reason is not None else []
