"""A recording to a verdict, in one function: :func:`diagnose_recording`.

Every door (``POST /diagnose``, the web page, ``rotordiag diagnose``, the benchmarks, the robustness report) calls
it with the active model (``models.predict.load_bundle``), so that the verdict, its speed and the features it was
computed from agree wherever a recording is diagnosed. Its body shows the stages in order — read, features and
sanity (once per speed hypothesis, :func:`read_features`), model scores, checks, assess status, verdict — each done
by its own module; the page
that walks through them is docs/pipeline.md. :func:`diagnose` is the same pipeline from features already extracted
(no recording: the checks that read the recording again find nothing).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from functools import partial
from typing import Any

import numpy as np

from rotordiag.features import FeatureResult, Recording, extract_features, with_sanity, with_speed_notes

from .checks import Check, CheckContext
from .checks.acquisitions import acquisitions_check
from .checks.attitude import attitude_check
from .checks.bearing_sets import bearing_set_check
from .checks.clearance_check import clearance_check
from .checks.common_mode import remove_pickup
from .checks.contradiction import contradiction_check
from .checks.family import family_check
from .checks.numbering import numbering_check
from .checks.one_position import one_position_check
from .checks.reverse_2x import reverse_2x_check
from .checks.speed_choice import choose_speed, chosen_speed_notes
from .families import answered_by, machine_family, training_families
from .predict import (
    ModelBundle,
    ModelScores,
    Verdict,
    model_scores,
    ood_score_and_class,
    predictor_threads,
    verdict_of,
)
from .status import DEFAULT_POLICY, ModelCall, Reason, RecordingChecks, assess, consistent_estimate, policy_of

__all__ = ["diagnose_recording", "diagnose", "read_features", "SCORE_CHECKS", "DOUBT_CHECKS"]

#: the checks read beside the model's scores of the features the verdict is given at, in the order the answer lists
#: their reasons (the probe set's first; the doubts below come right after it)
SCORE_CHECKS: tuple[Check, ...] = (acquisitions_check, reverse_2x_check, numbering_check, family_check,
                                   contradiction_check)
#: the checks that read the recording again, given the status found without them (``CheckContext.status``)
DOUBT_CHECKS: tuple[Check, ...] = (clearance_check, attitude_check)


def diagnose_recording(bundle: Any, recording: Recording | None, *, clearance_um: float | None = None,
                       top_k: int = 5, fr: FeatureResult | None = None, plant_model: str | None = None,
                       plant_shaftline: dict[str, Any] | None = None,
                       declared_by: str | None = None) -> tuple[Verdict, FeatureResult]:
    """The verdict of one recording with the active model, and the features it was given from.

    Parameters
    ----------
    bundle : models.predict.ModelBundle or fitted MisalignmentModel
    recording : features.Recording or None
        The recording, read by a reader (``features.reader``, ``service.parsing``). None with ``fr``: the verdict
        of given features (no speed choice, no doubt that reads the recording again).
    clearance_um : float, optional
        Radial bearing clearance c (µm): gives the offset δ = Δ·c. Defaults to the features' ``clearance_um``.
    top_k : int
        Number of contributing features reported.
    fr : features.FeatureResult, optional
        The recording's features when the caller has them already (extracted at the recording's own speed).
    plant_model, plant_shaftline : optional
        The machine's plant model, when known (the asset's or the request's): ``default``, a preset's name
        (``train:NAME``: its finite-element train), or shaft-line tables (``models.families.machine_family``). A
        family the model's card does not list among its training families makes the verdict uncertain at most
        (``family_untrained``, ``models.checks.family``).
    declared_by : str, optional
        Who declared the plant model (``models.families.DECLARED_BY``: ``asset``, ``request``, ``command line``),
        for the verdict's ``answered_by``.

    Returns
    -------
    verdict, feature_result

    Raises
    ------
    ValueError
        With a message for the user: a recording the features refuse (``features.extract_features``), features
        none of which the model reads, a clearance that is not a positive number, a plant model that is not
        ``default``, a preset or readable shaft-line tables.
    """
    model = bundle.model if isinstance(bundle, ModelBundle) else bundle
    policy = policy_of(bundle.card) if isinstance(bundle, ModelBundle) else DEFAULT_POLICY
    family = machine_family(plant_model, plant_shaftline)
    card = bundle.card if isinstance(bundle, ModelBundle) else None
    families = training_families(card)
    answer = answered_by(bundle.version if isinstance(bundle, ModelBundle) else None, card, family, declared_by)
    with predictor_threads(model):
        # 1. read: the caller's reader made ``recording`` (units to µm, probes, bearings, keyphasor, clearance)
        # 2. features and 3. sanity, once per speed hypothesis (None: the recording's own reading of its speed):
        #    :func:`read_features`; given features (``fr``) come with their sanity findings
        features: dict[float | None, FeatureResult] = {} if fr is None else {None: fr}

        def features_at(rpm: float | None) -> FeatureResult:
            if rpm not in features:
                assert recording is not None
                features[rpm] = read_features(recording, rpm)
            return features[rpm]

        fr = features_at(None)
        if clearance_um is None:
            clearance_um = getattr(fr, "clearance_um", None)
        if clearance_um is not None and not (np.isfinite(clearance_um) and clearance_um > 0):
            raise ValueError(f"clearance_um: must be a positive number of micrometres, got {clearance_um!r}")
        # 4. model scores, once per speed hypothesis
        scored: dict[float | None, ModelScores] = {}

        def scores_at(rpm: float | None) -> ModelScores:
            if rpm not in scored:
                scored[rpm] = model_scores(bundle, features_at(rpm))
            return scored[rpm]

        def judge(rpm: float) -> tuple[float, bool] | None:
            try:
                features_at(rpm)
            except ValueError:                  # too few revolutions or samples per revolution at that speed
                return None
            at = scores_at(rpm)
            return at.ood_score, at.ood

        # 5. checks — the speed: a doubtful estimate out of distribution judged at the other speeds it allows
        scores = scores_at(None)
        speed = choose_speed(recording, fr, scores.ood_score, scores.ood, judge) if recording is not None else None
        if speed is not None and speed.chosen_rpm is not None:
            notes = chosen_speed_notes(fr, speed)
            chosen = features_at(speed.chosen_rpm)
            noted = with_speed_notes(chosen, notes)      # the chosen reading with its speed notes, not extracted again
            if noted is not None:               # its scores: the row is the same, the leading warnings changed
                fr, at = noted, scores_at(speed.chosen_rpm)
                scores = replace(at, warnings=[*noted.warnings, *at.warnings[len(chosen.warnings):]])
            elif recording is not None and recording.keyphasor_takes is not None:
                # read by take: each take reads its speed from its own keyphasor (``extract_by_take`` takes no
                # estimate and no notes), so the reading made is the one at the chosen speed
                fr, scores = chosen, scores_at(speed.chosen_rpm)
            else:                               # not a reading with its own speed notes: extracted with them
                assert recording is not None
                fr = read_features(recording, speed.chosen_rpm, notes)
                scores = model_scores(bundle, fr)
        #    — a 1X / 2X common to every probe (electrical pickup) is removed, and the rest read at the same speed
        pickup = remove_pickup(recording, fr, read_features) if recording is not None else None
        removed: list[Reason] = []
        if pickup is not None:
            call_as_sent = scores.call
            recording, fr = pickup.recording, pickup.fr
            scores = model_scores(bundle, fr)
            removed = [pickup.reason(call_as_sent, scores.call)]
        #    — beside the scores: the probe set, separate acquisitions, a reverse coupling 2X, the numbering
        ctx = CheckContext(fr=fr, names=scores.names, row=scores.row, call=scores.call,
                           aligned_band=str(model.bands_.names[0]), ood_score=scores.ood_score, ood=scores.ood,
                           classes_of=scores.classes_of, ood_of=scores.ood_of, score=partial(ood_score_and_class, bundle),
                           band_names=[str(c) for c in model.classes_], plan=scores.plan, recording=recording,
                           machine_family=family, model_families=families,
                           envelope_of=getattr(model, "envelope_findings", None))
        probe_set = bearing_set_check(ctx)
        beside = removed + [r for check in SCORE_CHECKS for r in check(ctx)]
        # 6. assess status: every reason together, by the decision policy stored with the model
        call = _model_call(scores, one_position_check(ctx))
        status, reasons = assess(_recording_checks(scores, fr, probe_set + beside), call, policy)
        #    — the doubts that read the recording again, given that status; assessed again when one is found
        doubts = [r for check in DOUBT_CHECKS for r in check(replace(ctx, status=status))]
        if doubts:
            status, reasons = assess(_recording_checks(scores, fr, probe_set + doubts + beside), call, policy)
        # 7. the verdict
        verdict = verdict_of(scores, fr, status, reasons, clearance_um=clearance_um, top_k=top_k)
        verdict.answered_by = answer
        return verdict, fr


def read_features(recording: Recording, speed_rpm: float | None = None,
                  speed_notes: Sequence[str] = ()) -> FeatureResult:
    """Stages 2 and 3 of one speed hypothesis: the recording's features (``features.extract_features`` at
    ``speed_rpm``, None: its own reading of its speed, with ``speed_notes``), then its physics sanity findings
    (``features.with_sanity``: flat / clipped channels, orbit against clearance, whirl, no sync line, a common
    mode) in ``FeatureResult.sanity``.

    The sanity checks read the features as well as the samples, so they run right after each extraction, once per
    reading; a failed one makes the verdict ``inconclusive`` in ``models.status.assess``. Raises ValueError
    (a message for the user) for a recording the features refuse.
    """
    features = extract_features(recording, speed_estimate_rpm=speed_rpm, speed_notes=speed_notes, sanity=False)
    return with_sanity(recording, features)


def diagnose(bundle: Any, feature_result: FeatureResult, *, clearance_um: float | None = None,
             top_k: int = 5) -> Verdict:
    """The verdict of features already extracted: :func:`diagnose_recording` without a recording (no speed choice,
    no doubt that reads the recording again)."""
    return diagnose_recording(bundle, None, clearance_um=clearance_um, top_k=top_k, fr=feature_result)[0]


def _recording_checks(scores: ModelScores, fr: FeatureResult, extra: Sequence[Reason]) -> RecordingChecks:
    return RecordingChecks(names=scores.names, row=scores.row,
                           feature_median=np.asarray(scores.model.feature_median_, dtype=float),
                           sanity=scores.sanity, ood_score=scores.ood_score, never_missing=scores.never_missing,
                           speed_source=getattr(fr, "speed_source", None), warnings=scores.warnings,
                           envelope=scores.findings, extra=extra,
                           attitude_reference_deg=_attitude_reference(scores.model, scores.row))


def _attitude_reference(model: Any, row: np.ndarray) -> np.ndarray | None:
    """Where the training journals nearest this recording sat (``MisalignmentModel.attitude_reference_deg``; the
    overall median of a model without it; None: a model saved before either)."""
    if hasattr(model, "attitude_reference_deg"):
        return model.attitude_reference_deg(row)
    return getattr(model, "attitude_offset_reference_deg_", None)


def _model_call(scores: ModelScores, static_offset: Sequence[Reason]) -> ModelCall:
    model = scores.model
    bands = model.bands_
    _, _, agree = consistent_estimate(scores.band, bands.edges, scores.point, scores.interval)
    return ModelCall(probabilities=scores.probabilities, class_delta_agree=agree, call_index=scores.call_index,
                     band_names=[str(c) for c in model.classes_], misaligned_call=scores.band > 0,
                     alarm=scores.alarm(), delta_interval=scores.interval, band_edges=bands.edges,
                     interval_level=1.0 - float(model.regressor_.alpha),
                     static_offset=static_offset)

