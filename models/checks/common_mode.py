"""A 1X or 2X common to every probe (electrical pickup) is removed, and the verdict given on the rest.

Mains pickup on a grid-synchronous generator's probe cables sits exactly at its 1X / 2X with the same amplitude
and phase at every probe, which no shaft orbit does (``features._common_mode``). A vibration analyst subtracts it
and reads what is left; so does :func:`remove_pickup`: a recording whose 1X or 2X common share reaches
:data:`COMMON_MODE_REMOVE_SHARE` is read again without that common signal (``features.without_common_mode``), the
verdict is given on that reading, and :meth:`PickupRemoved.reason` says so (``common_mode``, ``uncertain``: what was
removed, and the class the recording as sent would have had). Why not the recording as sent: its class is the
pickup's, a 2X the model reads as a coupling's. The measurements behind it: docs/checks.md.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

from rotordiag.core.notes import Length, Measured
from rotordiag.features import (
    COMMON_MODE_NOTABLE_SHARE,
    CommonMode,
    FeatureResult,
    Recording,
    common_mode,
    without_common_mode,
)

from ..status import UNCERTAIN, Reason

__all__ = ["COMMON_MODE_REMOVE_SHARE", "PickupRemoved", "remove_pickup"]

#: a 1X or 2X whose common share (``features.common_mode``) reaches this is removed before the verdict
#: (``features.COMMON_MODE_NOTABLE_SHARE``: about one in-family recording in 1000 reaches it)
COMMON_MODE_REMOVE_SHARE = COMMON_MODE_NOTABLE_SHARE
_ORDERS = (1, 2)
#: the sanity findings of the recording as sent kept with the reading without its pickup (they say what was sent)
_SAID = ("common_mode_1x", "common_mode_2x")

#: the pipeline's reading of a recording at a speed (``models.pipeline.read_features``)
Reader = Callable[[Recording, "float | None"], FeatureResult]


@dataclass(frozen=True)
class PickupRemoved:
    """A recording with its common 1X / 2X removed, and its features read at the speed of the recording as sent.

    Attributes
    ----------
    recording : features.Recording
        The recording without the common signals (µm).
    fr : features.FeatureResult
        Its features and sanity findings, with the warnings of the reading as sent (the speed notes among them) and
        its common-mode sanity findings (``common_mode_1x`` / ``common_mode_2x``: what was sent).
    found : tuple of features.CommonMode
        The common signals removed.
    """

    recording: Recording
    fr: FeatureResult
    found: tuple[CommonMode, ...]

    def reason(self, call_as_sent: str | None, call: str | None) -> Reason:
        """``common_mode`` (uncertain): what was removed, and the class of the recording as sent when it differs
        from ``call``, the class given without the pickup."""
        what = [x for k, cm in enumerate(self.found)
                for x in (("; " if k else "") + f"{cm.order}X: ", Length(cm.amp_um_pp),
                          f" pk-pk at {cm.phase_lag_deg:.0f}°, {100 * cm.share:.0f} % of its power over "
                          f"{cm.n_probes} probes")]
        values = {"orders": " and ".join(f"{cm.order}X" for cm in self.found), "per_order": Measured.of(*what),
                  "call": call}
        if call_as_sent != call:
            return Reason("common_mode", UNCERTAIN, {**values, "call_as_sent": call_as_sent}, "changed")
        return Reason("common_mode", UNCERTAIN, values)


def remove_pickup(recording: Recording, fr: FeatureResult, read: Reader) -> PickupRemoved | None:
    """``recording`` without each 1X / 2X whose common share reaches :data:`COMMON_MODE_REMOVE_SHARE`, read by
    ``read`` at the speed ``fr`` was given (an estimated one kept: the pickup is no reason to read another speed);
    None when no order's common share reaches it, the recording cannot be read without it, or it is read by take
    (each take's phases refer to its own keyphasor, so one shaft angle cannot subtract a signal from both)."""
    if recording.keyphasor_takes is not None:
        return None
    found = tuple(cm for k in _ORDERS
                  if (cm := common_mode(fr, k)) is not None and cm.share >= COMMON_MODE_REMOVE_SHARE)
    if not found:
        return None
    try:
        clean = without_common_mode(recording, fr, list(found))
        fr_clean = read(clean, float(fr.speed_rpm) if fr.speed_source == "estimated" else None)
    except ValueError:
        return None
    said = tuple(f for f in fr.sanity if f.code in _SAID)     # what the recording as sent showed: still said
    return PickupRemoved(clean, replace(fr_clean, warnings=fr.warnings, sanity=(*fr_clean.sanity, *said)), found)
