"""A doubtful estimated speed judged by the machine family the model knows (issue 15, item 6).

Without a keyphasor or a given speed, the running speed is read from the spectrum (``features.extract_features``).
In whirl, whip and period-n motion that reading can be wrong — a whirl partner, a 2X or a sub-harmonic read as the
1X — and the estimator then says it is in doubt (``features.speed_in_doubt``); the features computed at a wrong
speed describe no machine the model was trained on, and the verdict is out of distribution.

A vibration analyst in that place tries the other speeds the spectrum allows and keeps the one at which the machine
makes sense. :func:`choose_speed` does the same with the model's own yardstick, handed in as a ``judge`` (a speed to
the OOD score of the recording's features there, bound to the active model by ``models.pipeline``): when the estimate
is in doubt **and** out of distribution, each of ``features.speed_alternatives_rpm`` is judged, and the reading chosen
is the one in distribution with the lowest OOD score, when that score is at least :data:`SPEED_CHOICE_MIN_OOD_GAIN`
below the estimate's. The verdict at it stays ``uncertain`` (:func:`chosen_speed_notes` put the speed in doubt:
``speed_ambiguous``). Nothing changes for a recording whose estimate is not in doubt, or in distribution, or unlike
the training data at every speed. Measured on docs/robustness.md's base sets: docs/features.md, "Eighth pass".
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from rotordiag.features import FeatureResult, Note, Recording, speed_alternatives_rpm, speed_in_doubt

__all__ = ["SPEED_CHOICE_MIN_OOD_GAIN", "SpeedChoice", "Judge", "choose_speed", "chosen_speed_notes"]

#: a reading replaces the estimate only when its OOD score is this much lower (and it is in distribution):
#: a smaller gain is no evidence (chosen on the robustness base sets of seeds 815–818; docs/features.md)
SPEED_CHOICE_MIN_OOD_GAIN = 0.15

#: a speed (r/min) to the (OOD score, out of distribution) of the recording's features at it with the active model;
#: None when the features refuse that speed (too few revolutions or samples per revolution)
Judge = Callable[[float], "tuple[float, bool] | None"]


@dataclass(frozen=True)
class SpeedChoice:
    """What :func:`choose_speed` tried: the estimate and its OOD score, each other reading (r/min) with its OOD score
    (``inf``: the features refused that speed) and whether it was out of distribution, and the reading chosen
    (None: the estimate is kept) with its OOD score."""

    estimate_rpm: float
    estimate_ood_score: float
    tried: tuple[tuple[float, float, bool], ...]
    chosen_rpm: float | None
    chosen_ood_score: float | None = None


def choose_speed(recording: Recording, fr: FeatureResult, ood_score: float, ood: bool,
                 judge: Judge) -> SpeedChoice | None:
    """The reading of the speed the model finds in distribution (see the module docstring).

    Parameters
    ----------
    recording : features.Recording
    fr : features.FeatureResult
        ``extract_features(recording)``: the estimate's features.
    ood_score, ood
        The model's OOD score of ``fr`` and whether it is out of distribution (OOD score above 1 or a feature
        outside the training range).
    judge : callable
        A speed to the (OOD score, out of distribution) of the features at it, or None (:data:`Judge`).

    Returns
    -------
    SpeedChoice or None
        None when the estimate is not in doubt or in distribution (nothing is tried); else what was tried, with
        ``chosen_rpm`` None when no reading was better.
    """
    if not (fr.speed_source == "estimated" and ood and any(speed_in_doubt(w) for w in fr.warnings)):
        return None
    tried: list[tuple[float, float, bool]] = []
    best: tuple[float, float] | None = None
    for rpm in speed_alternatives_rpm(recording, fr.speed_rpm):
        judged = judge(rpm)
        if judged is None:
            tried.append((rpm, float("inf"), True))
            continue
        score, out = float(judged[0]), bool(judged[1])
        tried.append((rpm, score, out))
        if out or not score <= ood_score - SPEED_CHOICE_MIN_OOD_GAIN:
            continue
        if best is None or score < best[1]:
            best = (rpm, score)
    return SpeedChoice(float(fr.speed_rpm), float(ood_score), tuple(tried),
                       None if best is None else best[0], None if best is None else best[1])


def chosen_speed_notes(fr: FeatureResult, choice: SpeedChoice) -> list[Note]:
    """The speed notes of the chosen reading: ``speed_chosen_by_model`` and, for each of the estimate's own doubts,
    ``speed_doubt_at_estimate`` (``fr``: the estimate's features)."""
    note = Note("speed_chosen_by_model", speed_rpm=choice.chosen_rpm, estimate_rpm=fr.speed_rpm,
                estimate_ood=choice.estimate_ood_score, n_tried=len(choice.tried), chosen_ood=choice.chosen_ood_score)
    return [note, *(Note("speed_doubt_at_estimate", estimate_rpm=fr.speed_rpm, note=w)
                    for w in fr.warnings if speed_in_doubt(w))]
