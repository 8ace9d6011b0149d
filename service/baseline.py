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

import datetime as dt
import math
import re
from typing import TYPE_CHECKING, Any

from .core.db import AssetBaseline
from .errors import InputError
from .store import AUTO_N, first_diagnoses, get_baseline, get_diagnosis, get_thresholds, put_baseline, store_diagnosis

if TYPE_CHECKING:
    from sqlalchemy.orm import Session

    from .state import AppState



def _iso(t: dt.datetime | None) -> str | None:
    if t is None:
        return None
    if t.tzinfo is None:
        t = t.replace(tzinfo=dt.UTC)
    return t.isoformat().replace("+00:00", "Z")


def baseline_dict(row: AssetBaseline, *, with_signature: bool = True) -> dict[str, Any]:
    """The API form of a stored baseline (what ``models.change.compare`` takes, plus its provenance)."""
    out: dict[str, Any] = {"asset_id": row.asset_id, "set_at": _iso(row.created_at), "recorded_at": _iso(row.recorded_at),
           "source": row.source, "diagnosis_ids": list(row.diagnosis_ids or []), "speed_rpm": row.speed_rpm,
           "model_version": row.model_version}
    if with_signature:
        out["signature"] = row.signature
    out["repeatability"] = row.repeatability
    return out


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
        d = get_diagnosis(s, asset_id, diagnosis_id)
        if d is None:
            raise InputError(f"asset {asset_id!r} has no stored diagnosis {diagnosis_id}; GET "
                             f"/assets/{asset_id}/history lists its diagnoses with their ids", "not_found")
        if d.signature is None:
            raise InputError(f"diagnosis {diagnosis_id} keeps no signature (it was stored before baselines existed, "
                             "or only its summary is kept past the history's retention); send its recording to "
                             "this endpoint instead", "conflict")
        row = AssetBaseline(asset_id=asset_id, source=source, diagnosis_ids=[d.id], recorded_at=d.created_at,
                            speed_rpm=d.speed_rpm, model_version=d.model_version, signature=d.signature)
    return baseline_dict(put_baseline(state, row))


def propose(session: Session, asset_id: str, n: int = AUTO_N) -> dict[str, Any]:
    """The automatic baseline proposal: the first ``n`` stored recordings, if at one operating condition,
    averaged, with their repeatability thresholds (None for fewer than ``models.change.REPEAT_MIN``).

    Raises
    ------
    InputError
        ``conflict`` when fewer than ``n`` are stored, or when their speeds spread wider than the band
        (the message names the speeds).
    """
    from rotordiag.features import SPEED_BAND_FRAC, average_signatures

    rows = first_diagnoses(session, asset_id, n)
    if len(rows) < n:
        raise InputError(f"asset {asset_id!r} has {len(rows)} stored recording(s) with a signature; an automatic "
                         f"baseline needs {n} (POST /diagnose with asset_id, or set one from a recording)", "conflict")
    if any(r.speed_rpm is None or not math.isfinite(r.speed_rpm) for r in rows):
        raise InputError("an automatic baseline needs the speed of every recording; one has none", "conflict")
    speeds = [float(r.speed_rpm or 0.0) for r in rows]
    med = sorted(speeds)[len(speeds) // 2]
    far = [(r.id, v) for r, v in zip(rows, speeds) if abs(v / med - 1.0) > SPEED_BAND_FRAC]
    if far:
        raise InputError(
            f"the first {n} recordings of asset {asset_id!r} are not at one operating condition: speeds "
            + ", ".join(f"{v:.0f}" for v in speeds) + f" r/min (diagnoses {', '.join(str(i) for i, _ in far)} "
            f"more than ±{100 * SPEED_BAND_FRAC:g} % from the median {med:.0f}); set the baseline from a recording "
            "or a diagnosis id instead", "conflict")
    from rotordiag.models.change import repeatability_thresholds

    sigs = [r.signature or {} for r in rows]
    sig = average_signatures(sigs)
    versions = sorted({r.model_version for r in rows})
    return {"diagnosis_ids": [r.id for r in rows], "recorded_at": rows[-1].created_at, "speed_rpm": sig["speed_rpm"],
            "model_version": versions[-1], "signature": sig, "repeatability": repeatability_thresholds(sigs)}


def set_auto(state: AppState, asset_id: str, n: int = AUTO_N) -> dict[str, Any]:
    """Set the automatic proposal as the asset's baseline."""
    with state.sessions() as s:
        p = propose(s, asset_id, n)
    row = AssetBaseline(asset_id=asset_id, source="auto", diagnosis_ids=p["diagnosis_ids"],
                        recorded_at=p["recorded_at"], speed_rpm=p["speed_rpm"], model_version=p["model_version"],
                        signature=p["signature"], repeatability=p["repeatability"])
    return baseline_dict(put_baseline(state, row))


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
