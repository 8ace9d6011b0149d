"""A doubtful estimated speed judged by the machine family the model knows (issue 15, item 6).

Without a keyphasor or a given speed, the running speed is read from the spectrum
(``features.extract_features``). In whirl, whip and period-n motion that reading can be wrong — a
whirl partner, a 2X or a sub-harmonic read as the 1X — and the estimator then says it is in doubt
(``features.speed_in_doubt``); the features computed at a wrong speed describe no machine the model
was trained on, and the verdict is out of distribution (``Verdict.ood``).

A vibration analyst in that place tries the other speeds the spectrum allows and keeps the one at
which the machine makes sense. :func:`choose_speed` (called by ``models.diagnosis.diagnose_recording``) does
the same with the model's own yardstick: when the estimate is in doubt **and** its verdict is out of distribution, each of
``features.speed_alternatives_rpm`` is tried, and the verdict is given at the one whose recording is
in distribution with the lowest OOD score, when that score is at least ``SPEED_CHOICE_MIN_OOD_GAIN``
below the estimate's. The verdict stays ``uncertain`` (the ``speed_ambiguous`` reason: the speed rests
on the model's judgement, not on the signal) and says which speed it used, which was estimated and why.
Nothing changes for a recording whose estimated speed is not in doubt, or whose verdict at it is in
distribution, or for a machine unlike the training data at every speed (all readings out of
distribution: it keeps the estimate and its OOD verdict).

Measured on docs/robustness.md's base sets (speed unknown, 48 revolutions): docs/features.md,
"Eighth pass".
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rotordiag.features import (
    FeatureResult,
    Note,
    Recording,
    extract_features,
    speed_alternatives_rpm,
    speed_in_doubt,
    with_speed_notes,
)

from .predict import Verdict, diagnose

__all__ = ["SPEED_CHOICE_MIN_OOD_GAIN", "SpeedChoice", "choose_speed"]

#: a reading replaces the estimate only when its OOD score is this much lower (and it is in distribution):
#: a smaller gain is no evidence (chosen on the robustness base sets of seeds 815–818; docs/features.md)
SPEED_CHOICE_MIN_OOD_GAIN = 0.15


@dataclass(frozen=True)
class SpeedChoice:
    """What :func:`choose_speed` tried: the estimate and its verdict's OOD score, each other reading (r/min)
    with its OOD score (``inf``: the features refused that speed) and whether it was out of distribution, and
    the reading chosen (None: the estimate was kept)."""

    estimate_rpm: float
    estimate_ood_score: float
    tried: tuple[tuple[float, float, bool], ...]
    chosen_rpm: float | None


def _worth_a_second_look(fr: FeatureResult, verdict: Verdict) -> bool:
    return (fr.speed_source == "estimated" and bool(verdict.ood)
            and any(speed_in_doubt(w) for w in fr.warnings))


def choose_speed(bundle: Any, recording: Recording, fr: FeatureResult, verdict: Verdict, *,
                 clearance_um: float | None = None, top_k: int = 5
                 ) -> tuple[Verdict, FeatureResult, SpeedChoice | None]:
    """The verdict at the reading of the speed the model finds in distribution (see the module docstring).

    Parameters
    ----------
    bundle : models.predict.ModelBundle or fitted MisalignmentModel
    recording : features.Recording
    fr, verdict
        ``extract_features(recording)`` and ``diagnose(bundle, fr, ...)``.
    clearance_um, top_k
        As :func:`models.predict.diagnose`.

    Returns
    -------
    verdict, feature_result, choice
        Unchanged, with ``choice`` None, when the estimate is not in doubt or its verdict is in
        distribution; else the chosen reading's (``choice.chosen_rpm`` None when none was better).
    """
    if not _worth_a_second_look(fr, verdict):
        return verdict, fr, None
    tried: list[tuple[float, float, bool]] = []
    best: tuple[float, FeatureResult, Verdict] | None = None
    for rpm in speed_alternatives_rpm(recording, fr.speed_rpm):
        try:
            fr_c = extract_features(recording, speed_estimate_rpm=rpm)
        except ValueError:              # too few revolutions or samples per revolution at that speed
            tried.append((rpm, float("inf"), True))
            continue
        v_c = diagnose(bundle, fr_c, clearance_um=clearance_um, top_k=0)
        tried.append((rpm, float(v_c.ood_score), bool(v_c.ood)))
        if v_c.ood or not v_c.ood_score <= verdict.ood_score - SPEED_CHOICE_MIN_OOD_GAIN:
            continue
        if best is None or v_c.ood_score < best[2].ood_score:
            best = (rpm, fr_c, v_c)
    choice = SpeedChoice(float(fr.speed_rpm), float(verdict.ood_score), tuple(tried),
                         None if best is None else best[0])
    if best is None:
        return verdict, fr, choice
    rpm, fr_c, v_c = best
    note = Note("speed_chosen_by_model", speed_rpm=rpm, estimate_rpm=fr.speed_rpm, estimate_ood=verdict.ood_score,
                n_tried=len(tried), chosen_ood=v_c.ood_score)
    estimator = [Note("speed_doubt_at_estimate", estimate_rpm=fr.speed_rpm, note=w)
                 for w in fr.warnings if speed_in_doubt(w)]
    noted = with_speed_notes(fr_c, [note, *estimator])      # the chosen reading's features, its notes changed
    fr_c = noted if noted is not None else extract_features(recording, speed_estimate_rpm=rpm,
                                                            speed_notes=[note, *estimator])
    return diagnose(bundle, fr_c, clearance_um=clearance_um, top_k=top_k), fr_c, choice
