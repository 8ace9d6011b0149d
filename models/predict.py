"""The model's side of a verdict: the loaded model, its scores of one feature result, and the verdict made of them.

``load_bundle`` (a registry's model and card), :func:`model_scores` (the "model scores" stage of
``models.pipeline``: band probabilities, Δ and its conformal interval, kNN OOD score, features outside the training
range), :func:`verdict_of` (a :class:`Verdict` from the scores and the assessed status), :func:`format_verdict`
(the CLI's text). The verdict of a recording is ``models.pipeline.diagnose_recording``.
"""
from __future__ import annotations

import copy
import logging
import weakref
from collections.abc import Sequence
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass, field, fields, is_dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from threadpoolctl import threadpool_limits

from rotordiag.core.notes import Measured, Note
from rotordiag.features import evidence

from .checks.backward_whirl import answer_reverse_whirl
from .checks.bearing_sets import bearing_plan, leave_out_bearings
from .direction import direction_answer
from .registry import Registry
from .status import INCONCLUSIVE, Reason, consistent_estimate

if TYPE_CHECKING:
    from .compiled import CompiledModel
    from .estimators import MisalignmentModel


@dataclass(frozen=True)
class ModelBundle:
    """A loaded model with its card (what ``models.pipeline.diagnose_recording`` needs)."""

    model: Any                 # fitted models.estimators.MisalignmentModel
    card: dict
    version: str | None = None


def load_bundle(registry_root: str | Path, version: str | None = None) -> ModelBundle:
    """Load ``version`` (default: the active one) of the registry at ``registry_root``.

    Raises
    ------
    models.registry.RegistryError
        No active model, unknown version, or a file that is not trusted.
    """
    model, card = Registry(registry_root).load(version)
    return ModelBundle(model=model, card=card, version=card.get("version"))


@dataclass
class FeatureContribution:
    """How much one feature moved the verdict.

    ``contribution`` is the drop in the probability of the predicted band when this
    feature alone is replaced by its training median (occlusion); positive values
    pushed toward the verdict.
    """

    name: str
    value: float | None
    reference: float
    contribution: float


@dataclass
class Verdict:
    """The diagnosis of one recording (JSON-able with :meth:`to_dict`).

    ``status`` is ``confident``, ``uncertain`` or ``inconclusive`` (:mod:`models.status`),
    ``reasons`` say why. An ``inconclusive`` verdict has ``severity == "inconclusive"`` and no
    Δ / offset (``None``); its probabilities stay available. ``severity`` is the calibrated
    classifier's class; ``misalignment`` is the Δ regressor's estimate clipped into that
    class's band (``misalignment_model`` unclipped), so the two always agree. ``evidence`` is
    model-independent (``features.evidence``). ``ood`` is true when the OOD score is above 1 or a
    feature lies outside the training range (``ood_findings``, from ``MisalignmentModel.envelope_findings``).
    ``direction`` and ``angular_offset`` (``models.direction.direction_answer``): which way the exciter sits and
    the angular offset α, each with 90 % intervals, or ``estimated: false`` with the reason (a model trained without
    direction labels, a recording without DC positions, an aligned or inconclusive verdict).
    """

    severity: str
    probabilities: dict[str, float]
    misalignment: float | None
    misalignment_interval: tuple[float | None, float | None]
    interval_level: float
    offset_um: float | None
    offset_interval_um: tuple[float, float] | None
    motion_type: str | None
    top_features: list[FeatureContribution]
    ood: bool
    ood_score: float
    speed_rpm: float | None
    model_version: str | None
    bands: dict
    warnings: list[str] = field(default_factory=list)
    status: str = "confident"
    reasons: list[dict] = field(default_factory=list)
    evidence: list[dict] = field(default_factory=list)
    misalignment_model: float | None = None
    ood_findings: list[dict] = field(default_factory=list)
    model_severity: str | None = None
    speed_source: str | None = None
    #: which model answered (version, training families, the plant it was retrained for) and which plant model the
    #: recording was judged as, who declared it (``models.families.answered_by``); None when not made by the pipeline
    answered_by: dict | None = None
    direction: dict | None = None
    angular_offset: dict | None = None

    def to_dict(self) -> dict:
        """The verdict as JSON-able data (as :func:`dataclasses.asdict`, 4× faster), with ``warning_codes``: the
        catalogue code of each warning (``rotordiag.core.notes``), in the order of ``warnings``.

        Raises
        ------
        TypeError
            For a warning that is not a catalogue :class:`~rotordiag.core.notes.Note` (a programming error: every
            warning a verdict is given is one).
        """
        d = {f.name: _copied(getattr(self, f.name)) for f in fields(self)}
        d["misalignment_interval"] = list(self.misalignment_interval)
        if self.offset_interval_um is not None:
            d["offset_interval_um"] = list(self.offset_interval_um)
        d["warning_codes"] = [_code(w) for w in self.warnings]
        return d


def _code(warning: object) -> str:
    if not isinstance(warning, Note):
        raise TypeError(f"a verdict's warnings are catalogue notes (rotordiag.core.notes.Note), not {warning!r}")
    return warning.code


def _copied(v: Any) -> Any:
    """A deep copy of a verdict field as :func:`dataclasses.asdict` makes it (dataclasses to dicts, containers
    copied with their types), for the few types a verdict holds. Strings are values: a warning (``Note``) or a
    measured text (``Measured``), ``str`` subclasses with their typed values, is kept as it is, not rebuilt."""
    t = type(v)
    if t is float or t is str or t is int or t is bool or v is None or isinstance(v, str):
        return v
    if t is list:
        return [_copied(x) for x in v]
    if t is dict:
        return {_copied(k): _copied(x) for k, x in v.items()}
    if t is tuple:
        return tuple(_copied(x) for x in v)
    if is_dataclass(v) and not isinstance(v, type):
        return {f.name: _copied(getattr(v, f.name)) for f in fields(v)}
    return copy.deepcopy(v)


def feature_vector(names: Sequence[str], feature_result) -> tuple[np.ndarray, list[str]]:
    """Order a feature result's values as the model's ``names``; missing names → NaN.

    ``feature_result`` needs ``names`` and ``values`` (a ``features.FeatureResult``).
    Returns the row and the list of model features the result did not provide.
    """
    values = np.asarray(feature_result.values, dtype=float)
    have, cols, missing = _columns_of(tuple(names), tuple(feature_result.names), len(values))
    row = np.full(len(have), np.nan)
    row[have] = values[cols]
    return row, list(missing)


@lru_cache(maxsize=16)
def _columns_of(names: tuple[str, ...], given: tuple[str, ...], n_values: int
                ) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Where each of the model's ``names`` is among a feature result's ``given`` names (the first ``n_values`` of them;
    a repeated name: its last place): the mask of those found, their columns, the names not found. Made once per
    pair of name lists (every recording of one extractor has the same)."""
    index = {n: i for i, n in enumerate(given[:n_values])}
    have = np.array([n in index for n in names], dtype=bool)
    cols = np.array([index[n] for n in names if n in index], dtype=np.intp)
    return have, cols, tuple(n for n in names if n not in index)


def _motion_type(feature_result) -> str | None:
    mt = getattr(feature_result, "motion_type", None)
    if mt is None:
        return None
    kind = getattr(mt, "kind", None)
    if kind is not None:
        period = getattr(mt, "period", None)
        if str(kind) == "period-n" and period:
            return f"period-{int(period)}"
        return str(kind)
    return str(mt)


_COMPILED: weakref.WeakKeyDictionary[Any, Any] = weakref.WeakKeyDictionary()


def fast_predictor(model: MisalignmentModel) -> CompiledModel | MisalignmentModel:
    """The model's :class:`models.compiled.CompiledModel` (built once per model object), or
    the model itself when it cannot be compiled (same ``predict_proba``,
    ``predict_misalignment``, ``ood_ratio`` methods and results either way)."""
    try:
        return _COMPILED[model]
    except (KeyError, TypeError):
        pass
    from .compiled import CompiledModel

    try:
        fast = CompiledModel(model)
    except (TypeError, AttributeError, KeyError, ValueError) as exc:
        # e.g. a model whose parts are not HistGradientBoosting: the plain (slower) path
        logging.getLogger("rotordiag.models").warning(
            "model not compiled for fast verdicts (%s: %s); using scikit-learn's predict methods",
            type(exc).__name__, exc)
        fast = model
    try:
        _COMPILED[model] = fast
    except TypeError:
        pass
    return fast


def _contributions(model, fast, row: np.ndarray, cls: int, top_k: int) -> list[FeatureContribution]:
    names = model.feature_names_
    ref = model.feature_median_
    if hasattr(fast, "occlusion_proba"):
        base_p, occluded = fast.occlusion_proba(row)
        drops = base_p[cls] - occluded[:, cls]
    else:
        trial = np.repeat(row[None, :], len(names), axis=0)
        trial[np.arange(len(names)), np.arange(len(names))] = ref
        cols = getattr(model, "clearance_columns_", None)
        if cols is not None and not model.clearance_stated(row[None, :])[0]:
            # the row's own case answers every occluded copy (as the compiled path): a clearance
            # feature given a median value would move the copy to the other case's classifier
            trial[:, cols] = np.nan
        base = model.predict_proba(row[None, :])[0, cls]
        drops = base - model.predict_proba(trial)[:, cls]
    order = np.argsort(-np.abs(drops), kind="stable")[:top_k]
    return [
        FeatureContribution(
            name=names[j],
            value=None if not np.isfinite(row[j]) else float(row[j]),
            reference=float(ref[j]),
            contribution=float(drops[j]),
        )
        for j in order
    ]


def predictor_threads(model: Any) -> AbstractContextManager:
    """The thread limit a verdict's model calls run under: none for a compiled model (:func:`fast_predictor`), one
    OpenMP thread for a model run through scikit-learn — for a single row that is the fastest, and the boosted
    trees' thread pool spins badly when the machine's cores are busy (measured: ~1 s per verdict on 2
    oversubscribed cores)."""
    if fast_predictor(model) is not model:
        return nullcontext()
    return threadpool_limits(limits=1, user_api="openmp")


def _alarm(model, proba: np.ndarray, cls: int, X: np.ndarray) -> tuple[float, float] | None:
    """(P(misaligned), its threshold) when an ordinal model calls the machine aligned, else None;
    the threshold is that of the classifier of the row's clearance case."""
    if cls != 0 or not getattr(model, "ordinal_", False):
        return None
    heads = getattr(model, "heads", None)
    clf = heads(bool(model.clearance_stated(X)[0]))[0] if heads is not None else model.classifier_
    thresholds = getattr(clf, "thresholds_", None)
    if thresholds is None:
        return None
    return float(1.0 - proba[0]), float(thresholds[0])


@dataclass(frozen=True)
class _ModelRow:
    """A feature result as the model reads it: its row over the model's features, the bearings it answers from."""

    model: Any
    version: str | None
    names: Sequence[str]
    row: np.ndarray
    missing: list[str]
    warnings: list[str]
    plan: Any
    sanity: tuple


def _model_row(bundle, feature_result) -> _ModelRow:
    """The model's feature row of ``feature_result``, with the bearings outside the answering probe set left out
    (models.checks.bearing_sets), and the warnings that go with it."""
    if isinstance(bundle, ModelBundle):
        model, version = bundle.model, bundle.version
    else:
        model, version = bundle, None
    names = model.feature_names_
    row, missing = feature_vector(names, feature_result)
    warnings = list(getattr(feature_result, "warnings", None) or ())       # Notes: code, typed values, text
    if len(missing) == len(names):
        raise ValueError(
            "feature_result: none of the model's features are present; "
            "the features were made by a different feature extractor than the model was trained on"
        )
    if missing:
        warnings.append(Note("model_features_not_produced", n_missing=len(missing),
                             examples=f"{missing[:5]}{' …' if len(missing) > 5 else ''}"))
    # the probe set the model reads (models.checks.bearing_sets): the other bearings' features left out
    # a backward 1X at one bearing that the nearest training machines share is theirs, not a probe mistake
    sanity, as_trained = answer_reverse_whirl(model, names, row, tuple(getattr(feature_result, "sanity", ()) or ()))
    warnings += as_trained
    plan = (bearing_plan(bundle, feature_result.bearings,
                         suspect=[f.bearing for f in sanity if f.code == "reverse_whirl" and f.bearing is not None])
            if getattr(feature_result, "bearings", None) else None)
    if plan is not None:
        if plan.answering is not None and plan.left_out:
            row = leave_out_bearings(names, row, plan.answering)
        warnings += plan.warnings()
    return _ModelRow(model, version, names, row, missing, warnings, plan, sanity)


def ood_score_and_class(bundle: ModelBundle | Any, feature_result) -> tuple[float, str]:
    """The kNN OOD score and the classifier's class of a feature result, as :func:`model_scores` computes them, and
    nothing else: for a second reading of a recording (``models.checks.clearance_check``,
    ``models.checks.common_mode``) at a fraction of a verdict's cost.
    """
    m = _model_row(bundle, feature_result)
    X = m.row[None, :]
    fast = fast_predictor(m.model)
    with predictor_threads(m.model):
        cls = int(m.model.band_index(fast.predict_proba(X), X)[0])
        return float(fast.ood_ratio(X)[0]), str(m.model.classes_[cls])


@dataclass(frozen=True)
class ModelScores:
    """The active model's reading of one feature result: the "model scores" stage of ``models.pipeline``.

    Attributes
    ----------
    model, fast, version
        The fitted model, its compiled predictor (:func:`fast_predictor`) and its registry version.
    names, row
        The model's feature names and the row (bearings outside the answering probe set left out).
    missing, never_missing
        The model's features the extractor did not produce; those missing here that training always had.
    warnings : list of rotordiag.core.notes.Note
        The feature result's warnings and the model side's (features not produced or missing, probe set, OOD).
    plan : models.checks.bearing_sets.BearingPlan or None
    sanity : tuple of features.SanityFinding
    probabilities : ndarray
        Calibrated band probabilities; ``call_index`` the called band's index into them (``call`` its name).
    point, interval
        The Δ regressor's own estimate and conformal interval.
    ood_score, findings, ood
        kNN OOD score, features outside the training range (``MisalignmentModel.envelope_findings``), and
        whether either puts the row out of distribution.
    """

    model: Any
    fast: Any
    version: str | None
    names: Sequence[str]
    row: np.ndarray
    missing: list[str]
    never_missing: list[str]
    warnings: list
    plan: Any
    sanity: tuple
    probabilities: np.ndarray
    call_index: int
    point: float
    interval: tuple[float, float]
    ood_score: float
    findings: list[dict]

    @property
    def ood(self) -> bool:
        return self.ood_score > 1.0 or bool(self.findings)

    @property
    def call(self) -> str:
        return str(self.model.classes_[self.call_index])

    @property
    def band(self) -> int:
        """The call's index into the model's severity bands."""
        bands = self.model.bands_
        return list(bands.names).index(self.call) if self.call in bands.names else self.call_index

    def classes_of(self, rows: np.ndarray) -> list[str]:
        """The classifier's class name of each of ``rows`` (n, n_features)."""
        return [str(self.model.classes_[k]) for k in self.model.band_index(self.fast.predict_proba(rows), rows)]

    def ood_of(self, rows: np.ndarray) -> np.ndarray:
        """The kNN OOD score of each of ``rows``."""
        return self.fast.ood_ratio(rows)

    def alarm(self) -> tuple[float, float] | None:
        """P(misaligned) and the ordinal classifier's false-alarm threshold for an "aligned" call, else None."""
        return _alarm(self.model, self.probabilities, self.call_index, self.row[None, :])


def model_scores(bundle: ModelBundle | Any, feature_result) -> ModelScores:
    """The model's reading of ``feature_result`` (:class:`ModelScores`); the caller holds
    :func:`predictor_threads`.

    Raises
    ------
    ValueError
        When none of the model's features are present (features of another extractor).
    """
    m = _model_row(bundle, feature_result)
    model, row, warnings = m.model, m.row, m.warnings
    never = (~np.isfinite(row)) & (model.feature_nan_rate_ == 0)
    never_missing = [n for n, flag in zip(m.names, never) if flag and n not in m.missing]
    if never_missing:
        warnings.append(Note("features_never_missing", n_missing=len(never_missing), examples=str(never_missing[:3])))
    X = row[None, :]
    fast = fast_predictor(model)
    proba = fast.predict_proba(X)[0]
    cls = int(model.band_index(proba, X)[0])
    point, interval = fast.predict_misalignment(X)
    ood_score = float(fast.ood_ratio(X)[0])
    findings = model.envelope_findings(X)[0] if hasattr(model, "envelope_findings") else []
    if ood_score > 1.0:
        warnings.append(Note("signal_unlike_training", ood_score=ood_score))
    if findings:
        warnings.append(Note("features_outside_training", n_outside=len(findings),
                             examples=f"{', '.join(f['feature'] for f in findings[:5])}"
                                      f"{' …' if len(findings) > 5 else ''}"))
    return ModelScores(model=model, fast=fast, version=m.version, names=m.names, row=row, missing=m.missing,
                       never_missing=never_missing, warnings=warnings, plan=m.plan, sanity=m.sanity,
                       probabilities=proba, call_index=cls, point=float(point[0]),
                       interval=(float(interval[0, 0]), float(interval[0, 1])), ood_score=ood_score,
                       findings=findings)


def verdict_of(scores: ModelScores, feature_result, status: str, reasons: Sequence[Reason], *,
               clearance_um: float | None, top_k: int) -> Verdict:
    """The :class:`Verdict` of a feature result from its model scores and its assessed status and reasons: the
    class and Δ made consistent (``models.status.consistent_estimate``), no severity nor Δ when inconclusive, the
    offset δ = Δ·c when the clearance is known, the occlusion contributions of the ``top_k`` features and the
    model-independent evidence."""
    model = scores.model
    bands = model.bands_
    raw = scores.point
    delta, (lo, hi), _ = consistent_estimate(scores.band, bands.edges, raw, scores.interval)
    severity = scores.call
    shown: float | None = delta
    shown_iv: tuple[float | None, float | None] = (lo, hi)
    if status == INCONCLUSIVE:
        severity, shown, shown_iv = INCONCLUSIVE, None, (None, None)
    offset = offset_iv = None
    if clearance_um is not None and shown is not None:
        offset = delta * float(clearance_um)
        offset_iv = (lo * float(clearance_um), hi * float(clearance_um))
    speed = getattr(feature_result, "speed_rpm", None)
    ev = evidence(feature_result) if getattr(feature_result, "bearings", None) else []
    direction, angular = direction_answer(
        getattr(model, "direction_heads_", None), scores.row, aligned_call=scores.band == 0,
        inconclusive=status == INCONCLUSIVE, delta=shown, delta_interval=shown_iv, clearance_um=clearance_um,
        dc_removed=any(getattr(w, "code", None) == "no_dc_position" for w in scores.warnings))
    return Verdict(
        status=status,
        reasons=[r.to_dict() for r in reasons],
        evidence=[e.to_dict() for e in ev],
        misalignment_model=raw,
        model_severity=scores.call,
        speed_source=getattr(feature_result, "speed_source", None),
        severity=severity,
        probabilities={str(n): float(p) for n, p in zip(model.classes_, scores.probabilities)},
        misalignment=shown,
        misalignment_interval=shown_iv,
        interval_level=1.0 - float(model.regressor_.alpha),
        offset_um=offset,
        offset_interval_um=offset_iv,
        motion_type=_motion_type(feature_result),
        top_features=_contributions(model, scores.fast, scores.row, scores.call_index, top_k),
        ood=bool(scores.ood),
        ood_score=scores.ood_score,
        ood_findings=scores.findings,
        speed_rpm=None if speed is None else float(speed),
        model_version=scores.version,
        bands=bands.to_dict(),
        warnings=scores.warnings,
        direction=direction,
        angular_offset=angular,
    )


def _direction_lines(v: Verdict, units: str) -> list[str]:
    """The CLI's lines of the verdict's direction and angular offset (nothing for a verdict made without them)."""
    from .direction import direction_text

    lines = []
    d, a = v.direction, v.angular_offset
    if d is not None:
        lines.append(f"direction: {direction_text(d, units)}" if d.get("estimated")
                     else f"direction: not estimated — {d.get('why_not')}")
    if a is not None:
        if a.get("estimated"):
            lo, hi = a["interval_mrad"]
            lines.append(f"angular offset α: {a['angular_mrad']:+.3f} mrad ({a['interval_level']:.0%} interval "
                         f"{lo:+.3f} – {hi:+.3f} mrad; {a['meaning']})")
        else:
            lines.append(f"angular offset α: not estimated — {a.get('why_not')}")
    return lines


def format_verdict(v: Verdict, output_units: str = "um", *, baseline: dict | None = None) -> str:
    """Human-readable multi-line text of a verdict (for the CLI); every length in ``output_units`` (um | mil):
    the offset, the µm-named features (renamed ``…_mil_pp``, values and ranges converted) and the evidence
    texts, as the API's ``output_units`` (:func:`rotordiag.models.output_units.verdict_in_units`). The first line
    is the headline (:mod:`rotordiag.models.headline`, with the ``baseline`` comparison when there is one); a
    recording whose measurement is in doubt shows no severity."""
    import copy

    from rotordiag.core.units import lengths_in, um_to

    from .headline import headline
    from .output_units import verdict_in_units

    unit = "mil" if output_units.strip().lower().startswith("mil") else "µm"
    unit_key = "mil" if unit == "mil" else "um"
    scale = float(um_to(1.0, "mil" if unit == "mil" else "um"))

    def named(name: str, *values: Any) -> tuple[str, list[Any]]:
        """A feature's name and values in the output units (``b2_1x_major_um_pp`` → ``b2_1x_major_mil_pp``)."""
        ((new, converted),) = lengths_in({name: list(values)}, "mil" if unit == "mil" else "um").items()
        return new, converted

    evidence = verdict_in_units({"evidence": copy.deepcopy(v.evidence)}, output_units)["evidence"]
    head = headline({"status": v.status, "severity": v.severity, "reasons": v.reasons,
                     "motion_type": v.motion_type, "offset_um": v.offset_um}, baseline=baseline, units=unit_key)
    lines = [f"WHAT TO DO: {head.text}  [{head.action.replace('_', ' ')}; urgency: {head.urgency.replace('_', ' ')}]",
             f"status: {v.status}"]
    for r in v.reasons:
        msg = r["message"]
        lines.append(f"  {r['status']}: {msg.render(unit_key) if isinstance(msg, Measured) else msg}")
    if not head.show_severity:
        lines.append("severity: not given (the measurement is in doubt: see the reasons)")
    else:
        lines.append(f"severity: {v.severity}" + ("  (no severity: see the reasons and the evidence)"
                                                  if v.status == INCONCLUSIVE else ""))
    lines.append("probabilities: " + ", ".join(f"{k} {p:.2f}" for k, p in v.probabilities.items()))
    lo, hi = v.misalignment_interval
    if v.misalignment is not None and lo is not None and hi is not None:
        lines.append(
            f"misalignment Δ = δ/c: {v.misalignment:.3f}  ({v.interval_level:.0%} interval {lo:.3f} – {hi:.3f})"
        )
    else:
        lines.append("misalignment Δ = δ/c: not given (inconclusive)")
    if v.offset_um is not None and v.offset_interval_um is not None:
        a, b = v.offset_interval_um
        nd = 2 if unit == "mil" else 1
        lines.append(f"offset δ: {v.offset_um * scale:.{nd}f} {unit}  ({a * scale:.{nd}f} – {b * scale:.{nd}f} {unit})")
    elif v.misalignment is None:
        lines.append("offset δ: not given (inconclusive)")
    else:
        lines.append(f"offset δ: unknown (give the bearing clearance to convert Δ to {unit})")
    lines += _direction_lines(v, unit_key)
    if v.speed_rpm is not None:
        lines.append(f"speed: {v.speed_rpm:.1f} r/min")
    lines.append(f"motion type: {v.motion_type or 'not determined'}")
    lines.append("features that drove the verdict (drop in P(severity) when set to the training median):")
    for f in v.top_features:
        name, (value, reference) = named(f.name, f.value, f.reference)
        val = "missing" if value is None else f"{value:.4g}"
        lines.append(f"  {name:<40s} {val:>10s}  (typical {reference:.4g})  {f.contribution:+.3f}")
    lines.append(f"out-of-distribution score: {v.ood_score:.2f}" + ("  ⚠ OOD" if v.ood else ""))
    for found in v.ood_findings:
        name, (value, lo_, hi_) = named(found["feature"], found["value"], found["train_min"], found["train_max"])
        lines.append(f"  outside the training range: {name} = {value:.4g} (training {lo_:.4g} … {hi_:.4g})")
    if v.model_version:
        lines.append(f"model: {v.model_version}")
    if v.answered_by:
        lines.append(f"answered by: {v.answered_by['text']}")
    for w in v.warnings:
        lines.append(f"warning: {w.render(unit_key) if isinstance(w, Note) else w}")
    if evidence:
        lines.append("evidence (measured, independent of the model):")
        for e in evidence:
            lines.append(f"  {e['scope']:<14s} {e['name']:<24s} {e['value']}")
            lines.append(f"  {'':<14s} {'':<24s} → {e['meaning']}")
    return "\n".join(lines)
