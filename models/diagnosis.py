"""One recording's verdict, the same everywhere: features, the speed judged when in doubt, the doubts read again.

:func:`diagnose_recording` is the one path from a :class:`features.Recording` to a verdict — the service, ``rotordiag
diagnose`` and the benchmarks call it — so that the verdict, its speed and the features it was computed from agree
wherever a recording is diagnosed. Each step is its own module: ``models.speed_choice`` (a doubtful estimated
speed judged by the machine family the model knows), ``models.checks.common_mode`` (a 1X / 2X common to every probe) and
``models.checks.clearance_check`` (a stated clearance that may be the diametral one).
"""
from __future__ import annotations

from functools import partial
from typing import Any

from rotordiag.features import FeatureResult, Recording, extract_features

from .checks.clearance_check import clearance_reason
from .checks.common_mode import common_mode_reason
from .predict import Verdict, diagnose, ood_score_and_class
from .speed_choice import choose_speed

__all__ = ["diagnose_recording"]


def diagnose_recording(bundle: Any, recording: Recording, *, clearance_um: float | None = None,
                       top_k: int = 5, fr: FeatureResult | None = None) -> tuple[Verdict, FeatureResult]:
    """Features and verdict of one recording, the speed judged by the model when the estimate is in doubt.

    ``extract_features`` (unless ``fr``, the recording's features, is given) then ``diagnose``, then
    ``models.speed_choice.choose_speed``, then the common-mode doubt (``models.checks.common_mode``: the verdict read
    again without a 1X / 2X common to every probe) and the clearance doubt (``models.checks.clearance_check``: a confident verdict read
    again at half the stated clearance).
    Every caller that diagnoses a recording (the service, ``rotordiag diagnose``, the benchmarks) goes through
    here, so that the verdict, its speed and the features it was computed from are the same everywhere.

    Raises
    ------
    ValueError
        As ``extract_features`` and ``diagnose``, with a message for the user.
    """
    if fr is None:
        fr = extract_features(recording)
    verdict = diagnose(bundle, fr, clearance_um=clearance_um, top_k=top_k)
    verdict, fr, _ = choose_speed(bundle, recording, fr, verdict, clearance_um=clearance_um, top_k=top_k)
    score = partial(ood_score_and_class, bundle)
    doubts = [r for r in (common_mode_reason(score, recording, fr, verdict),
                          clearance_reason(score, recording, fr, verdict)) if r is not None]
    if doubts:
        verdict = diagnose(bundle, fr, clearance_um=clearance_um, top_k=top_k, extra_reasons=doubts)
    return verdict, fr
