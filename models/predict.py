"""The verdict: one function, used by ``rotordiag diagnose`` and by the service.

``diagnose(bundle, feature_result) -> Verdict``: severity band and calibrated
probabilities, Δ estimate with its conformal interval (and the offset δ = Δ·c in µm
when the bearing clearance is known), motion type, the features that drove the
verdict, and an out-of-distribution warning.
"""
from __future__ import annotations

import copy
import logging
import weakref
from collections.abc import Sequence
from dataclasses import dataclass, field, fields, is_dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from threadpoolctl import threadpool_limits

from rotordiag.core.notes import Measured, Note
from rotordiag.features import evidence

from .checks.acquisitions import acquisitions_reason, coupling_phase_rows, coupling_split
from .checks.bearing_sets import bearing_plan, leave_out_bearings
from .checks.numbering import has_every_bearing, mirrored_row, numbering_reason
from .checks.reverse_2x import reverse_2x_reason
from .registry import Registry
from .status import (
    DEFAULT_POLICY,
    INCONCLUSIVE,
    ModelCall,
    Reason,
    RecordingChecks,
    assess,
    consistent_estimate,
    journals_at_one_position,
    policy_of,
)

if TYPE_CHECKING:
    from .compiled import CompiledModel
    from .estimators import MisalignmentModel


@dataclass(frozen=True)
class ModelBundle:
    """A loaded model with its card (what :func:`diagnose` needs)."""

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

    def to_dict(self) -> dict:
        d = {f.name: _copied(getattr(self, f.name)) for f in fields(self)}     # as dataclasses.asdict, 4× faster
        d["misalignment_interval"] = list(self.misalignment_interval)
        if self.offset_interval_um is not None:
            d["offset_interval_um"] = list(self.offset_interval_um)
        return d


def _copied(v: Any) -> Any:
    """A deep copy of a verdict field as :func:`dataclasses.asdict` makes it (dataclasses to dicts, containers
    copied with their types), for the few types a verdict holds."""
    t = type(v)
    if t is float or t is str or t is int or t is bool or v is None:
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
    got = dict(zip(tuple(feature_result.names), np.asarray(feature_result.values, dtype=float)))
    row = np.array([got.get(n, np.nan) for n in names], dtype=float)
    missing = [n for n in names if n not in got]
    return row, missing


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


def diagnose(
    bundle: ModelBundle | Any,
    feature_result,
    *,
    clearance_um: float | None = None,
    top_k: int = 5,
    extra_reasons: Sequence[Reason] = (),
) -> Verdict:
    """Diagnose one recording from its features.

    Parameters
    ----------
    bundle : ModelBundle or fitted MisalignmentModel
    feature_result : features.FeatureResult
        Anything with ``names`` and ``values``; ``speed_rpm``, ``warnings``,
        ``motion_type`` and ``clearance_um`` are used when present.
    clearance_um : float, optional
        Radial bearing clearance c in µm; gives the offset δ = Δ·c. Defaults to the
        feature result's ``clearance_um`` when it has one.
    top_k : int
        Number of contributing features reported.
    extra_reasons : sequence of models.status.Reason
        Reasons found outside the feature row, by a caller that has the recording
        (``models.checks.common_mode``, ``models.checks.clearance_check``); they count in the status like the others.

    Returns
    -------
    Verdict

    Notes
    -----
    The trees are walked by the compiled predictor (:mod:`models.compiled`; same numbers
    as the scikit-learn methods, about 1 ms instead of about 30 ms per verdict). A model
    it cannot compile runs through scikit-learn with one OpenMP thread: for a single row
    that is the fastest, and the boosted trees' thread pool spins badly when the
    machine's cores are busy (measured: ~1 s per verdict on 2 oversubscribed cores).
    """
    model = bundle.model if isinstance(bundle, ModelBundle) else bundle
    if fast_predictor(model) is not model:
        return _diagnose(bundle, feature_result, clearance_um=clearance_um, top_k=top_k, extra_reasons=extra_reasons)
    with threadpool_limits(limits=1, user_api="openmp"):
        return _diagnose(bundle, feature_result, clearance_um=clearance_um, top_k=top_k, extra_reasons=extra_reasons)


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


def _one_position_call(model, fast, names: Sequence[str], row: np.ndarray) -> int | None:
    """The lowest band the classifier gives ``row`` with the coupling-end journals at one static position
    (``models.status.journals_at_one_position``), or None when their centrelines are not measured."""
    rows = journals_at_one_position(names, row)
    if rows is None:
        return None
    return int(np.min(model.band_index(fast.predict_proba(rows), rows)))


def _numbering_reasons(model, fast, names, row: np.ndarray, ood_score: float, cls: int) -> list:
    """``bearing_numbering`` (models.checks.numbering) for a four-bearing row that is markedly more like the training family
    numbered from the other end: one more OOD and class pass, on the renumbered row."""
    if not has_every_bearing(names, row):
        return []
    X_other = mirrored_row(names, row)[None, :]
    other_cls = int(model.band_index(fast.predict_proba(X_other), X_other)[0])
    reason = numbering_reason(ood_score, float(fast.ood_ratio(X_other)[0]), str(model.classes_[cls]),
                              str(model.classes_[other_cls]))
    return [reason] if reason is not None else []


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
    sanity = tuple(getattr(feature_result, "sanity", ()) or ())
    plan = (bearing_plan(bundle, feature_result.bearings,
                         suspect=[f.bearing for f in sanity if f.code == "reverse_whirl" and f.bearing is not None])
            if getattr(feature_result, "bearings", None) else None)
    if plan is not None:
        if plan.answering is not None and plan.left_out:
            row = leave_out_bearings(names, row, plan.answering)
        warnings += plan.warnings()
    return _ModelRow(model, version, names, row, missing, warnings, plan, sanity)


def ood_score_and_class(bundle: ModelBundle | Any, feature_result) -> tuple[float, str]:
    """The kNN OOD score and the classifier's class of a feature result, as :func:`diagnose` computes them, and
    nothing else: for a second reading of a recording (``models.checks.clearance_check``, ``models.checks.common_mode``) at a
    fraction of a verdict's cost.
    """
    m = _model_row(bundle, feature_result)
    X = m.row[None, :]
    fast = fast_predictor(m.model)

    def score() -> tuple[float, str]:
        cls = int(m.model.band_index(fast.predict_proba(X), X)[0])
        return float(fast.ood_ratio(X)[0]), str(m.model.classes_[cls])

    if fast is not m.model:                 # compiled trees: no thread pool (as diagnose)
        return score()
    with threadpool_limits(limits=1, user_api="openmp"):
        return score()


def _diagnose(bundle, feature_result, *, clearance_um, top_k, extra_reasons: Sequence[Reason] = ()) -> Verdict:
    read = _model_row(bundle, feature_result)
    model, version, names, row, missing = read.model, read.version, read.names, read.row, read.missing
    warnings, plan, sanity = read.warnings, read.plan, read.sanity
    never_missing = (~np.isfinite(row)) & (model.feature_nan_rate_ == 0)
    never_missing_names = [n for n, m in zip(names, never_missing) if m and n not in missing]
    if never_missing_names:
        warnings.append(Note("features_never_missing", n_missing=len(never_missing_names),
                             examples=str(never_missing_names[:3])))
    X = row[None, :]
    fast = fast_predictor(model)
    proba = fast.predict_proba(X)[0]
    cls = int(model.band_index(proba, X)[0])
    point, interval = fast.predict_misalignment(X)
    ood_score = float(fast.ood_ratio(X)[0])
    findings = model.envelope_findings(X)[0] if hasattr(model, "envelope_findings") else []
    ood = ood_score > 1.0 or bool(findings)
    extra = (plan.reasons() if plan is not None else []) + list(extra_reasons)
    if coupling_split(feature_result):
        X_phase = coupling_phase_rows(names, row)
        readings = None if X_phase is None else \
            [str(model.classes_[k]) for k in model.band_index(fast.predict_proba(X_phase), X_phase)]
        extra.append(acquisitions_reason(feature_result, readings))
    backward = reverse_2x_reason(names, row, str(model.classes_[cls]) != str(model.bands_.names[0]))
    if backward is not None:
        extra.append(backward)
    if not ood:
        extra += _numbering_reasons(model, fast, names, row, ood_score, cls)
    if ood_score > 1.0:
        warnings.append(Note("signal_unlike_training", ood_score=ood_score))
    if findings:
        warnings.append(Note("features_outside_training", n_outside=len(findings),
                             examples=f"{', '.join(f['feature'] for f in findings[:5])}"
                                      f"{' …' if len(findings) > 5 else ''}"))
    if clearance_um is None:
        clearance_um = getattr(feature_result, "clearance_um", None)
    if clearance_um is not None and not (np.isfinite(clearance_um) and clearance_um > 0):
        raise ValueError(f"clearance_um: must be a positive number of micrometres, got {clearance_um!r}")
    severity = str(model.classes_[cls])
    bands = model.bands_
    band = list(bands.names).index(severity) if severity in bands.names else cls
    raw = float(point[0])
    delta, (lo, hi), agree = consistent_estimate(band, bands.edges, raw, (float(interval[0, 0]),
                                                                          float(interval[0, 1])))
    status, reasons = assess(
        RecordingChecks(names=names, row=row, feature_median=np.asarray(model.feature_median_, dtype=float),
                        sanity=sanity, ood_score=ood_score,
                        never_missing=never_missing_names, speed_source=getattr(feature_result, "speed_source", None),
                        warnings=warnings, envelope=findings, extra=extra),
        ModelCall(probabilities=proba, class_delta_agree=agree, call_index=cls,
                  band_names=[str(c) for c in model.classes_], misaligned_call=band > 0,
                  alarm=_alarm(model, proba, cls, X), delta_interval=(float(interval[0, 0]), float(interval[0, 1])),
                  band_edges=bands.edges, interval_level=1.0 - float(model.regressor_.alpha),
                  one_position_call=_one_position_call(model, fast, names, row) if band > 0 else None),
        policy_of(bundle.card) if isinstance(bundle, ModelBundle) else DEFAULT_POLICY)
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
    return Verdict(
        status=status,
        reasons=[r.to_dict() for r in reasons],
        evidence=[e.to_dict() for e in ev],
        misalignment_model=raw,
        model_severity=str(model.classes_[cls]),
        speed_source=getattr(feature_result, "speed_source", None),
        severity=severity,
        probabilities={str(n): float(p) for n, p in zip(model.classes_, proba)},
        misalignment=shown,
        misalignment_interval=shown_iv,
        interval_level=1.0 - float(model.regressor_.alpha),
        offset_um=offset,
        offset_interval_um=offset_iv,
        motion_type=_motion_type(feature_result),
        top_features=_contributions(model, fast, row, cls, top_k),
        ood=bool(ood),
        ood_score=ood_score,
        ood_findings=findings,
        speed_rpm=None if speed is None else float(speed),
        model_version=version,
        bands=model.bands_.to_dict(),
        warnings=warnings,
    )


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
    for w in v.warnings:
        lines.append(f"warning: {w.render(unit_key) if isinstance(w, Note) else w}")
    if evidence:
        lines.append("evidence (measured, independent of the model):")
        for e in evidence:
            lines.append(f"  {e['scope']:<14s} {e['name']:<24s} {e['value']}")
            lines.append(f"  {'':<14s} {'':<24s} → {e['meaning']}")
    return "\n".join(lines)
