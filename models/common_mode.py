"""A verdict that rests on a 1X or 2X common to every probe (electrical pickup), read again without it.

A 2-pole generator runs synchronously with the grid, so mains pickup on the probe cables (a ground loop,
a shared supply) sits exactly at its 1X (50/60 Hz) and 2X (100/120 Hz): the same amplitude and phase at
every probe. No shaft orbit looks like that (``features._common_mode``). When it dominates an order, the
sanity check ``common_mode_1x`` / ``common_mode_2x`` warns (a share of 0.85 over 8 probes, 0.95 over 6;
held-out machines reach 0.66 and 0.92). A weaker pickup beside the shaft's own 2X still moves the verdict: the
classifier reads it as a coupling's 2X, and a share of 0.6–0.85 is no proof of pickup on its own.

So :func:`common_mode_reason` reads a recording whose 1X or 2X common share is at least
:data:`COMMON_MODE_DOUBT_SHARE` once more with that common signal removed from every channel
(``features.without_common_mode``); when the class differs, the verdict gets ``common_mode``: the call rests on a
part of the signal that no shaft motion explains, and the message says what the class is without it and what to
check — ``inconclusive`` when the sanity check found that part dominating (the order is pickup, not shaft: no
severity from it), else ``uncertain``. When the class is the same either way the pickup does not matter to it,
and the sanity warning alone keeps the verdict from ``confident``. The verdict itself is the recording's as sent.

docs/robustness.md, row "mains pickup at 2X, 10 µm" (the clean base set, seed 815, a 10 µm 0-pk pickup at 2X on
every channel): before these checks 50 of 240 verdicts were ``confident``, 9 of them two bands off (8 aligned
machines shown moderate, a flexible coupling at Δ 0.14 shown severe); with them 25, none two bands off (status 10 / 50 / 40 %;
42 of the 48 healthy machines ``inconclusive``). In family nothing changes: of 1920 held-out recordings (clean base sets of seeds 815–817, far,
presets, SNR 15 dB, speed unknown, coupling bearings only) 5 were read twice and none doubted.
"""
from __future__ import annotations

from typing import Any

from rotordiag.features import (
    COMMON_MODE_NOTABLE_SHARE,
    FeatureResult,
    Recording,
    common_mode,
    extract_features,
    without_common_mode,
)

from .status import INCONCLUSIVE, UNCERTAIN, Reason

__all__ = ["COMMON_MODE_DOUBT_SHARE", "common_mode_reason"]

#: a 1X or 2X whose common share (``features.common_mode``) reaches this is read again without its common part
#: (``features.COMMON_MODE_NOTABLE_SHARE``: about one in-family recording in 1000); doubted only when the class changes
COMMON_MODE_DOUBT_SHARE = COMMON_MODE_NOTABLE_SHARE
_ORDERS = (1, 2)


def common_mode_reason(bundle: Any, recording: Recording, fr: FeatureResult, verdict: Any) -> Reason | None:
    """``common_mode`` when the verdict's class changes with the common 1X / 2X removed, else None.

    Parameters
    ----------
    bundle : models.ModelBundle or fitted model
    recording : features.Recording
        The recording as sent.
    fr : features.FeatureResult
        Its features (the speed the verdict was given at).
    verdict : models.Verdict
        Its verdict; an inconclusive one is not read again.
    """
    from .predict import ood_score_and_class

    found = [cm for k in _ORDERS if (cm := common_mode(fr, k)) is not None and cm.share >= COMMON_MODE_DOUBT_SHARE]
    if not found or verdict.status == INCONCLUSIVE or verdict.model_severity is None:
        return None
    try:
        clean = without_common_mode(recording, fr, found)
        fr_clean = extract_features(clean, speed_estimate_rpm=fr.speed_rpm if fr.speed_source == "estimated" else None,
                                    speed_notes=list(fr.warnings))
        _, other = ood_score_and_class(bundle, fr_clean)
    except ValueError:
        return None
    if other == verdict.model_severity:
        return None
    dominant = [f.code for f in fr.sanity if f.code in ("common_mode_1x", "common_mode_2x")]
    what = "; ".join(f"{cm.order}X: {cm.amp_um_pp:.3g} µm pk-pk at {cm.phase_lag_deg:.0f}°, {100 * cm.share:.0f} % of "
                     f"its power over {cm.n_probes} probes" for cm in found)
    return Reason(
        "common_mode", INCONCLUSIVE if dominant else UNCERTAIN,
        f"most of the {' and '.join(f'{cm.order}X' for cm in found)} is one signal common to every probe ({what}); a "
        f"shaft's orbit differs from probe to probe and bearing to bearing, so that part is likely electrical pickup "
        f"(mains at the running frequency or twice it on a grid-synchronous generator) or the probe mountings "
        f"vibrating together. Without it the class is {other!r}, not {verdict.model_severity!r}: check the probe "
        "cabling and grounding (a probe at a fixed target reads the pickup alone) before acting on this verdict"
        + (f" ({' and '.join(dominant)}: that part dominates, so no severity is given)" if dominant else ""))
