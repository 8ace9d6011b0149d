"""GET /assets/{asset_id}/history."""
from __future__ import annotations

import datetime as dt
from typing import Annotated

from fastapi import APIRouter, Path, Query
from pydantic import BeforeValidator

from ...schemas import MAX_LABEL_LEN, AssetHistory, AssetPoint, ErrorOut
from ...store import asset_history
from ..deps import SessionDep
from ..errors import InputError

router = APIRouter(tags=["assets"])


def _iso_time(value: object) -> object:
    """Refuse a bare number for ``since`` (pydantic would read ``0.5`` as seconds since 1970)."""
    if isinstance(value, str):
        try:
            float(value)
        except ValueError:
            return value
        raise ValueError("since: give a date and time in ISO 8601, e.g. 2024-05-01T12:00:00Z (not a number)")
    return value


@router.get("/assets/{asset_id}/history", response_model=AssetHistory,
            responses={404: {"model": ErrorOut, "description": "No diagnosis stored for this asset."}},
            summary="Trend of an asset's diagnoses")
def history(
    asset_id: Annotated[str, Path(min_length=1, max_length=MAX_LABEL_LEN, pattern=r"^[A-Za-z0-9._:-]+$",
                                  description="The `asset_id` sent with /diagnose.")],
    session: SessionDep,
    limit: Annotated[int, Query(ge=1, le=10_000, description="Most recent points to return.")] = 500,
    since: Annotated[dt.datetime | None, BeforeValidator(_iso_time), Query(description="Only points at or after this time (ISO 8601; "
                                               "UTC when no offset is given).")] = None,
) -> AssetHistory:
    rows = asset_history(session, asset_id, limit, since)
    if not rows and since is None:
        raise InputError(f"no diagnosis stored for asset {asset_id!r}; POST /diagnose with \"asset_id\": "
                         f"\"{asset_id}\" to start its history", "not_found")
    points = [AssetPoint(time=r.created_at, severity=r.severity, misalignment=r.misalignment,
                         misalignment_low=r.misalignment_low, misalignment_high=r.misalignment_high,
                         speed_rpm=r.speed_rpm, ood=r.ood, model_version=r.model_version, plant=r.plant,
                         key_features=r.key_features, amplitudes_um_pp=_amplitudes(r.verdict)) for r in rows]
    return AssetHistory(asset_id=asset_id, count=len(points), points=points)


def _amplitudes(verdict: dict | None) -> dict[str, float | None]:
    """1X/2X orbit major axes (µm pk-pk) of each bearing, from a stored verdict's per-bearing features."""
    out: dict[str, float | None] = {}
    for b in (verdict or {}).get("bearings") or []:
        feats = b.get("features") or {}
        for name in (f"b{b.get('bearing')}_1x_major_um_pp", f"b{b.get('bearing')}_2x_major_um_pp"):
            if name in feats:
                out[name] = feats[name]
    return out
