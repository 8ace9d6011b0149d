"""Writing and reading asset diagnoses (the per-asset trend)."""
from __future__ import annotations

import datetime as dt
from typing import TYPE_CHECKING, Any

from sqlalchemy import select

from .core.db import AssetDiagnosis

if TYPE_CHECKING:
    from sqlalchemy.orm import Session

    from .state import AppState


def _num(value: Any) -> float | None:
    try:
        return None if value is None else float(value)
    except (TypeError, ValueError):
        return None


def store_diagnosis(state: AppState, asset_id: str, plant: str | None, verdict: dict[str, Any]) -> None:
    """Store one verdict for ``asset_id`` (time, verdict, key features, model version)."""
    interval = verdict.get("misalignment_interval") or (None, None)
    row = AssetDiagnosis(
        asset_id=asset_id, plant=plant, model_version=str(verdict.get("model_version", "")),
        severity=str(verdict.get("severity", "")),
        misalignment=_num(verdict.get("misalignment")),
        misalignment_low=_num(interval[0]), misalignment_high=_num(interval[1]),
        speed_rpm=_num(verdict.get("speed_rpm")),
        ood=None if verdict.get("ood") is None else bool(verdict.get("ood")),
        verdict=verdict, key_features=dict(verdict.get("key_features") or {}),
    )
    with state.sessions.begin() as s:
        s.add(row)


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
