"""A verdict of "aligned" that its own evidence contradicts: never confident.

The coupling bearings' largest 2X/1X is in every answer's evidence, and the classic rule of thumb reads it in
bands (``models.baselines.DEFAULT_RULE_CUTS``: 0.5 / 1 / 2). When it reads two or more bands above the model's
call — "aligned" beside a 2X/1X of 1 or more, the textbook's strong misalignment signature — the answer would
contradict what it shows; it is ``uncertain`` (``signature_contradicts_call``), the contradiction named, and
``inconclusive`` (no severity shown) from :data:`BANDS_INCONCLUSIVE` bands on — "aligned" beside a 2X/1X of 2 or
more: the independent-code machines of docs/robustness.md read 2–10 there, misaligned by 0.3–0.6 c. Outside the
training family the same reading makes the verdict inconclusive (``signature_above_call``, ``models.status``), so
this check judges recordings inside it only. The figures: docs/robustness.md, docs/train-verdict.md.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rotordiag.core.reasons import INCONCLUSIVE, UNCERTAIN

from ..baselines import DEFAULT_RULE_CUTS
from ..status import SIGNATURE_BANDS_ABOVE_CALL, Reason, coupling_2x_1x, signature_band
from . import CheckContext

__all__ = ["BANDS_INCONCLUSIVE", "contradiction_reason", "contradiction_check"]

#: the coupling 2X/1X this many rule-of-thumb bands or more above the call: no severity is shown (``inconclusive``)
BANDS_INCONCLUSIVE = SIGNATURE_BANDS_ABOVE_CALL + 1


def contradiction_reason(names: Sequence[str], row: np.ndarray, call: str, band_names: Sequence[str],
                         outside: bool) -> Reason | None:
    """``signature_contradicts_call`` when, inside the training family (``outside`` False), the coupling 2X/1X reads
    :data:`~models.status.SIGNATURE_BANDS_ABOVE_CALL` or more bands above ``call`` (``uncertain``; ``inconclusive``
    from :data:`BANDS_INCONCLUSIVE` bands on); else None."""
    if outside or call not in band_names:
        return None
    ratio = coupling_2x_1x(names, row)
    rule = signature_band(ratio, len(band_names))
    k = list(band_names).index(call)
    if rule is None or rule - k < SIGNATURE_BANDS_ABOVE_CALL:
        return None
    return Reason("signature_contradicts_call", INCONCLUSIVE if rule - k >= BANDS_INCONCLUSIVE else UNCERTAIN,
                  {"call": call, "ratio": ratio, "rule_band": band_names[rule], "rule_cut": DEFAULT_RULE_CUTS[rule - 1]})


def contradiction_check(ctx: CheckContext) -> list[Reason]:
    """:func:`contradiction_reason` of the context's row, call and bands (``ctx.ood``: outside the family)."""
    reason = contradiction_reason(ctx.names, ctx.row, ctx.call, ctx.band_names, ctx.ood)
    return [reason] if reason is not None else []
