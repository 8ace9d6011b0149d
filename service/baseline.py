"""Asset baselines and trend alarms (issue 17): the service's side.

The comparison itself is the features package's (``features.change_features``) and the verdict
on it the models package's (``models.change``); this module stores baselines and per-asset
thresholds, attaches the comparison to a /diagnose answer and proposes automatic baselines.

A baseline is always made of stored diagnoses of the asset (a recording sent to
``POST /assets/{id}/baseline`` is diagnosed and stored first): ``source`` is ``recording``,
``diagnosis`` (a stored diagnosis id) or ``auto`` (the average of the first
:data:`AUTO_N` stored recordings, which must lie within ``features.SPEED_BAND_FRAC`` of their
median speed).
"""
from __future__ import annotations

import math
import re
from typing import TYPE_CHECKING, Any

from rotordiag.core.timefmt import iso_utc

from .core.db import AssetBaseline, AssetBaselineRecording, AssetDiagnosis, utcnow
from .errors import InputError
from .store import (
    AUTO_N,
    baseline_recordings,
    first_diagnoses,
    get_baseline,
    get_diagnosis,
    get_thresholds,
    put_baseline,
    replace_baseline,
    store_diagnosis,
)

if TYPE_CHECKING:
    from sqlalchemy.orm import Session

    from .state import AppState


def baseline_dict(row: AssetBaseline, *, with_signature: bool = True,
                  recordings: list[AssetBaselineRecording] | None = None) -> dict[str, Any]:
    """The API form of a stored baseline (what ``models.change.compare`` takes, plus its provenance): with
    ``recordings`` (its rows, :func:`service.store.baseline_recordings`) each one's id, speed and times, and
    where its change thresholds come from (``thresholds_basis``, ``models.change.thresholds_basis``)."""
    from rotordiag.models.change import thresholds_basis

    out: dict[str, Any] = {"asset_id": row.asset_id, "set_at": iso_utc(row.created_at), "recorded_at": iso_utc(row.recorded_at),
           "source": row.source, "diagnosis_ids": list(row.diagnosis_ids or []), "speed_rpm": row.speed_rpm,
           "model_version": row.model_version}
    if with_signature:
        out["signature"] = row.signature
    out["repeatability"] = row.repeatability
    out["n_recordings"] = len(out["diagnosis_ids"]) or 1
    if recordings is not None:
        out["recordings"] = [{"diagnosis_id": r.diagnosis_id, "speed_rpm": r.speed_rpm,
                              "recorded_at": iso_utc(r.recorded_at), "added_at": iso_utc(r.added_at)} for r in recordings]
    out["thresholds_basis"] = thresholds_basis(out)
    return out


def _member(asset_id: str, d: Any) -> AssetBaselineRecording:
    """The baseline-recording row of a stored diagnosis ``d`` (its signature copied)."""
    return AssetBaselineRecording(asset_id=asset_id, diagnosis_id=d.id, added_at=utcnow(),
                                  recorded_at=d.recorded_at or d.created_at,
                                  speed_rpm=d.speed_rpm, model_version=d.model_version, signature=d.signature)


def _build(asset_id: str, source: str, members: list[AssetBaselineRecording]) -> AssetBaseline:
    """A baseline made of ``members``: one recording as it is; several averaged as vectors
    (``features.average_signatures``) with their repeatability thresholds (``models.change.
    repeatability_thresholds``; None for fewer than ``REPEAT_MIN`` or recordings not at one operating condition)."""
    from rotordiag.features import average_signatures
    from rotordiag.models.change import repeatability_thresholds

    sigs = [m.signature or {} for m in members]
    sig = sigs[0] if len(sigs) == 1 else average_signatures(sigs)
    times = [m.recorded_at for m in members if m.recorded_at is not None]
    return AssetBaseline(asset_id=asset_id, source=source, diagnosis_ids=[m.diagnosis_id for m in members],
                         recorded_at=max(times) if times else None,
                         speed_rpm=sig.get("speed_rpm", members[0].speed_rpm) if len(sigs) > 1 else members[0].speed_rpm,
                         model_version=sorted({m.model_version for m in members})[-1], signature=sig,
                         repeatability=repeatability_thresholds(sigs))


def _same_condition(speeds: list[float | None], ids: list[int], what: str, fix: str) -> None:
    """``InputError`` (409) unless every speed is known and within ``features.SPEED_BAND_FRAC`` of their median
    (``what``: the recordings, in words; ``fix``: what to do instead)."""
    from rotordiag.features import SPEED_BAND_FRAC

    if any(v is None or not math.isfinite(v) for v in speeds):
        raise InputError(f"{what} need the speed of every recording; one has none", "conflict")
    vals = [float(v) for v in speeds]   # type: ignore[arg-type]
    med = sorted(vals)[len(vals) // 2]
    far = [(i, v) for i, v in zip(ids, vals) if abs(v / med - 1.0) > SPEED_BAND_FRAC]
    if far:
        raise InputError(
            f"{what} are not at one operating condition: speeds " + ", ".join(f"{v:.0f}" for v in vals)
            + f" r/min (diagnoses {', '.join(str(i) for i, _ in far)} more than ±{100 * SPEED_BAND_FRAC:g} % from "
            f"the median {med:.0f}); {fix}", "conflict")


def _baseline_candidate(session: Session, asset_id: str, diagnosis_id: int) -> AssetDiagnosis:
    """The stored diagnosis ``diagnosis_id`` of ``asset_id``, to make (part of) its baseline; InputError
    ``not_found`` when the asset has no such diagnosis, ``conflict`` when it keeps no signature to compare with."""
    d = get_diagnosis(session, asset_id, diagnosis_id)
    if d is None:
        raise InputError(f"asset {asset_id!r} has no stored diagnosis {diagnosis_id}; GET "
                         f"/assets/{asset_id}/history lists its diagnoses with their ids", "not_found")
    if d.signature is None:
        raise InputError(f"diagnosis {diagnosis_id} keeps no signature (it was stored before baselines existed, or "
                         "only its summary is kept past the history's retention); send its recording instead",
                         "conflict")
    return d


def add_recording(state: AppState, asset_id: str, diagnosis_id: int) -> dict[str, Any]:
    """Add the stored diagnosis ``diagnosis_id`` to the asset's baseline (making one when it has none) and recompute
    the baseline and its own thresholds.

    Raises
    ------
    InputError
        ``not_found`` for a diagnosis the asset lacks; ``conflict`` when it keeps no signature, is already in
        the baseline, is not at the baseline's operating condition, or the baseline predates per-recording storage.
    """
    with state.sessions.begin() as s:   # read, check and rewrite in one transaction, the baseline row locked
        row = get_baseline(s, asset_id, lock=True)
        d = _baseline_candidate(s, asset_id, diagnosis_id)
        members = baseline_recordings(s, asset_id)
        if row is not None and not members:
            raise InputError(f"the baseline of asset {asset_id!r} was set before its recordings were kept one by one "
                             "and its recordings' signatures are gone; set a new baseline (POST "
                             f"/assets/{asset_id}/baseline)", "conflict")
        if any(m.diagnosis_id == diagnosis_id for m in members):
            raise InputError(f"diagnosis {diagnosis_id} is already in the baseline of asset {asset_id!r}", "conflict")
        fresh = [*(_copy(m) for m in members), _member(asset_id, d)]
        _same_condition([m.speed_rpm for m in fresh], [m.diagnosis_id for m in fresh],
                        f"the baseline's recordings with diagnosis {diagnosis_id}",
                        "record at the baseline's operating condition, or set a new baseline")
        replace_baseline(s, _build(asset_id, row.source if row is not None else "recording", fresh), fresh)
    return _stored(state, asset_id)


def remove_recording(state: AppState, asset_id: str, diagnosis_id: int) -> dict[str, Any]:
    """Take the recording ``diagnosis_id`` out of the asset's baseline and recompute it (its own thresholds go
    back to the fleet-wide ones below ``models.change.REPEAT_MIN`` recordings).

    Raises
    ------
    InputError
        ``not_found`` when it is not one of the baseline's recordings (or there is no baseline); ``conflict``
        for the last one (DELETE the baseline instead).
    """
    with state.sessions.begin() as s:   # read, check and rewrite in one transaction, the baseline row locked
        row = get_baseline(s, asset_id, lock=True)
        members = baseline_recordings(s, asset_id)
        if row is None or not any(m.diagnosis_id == diagnosis_id for m in members):
            ids = [m.diagnosis_id for m in members]
            raise InputError(f"diagnosis {diagnosis_id} is not a recording of the baseline of asset {asset_id!r}"
                             + (f" (its recordings: {ids})" if ids else " (it has no baseline made of recordings)"),
                             "not_found")
        if len(members) == 1:
            raise InputError(f"diagnosis {diagnosis_id} is the baseline's only recording; DELETE "
                             f"/assets/{asset_id}/baseline removes the baseline", "conflict")
        fresh = [_copy(m) for m in members if m.diagnosis_id != diagnosis_id]
        replace_baseline(s, _build(asset_id, row.source, fresh), fresh)
    return _stored(state, asset_id)


def _copy(m: AssetBaselineRecording) -> AssetBaselineRecording:
    """A new (transient) row with ``m``'s values, to be written again with the rebuilt baseline."""
    return AssetBaselineRecording(asset_id=m.asset_id, diagnosis_id=m.diagnosis_id, added_at=m.added_at,
                                  recorded_at=m.recorded_at, speed_rpm=m.speed_rpm, model_version=m.model_version,
                                  signature=m.signature)


def _stored(state: AppState, asset_id: str) -> dict[str, Any]:
    """The asset's stored baseline in its API form, with its recordings."""
    with state.sessions() as s:
        row = get_baseline(s, asset_id)
        assert row is not None
        return baseline_dict(row, recordings=baseline_recordings(s, asset_id))


def rule_for(session: Session, asset_id: str, row: AssetBaseline | None = None):
    """The asset's alarm thresholds: the shipped ones, the repeatability ones of its baseline (``row``, read
    when not given), then the asset's edits."""
    from rotordiag.models.change import shipped_rule

    if row is None:
        row = get_baseline(session, asset_id)
    rep = row.repeatability if row is not None else None
    return shipped_rule().with_repeatability(rep).with_overrides(get_thresholds(session, asset_id))


def thresholds_origin(session: Session, asset_id: str, row: AssetBaseline | None = None) -> dict[str, str]:
    """Per threshold in force: ``shipped``, ``repeatability`` or ``edited`` (see :func:`rule_for`)."""
    from rotordiag.models.change import shipped_rule

    if row is None:
        row = get_baseline(session, asset_id)
    own = set(((row.repeatability or {}).get("thresholds") or {}) if row is not None else ())
    edited = set(get_thresholds(session, asset_id))
    return {k: "edited" if k in edited else "repeatability" if k in own else "shipped"
            for k in shipped_rule().thresholds}


def attach_baseline(state: AppState, asset_id: str, verdict: dict[str, Any], signature: dict[str, Any] | None,
                    storing: bool = False) -> None:
    """Put the ``baseline`` section into ``verdict`` (in place) and the change items into its evidence
    (``storing``: this recording is about to be stored, so the hint counts it)."""
    from rotordiag.models.change import compare

    with state.sessions() as s:
        row = get_baseline(s, asset_id)
        rule = rule_for(s, asset_id, row)
        base = baseline_dict(row) if row is not None else None
        hint = "" if row is not None else _auto_hint(s, asset_id, storing and signature is not None)
    if signature is None:
        section = compare({"bearings": []}, None, rule, asset_hint=hint)
    else:
        section = compare(signature, base, rule, asset_hint=hint)
    verdict["baseline"] = section
    verdict["evidence"] = list(section.pop("evidence", [])) + list(verdict.get("evidence") or [])


#: an operating-state tag name (``load_mw``, ``field_current_a``, ``stator_temp_c``: units in the name)
_TAG_NAME = re.compile(r"^[a-z][a-z0-9_]{0,47}$")
MAX_TAGS = 32


def parse_tags(text: str | None) -> dict[str, float | str]:
    """Operating-state tags from ``name=value;name=value`` (a number where the value reads as a finite one,
    else the text, at most 200 characters); ``InputError`` saying what to fix."""
    out: dict[str, float | str] = {}
    for part in (text or "").split(";"):
        if not part.strip():
            continue
        name, sep, value = part.partition("=")
        name, value = name.strip(), value.strip()
        if not sep or not _TAG_NAME.match(name) or not value or len(value) > 200:
            raise InputError(f"tags: {part.strip()[:60]!r} is not name=value (a lower-case name with its unit, "
                             "e.g. load_mw=350;field_current_a=1210;stator_temp_c=71)")
        try:
            num = float(value)
            out[name] = num if math.isfinite(num) else value
        except ValueError:
            out[name] = value
    if len(out) > MAX_TAGS:
        raise InputError(f"tags: {len(out)} given; at most {MAX_TAGS}")
    return out


def record_verdict(state: AppState, asset_id: str | None, plant: str | None, verdict: dict[str, Any],
                   store: bool = True, meta: dict[str, Any] | None = None) -> int | None:
    """The last step of every diagnosis: take the recording's signature out of the answer and, with an
    ``asset_id``, compare with the asset's baseline and, when ``store`` (the request carried the API key),
    store the diagnosis (its id goes into the answer). The answer says whether it was stored (``stored``,
    and ``storage_note`` when not)."""
    signature = verdict.pop("signature", None)
    if asset_id is None:
        return None
    attach_baseline(state, asset_id, verdict, signature, storing=store)
    from .startups import attach_startup

    with state.sessions() as s:
        verdict.update(attach_startup(s, asset_id, verdict))
    verdict["stored"] = store
    if not store:
        verdict["storage_note"] = (f"not stored in the history of asset {asset_id!r}: storing a diagnosis needs the "
                                   "API key in the X-API-Key header; this answer is complete without it")
        return None
    verdict["diagnosis_id"] = store_diagnosis(state, asset_id, plant, verdict, signature, meta)
    return verdict["diagnosis_id"]


def _auto_hint(session: Session, asset_id: str, this_one_stored: bool = False) -> str:
    """How to set a baseline, with the count of stored recordings — this one included when it is being stored
    (the hint is written before the answer is stored)."""
    n = min(AUTO_N, len(first_diagnoses(session, asset_id, AUTO_N)) + int(this_one_stored))
    return (f"; set one with POST /assets/{asset_id}/baseline (a recording, ?diagnosis_id=, or ?auto=true once "
            f"{AUTO_N} recordings at one operating condition are stored: {n} with this one)" if this_one_stored else
            f"; set one with POST /assets/{asset_id}/baseline (a recording, ?diagnosis_id=, or ?auto=true once "
            f"{AUTO_N} recordings at one operating condition are stored: {n} stored)")


def from_diagnosis(state: AppState, asset_id: str, diagnosis_id: int, source: str = "diagnosis") -> dict[str, Any]:
    """Make the stored diagnosis ``diagnosis_id`` of ``asset_id`` the asset's baseline."""
    with state.sessions() as s:
        member = _member(asset_id, _baseline_candidate(s, asset_id, diagnosis_id))
    put_baseline(state, _build(asset_id, source, [member]), [member])
    return _stored(state, asset_id)


def propose(session: Session, asset_id: str, n: int = AUTO_N) -> dict[str, Any]:
    """The automatic baseline proposal: the first ``n`` stored recordings, if at one operating condition,
    averaged, with their repeatability thresholds (None for fewer than ``models.change.REPEAT_MIN``).

    Raises
    ------
    InputError
        ``conflict`` when fewer than ``n`` are stored, or when their speeds spread wider than the band
        (the message names the speeds).
    """
    from rotordiag.features import average_signatures

    rows = first_diagnoses(session, asset_id, n)
    if len(rows) < n:
        raise InputError(f"asset {asset_id!r} has {len(rows)} stored recording(s) with a signature; an automatic "
                         f"baseline needs {n} (POST /diagnose with asset_id, or set one from a recording)", "conflict")
    _same_condition([r.speed_rpm for r in rows], [r.id for r in rows],
                    f"the first {n} recordings of asset {asset_id!r}",
                    "set the baseline from a recording or a diagnosis id instead")
    from rotordiag.models.change import repeatability_thresholds

    sigs = [r.signature or {} for r in rows]
    sig = average_signatures(sigs)
    versions = sorted({r.model_version for r in rows})
    return {"diagnosis_ids": [r.id for r in rows], "recorded_at": rows[-1].created_at, "speed_rpm": sig["speed_rpm"],
            "model_version": versions[-1], "signature": sig, "repeatability": repeatability_thresholds(sigs),
            "members": [_member(asset_id, r) for r in rows]}


def set_auto(state: AppState, asset_id: str, n: int = AUTO_N) -> dict[str, Any]:
    """Set the automatic proposal as the asset's baseline (its recordings kept one by one)."""
    with state.sessions() as s:
        p = propose(s, asset_id, n)
    put_baseline(state, _build(asset_id, "auto", p["members"]), p["members"])
    return _stored(state, asset_id)


def alarm_events(rows: list[Any]) -> list[dict[str, Any]]:
    """Alarm history from stored diagnoses (oldest first): ``raised`` when a compared diagnosis changed after
    one that had not (or the first), ``cleared`` when a compared diagnosis no longer changed."""
    events = []
    state = False
    for r in rows:
        if r.alarm is None:
            continue
        if r.alarm and not state:
            events.append({"time": r.recorded_at or r.created_at, "event": "raised", "diagnosis_id": r.id,
                           "quantities": list((r.change or {}).get("exceeded") or [])})
        elif not r.alarm and state:
            events.append({"time": r.recorded_at or r.created_at, "event": "cleared", "diagnosis_id": r.id, "quantities": []})
        state = bool(r.alarm)
    return events
