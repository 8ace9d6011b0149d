"""A verdict that rests on a 1X or 2X common to every probe (electrical pickup), read again without it.

Mains pickup on a grid-synchronous generator's probe cables sits exactly at its 1X / 2X with the same amplitude
and phase at every probe, which no shaft orbit does (``features._common_mode``). :func:`common_mode_reason` reads a
recording whose common share is at least :data:`COMMON_MODE_DOUBT_SHARE` once more without that common signal
(``features.without_common_mode``); when the class differs the verdict gets ``common_mode`` (``inconclusive`` when
the sanity check found the pickup dominating, else ``uncertain``). The verdict itself is the recording's as sent.
The measurements behind it: docs/checks.md.
"""
from __future__ import annotations

from rotordiag.core.notes import Length, Measured
from rotordiag.features import (
    COMMON_MODE_NOTABLE_SHARE,
    FeatureResult,
    Recording,
    common_mode,
    extract_features,
    without_common_mode,
)

from ..status import INCONCLUSIVE, UNCERTAIN, Reason
from . import CheckContext, Scorer

__all__ = ["COMMON_MODE_DOUBT_SHARE", "common_mode_reason", "common_mode_check"]

#: a 1X or 2X whose common share (``features.common_mode``) reaches this is read again without its common part
#: (``features.COMMON_MODE_NOTABLE_SHARE``: about one in-family recording in 1000); doubted only when the class changes
COMMON_MODE_DOUBT_SHARE = COMMON_MODE_NOTABLE_SHARE
_ORDERS = (1, 2)


def common_mode_check(ctx: CheckContext) -> list[Reason]:
    """:func:`common_mode_reason` of the context's recording, features, status before the doubts and call."""
    if ctx.recording is None:
        return []
    reason = common_mode_reason(ctx.score, ctx.recording, ctx.fr, ctx.status, ctx.call)
    return [reason] if reason is not None else []


def common_mode_reason(score: Scorer, recording: Recording, fr: FeatureResult, status: str | None,
                       call: str | None) -> Reason | None:
    """``common_mode`` when the verdict's class changes with the common 1X / 2X removed, else None.

    Parameters
    ----------
    score : callable
        A recording's features to (OOD score, class) with the active model (``models.predict.ood_score_and_class``
        bound to the bundle): given, so that this check does not import the predictor.
    recording : features.Recording
        The recording as sent.
    fr : features.FeatureResult
        Its features (the speed the verdict was given at).
    status : str
        The verdict's status (before this doubt); an inconclusive one is not read again.
    call : str
        The classifier's class of the recording (``Verdict.model_severity``).
    """
    found = [cm for k in _ORDERS if (cm := common_mode(fr, k)) is not None and cm.share >= COMMON_MODE_DOUBT_SHARE]
    if not found or status == INCONCLUSIVE or call is None:
        return None
    try:
        clean = without_common_mode(recording, fr, found)
        fr_clean = extract_features(clean, speed_estimate_rpm=fr.speed_rpm if fr.speed_source == "estimated" else None,
                                    speed_notes=list(fr.warnings))
        _, other = score(fr_clean)
    except ValueError:
        return None
    if other == call:
        return None
    dominant = [f.code for f in fr.sanity if f.code in ("common_mode_1x", "common_mode_2x")]
    what = [x for k, cm in enumerate(found)
            for x in (("; " if k else "") + f"{cm.order}X: ", Length(cm.amp_um_pp), f" pk-pk at {cm.phase_lag_deg:.0f}°, "
                      f"{100 * cm.share:.0f} % of its power over {cm.n_probes} probes")]
    values = {"orders": " and ".join(f"{cm.order}X" for cm in found), "per_order": Measured.of(*what),
              "other_call": other, "call": call}
    if dominant:
        return Reason("common_mode", INCONCLUSIVE, {**values, "dominant": " and ".join(dominant)}, "dominant")
    return Reason("common_mode", UNCERTAIN, values)
