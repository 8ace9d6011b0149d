"""Writing and reading asset diagnoses (the per-asset trend), baselines, alarm thresholds and probe configurations."""
from __future__ import annotations

import datetime as dt
from typing import TYPE_CHECKING, Any

from sqlalchemy import select

from .core.db import AssetBaseline, AssetDiagnosis, AssetSettings

if TYPE_CHECKING:
    from sqlalchemy.orm import Session

    from .state import AppState


def _num(value: Any) -> float | None:
    try:
        return None if value is None else float(value)
    except (TypeError, ValueError):
        return None


def store_diagnosis(state: AppState, asset_id: str, plant: str | None, verdict: dict[str, Any],
                    signature: dict[str, Any] | None = None) -> int:
    """Store one verdict for ``asset_id`` (time, verdict, key features, model version, the recording's
    signature, the comparison with the baseline when the verdict has one); returns the row id."""
    section = verdict.get("baseline") or {}
    change = {k: v for k, v in section.items() if k != "evidence"} if section.get("compared") else None
    interval = verdict.get("misalignment_interval") or (None, None)
    row = AssetDiagnosis(
        asset_id=asset_id, plant=plant, model_version=str(verdict.get("model_version", "")),
        severity=str(verdict.get("severity", "")),
        misalignment=_num(verdict.get("misalignment")),
        misalignment_low=_num(interval[0]), misalignment_high=_num(interval[1]),
        speed_rpm=_num(verdict.get("speed_rpm")),
        ood=None if verdict.get("ood") is None else bool(verdict.get("ood")),
        verdict=verdict, key_features=dict(verdict.get("key_features") or {}),
        signature=signature, change=change, alarm=None if change is None else bool(change.get("changed")),
    )
    with state.sessions.begin() as s:
        s.add(row)
        s.flush()
        return int(row.id)


def asset_history(session: Session, asset_id: str, limit: int, since: dt.datetime | None) -> list[AssetDiagnosis]:
    """The latest ``limit`` diagnoses of ``asset_id`` (after ``since``), oldest first."""
    q = select(AssetDiagnosis).where(AssetDiagnosis.asset_id == asset_id)
    if since is not None:
        if since.tzinfo is None:
            since = since.replace(tzinfo=dt.UTC)
        q = q.where(AssetDiagnosis.created_at >= since)
    q = q.order_by(AssetDiagnosis.created_at.desc(), AssetDiagnosis.id.desc()).limit(limit)
    rows = list(session.scalars(q))
    rows.reverse()
    return rows


def get_diagnosis(session: Session, asset_id: str, diagnosis_id: int) -> AssetDiagnosis | None:
    """The stored diagnosis ``diagnosis_id`` of ``asset_id`` (None when there is none)."""
    row = session.get(AssetDiagnosis, diagnosis_id)
    return row if row is not None and row.asset_id == asset_id else None


def first_diagnoses(session: Session, asset_id: str, limit: int) -> list[AssetDiagnosis]:
    """The oldest ``limit`` diagnoses of ``asset_id`` that carry a signature, oldest first."""
    q = (select(AssetDiagnosis).where(AssetDiagnosis.asset_id == asset_id, AssetDiagnosis.signature.is_not(None))
         .order_by(AssetDiagnosis.created_at, AssetDiagnosis.id).limit(limit))
    return list(session.scalars(q))


def get_baseline(session: Session, asset_id: str) -> AssetBaseline | None:
    return session.get(AssetBaseline, asset_id)


def put_baseline(state: AppState, row: AssetBaseline) -> AssetBaseline:
    """Store ``row`` as the asset's baseline, replacing any previous one."""
    with state.sessions.begin() as s:
        old = s.get(AssetBaseline, row.asset_id)
        if old is not None:
            s.delete(old)
            s.flush()
        s.add(row)
    return row


def delete_baseline(state: AppState, asset_id: str) -> bool:
    """Remove the asset's baseline; False when it had none."""
    with state.sessions.begin() as s:
        old = s.get(AssetBaseline, asset_id)
        if old is None:
            return False
        s.delete(old)
    return True


def get_thresholds(session: Session, asset_id: str) -> dict[str, Any]:
    """The asset's edited alarm thresholds (empty when it uses the shipped ones)."""
    row = session.get(AssetSettings, asset_id)
    return dict(row.thresholds or {}) if row is not None else {}


def put_thresholds(state: AppState, asset_id: str, thresholds: dict[str, Any]) -> None:
    """Replace the asset's edited thresholds (an empty dict goes back to the shipped ones)."""
    with state.sessions.begin() as s:
        row = s.get(AssetSettings, asset_id)
        if row is None:
            s.add(AssetSettings(asset_id=asset_id, thresholds=dict(thresholds)))
        else:
            row.thresholds = dict(thresholds)


def get_probe_config(session: Session, asset_id: str) -> tuple[dict[str, Any], Any] | None:
    """The asset's stored probe configuration and when it was set, or ``None``."""
    row = session.get(AssetSettings, asset_id)
    if row is None or not row.probes:
        return None
    return dict(row.probes), row.updated_at


def put_probe_config(state: AppState, asset_id: str, probes: dict[str, Any]) -> None:
    """Replace the asset's probe configuration (an empty dict removes it)."""
    with state.sessions.begin() as s:
        row = s.get(AssetSettings, asset_id)
        if row is None:
            s.add(AssetSettings(asset_id=asset_id, thresholds={}, probes=dict(probes) or None))
        else:
            row.probes = dict(probes) or None


def latest_changes(session: Session) -> list[tuple[str, dict[str, Any]]]:
    """``(asset_id, change)`` of each asset's latest diagnosis compared with a baseline (for the metrics)."""
    from sqlalchemy import func

    last = (select(AssetDiagnosis.asset_id, func.max(AssetDiagnosis.id).label("id"))
            .where(AssetDiagnosis.change.is_not(None)).group_by(AssetDiagnosis.asset_id).subquery())
    q = select(AssetDiagnosis).join(last, AssetDiagnosis.id == last.c.id)
    return [(r.asset_id, r.change or {}) for r in session.scalars(q)]
