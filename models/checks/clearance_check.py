"""A stated clearance that may be the diametral one, judged by the machine family the model knows.

``clearance_um`` is the radial clearance c; one typed in diametral (2c) halves every per-clearance feature without
putting any out of range. :func:`clearance_reason` reads a ``confident`` verdict's feature row once more at half
the stated clearance (``features.with_scale``, exact, no second extraction); when its OOD score is at or below
:data:`DIAMETRAL_OOD_RATIO` times the recording's own, the verdict gets ``clearance_diametral`` (uncertain). The
verdict stays the one at the clearance given. The measurements behind it: docs/checks.md.
"""
from __future__ import annotations

from collections.abc import Mapping

from rotordiag.core.notes import Length, Measured
from rotordiag.features import FeatureResult, Recording, with_scale

from ..status import CONFIDENT, UNCERTAIN, Reason
from . import CheckContext, Scorer

__all__ = ["DIAMETRAL_OOD_RATIO", "clearance_reason", "clearance_check"]

#: the OOD score at half the stated clearance at or below this fraction of the stated clearance's →
#: ``clearance_diametral``: half the clearance is at least as like the training family (module docstring). At 0.95
#: the far slips kept 25 confident verdicts, 1 of them a healthy machine shown moderate, for 3 in-family verdicts
#: fewer doubted
DIAMETRAL_OOD_RATIO = 1.0


def clearance_check(ctx: CheckContext) -> list[Reason]:
    """:func:`clearance_reason` of the context's recording, features, status before the doubts and OOD score."""
    if ctx.recording is None:
        return []
    reason = clearance_reason(ctx.score, ctx.recording, ctx.fr, ctx.status, ctx.ood_score)
    return [reason] if reason is not None else []


def clearance_reason(score: Scorer, recording: Recording, fr: FeatureResult, status: str | None,
                     ood_score: float) -> Reason | None:
    """``clearance_diametral`` when half the stated clearance makes a confident verdict's recording markedly more
    like the training family, else None.

    Parameters
    ----------
    score : callable
        A recording's features to (OOD score, class) with the active model (``models.predict.ood_score_and_class``
        bound to the bundle): given, so that this check does not import the predictor.
    recording : features.Recording
        The recording as sent; judged only when it states a clearance.
    fr : features.FeatureResult
        Its features (the speed the verdict was given at).
    status : str
        The verdict's status (before this doubt); only a confident one is judged.
    ood_score : float
        The recording's own OOD score at the clearance given.
    """
    if status != CONFIDENT or recording.clearance_um is None:
        return None
    try:
        ood_half, class_half = score(with_scale(fr, clearance_factor=0.5))
    except ValueError:
        return None
    ratio = ood_half / ood_score if ood_score > 0 else float("inf")
    if not ratio <= DIAMETRAL_OOD_RATIO:
        return None
    stated = recording.clearance_um
    said: list[str | Length] = (
        [x for k, (b, c) in enumerate(sorted(stated.items())) for x in ((", " if k else "") + f"bearing {b}: ",
                                                                       Length(float(c), "g"))]
        if isinstance(stated, Mapping) else [Length(float(stated), "g")])
    return Reason("clearance_diametral", UNCERTAIN,
                  {"clearance": Measured.of(*said), "ood_half": ood_half, "ood_score": ood_score,
                   "class_half": class_half})
