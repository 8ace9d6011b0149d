"""A misalignment call that rests on the static offset between the coupling-end journals (``static_offset_only``).

The simulator that trained the model ties the two coupling-end journals together (MODEL.md: r3 = r4 on an aligned
train), so to the model any static offset between them is a shaft-line offset; on a real train each journal sits
by its own load, and a DC gap referenced to the wrong zero reads the same. :func:`one_position_check` reads a
misalignment call's row once more with the two journals at one position (``models.status.journals_at_one_position``,
two rows); when the classifier lowers the call there, the verdict gets ``static_offset_only`` (uncertain). The
status lists it right after the call's own 2X reason (``models.status.ModelCall.static_offset``). The measurements
behind it: docs/robustness.md, "coupling journals apart".
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..status import UNCERTAIN, Reason, journals_apart_c, journals_at_one_position
from . import CheckContext

__all__ = ["one_position_check", "static_offset_reason"]


def one_position_check(ctx: CheckContext) -> list[Reason]:
    """``static_offset_only`` when a misalignment call falls to a lower band with the coupling-end journals at one
    static position; none for an aligned call or when their centrelines are not measured."""
    if ctx.call == ctx.aligned_band:
        return []
    rows = journals_at_one_position(ctx.names, ctx.row)
    if rows is None:
        return []
    bands = list(ctx.band_names)
    lower = min(bands.index(c) for c in ctx.classes_of(rows))
    reason = static_offset_reason(lower, bands.index(ctx.call), bands, ctx.names, ctx.row)
    return [reason] if reason is not None else []


def static_offset_reason(lower: int, call_index: int, band_names: Sequence[str], names: Sequence[str],
                         row: np.ndarray) -> Reason | None:
    """``static_offset_only`` when ``lower`` (the lowest band with the journals at one position) is below the call's
    band ``call_index``, with how far apart the journals sit; else None."""
    if not lower < call_index:
        return None
    values: dict[str, object] = {}
    if lower > 0:
        values["lower_band"] = str(band_names[lower]) if len(band_names) > lower else f"band {lower}"
    apart = journals_apart_c(names, row)
    if apart is not None:
        values.update(apart_c=float(np.hypot(*apart)), apart_x_c=float(apart[0]), apart_y_c=float(apart[1]))
    variant = {(False, False): "default", (False, True): "apart", (True, False): "aligned",
               (True, True): "aligned_apart"}[(lower == 0, apart is not None)]
    return Reason("static_offset_only", UNCERTAIN, values, variant)
