"""An asset's start-ups and coast-downs as evidence beside its steady verdicts (issue 46, item 4).

A start-up uploaded to an asset (``POST /assets/{id}/startup``) is order-tracked and reduced to what
:mod:`rotordiag.models.checks.startup` compares — the 1X criticals and the coupling-end bearings' centreline rise —
and stored (``asset_startups``; no waveform). One start-up is the asset's **baseline start-up** (``?baseline=true``:
the latest such upload). A later start-up is compared with it, and the comparison is evidence in the asset's
verdicts from then on: every diagnosis of the asset (:func:`attach_startup`, called by
``service.baseline.record_verdict``) and the asset's report carry it as ``start-up`` evidence rows, and on an
"aligned" call a start-up that changed adds the ``startup_changed`` reason (a confident verdict becomes
uncertain, the headline "investigate change"). It never changes a band, Δ or a probability.
"""
from __future__ import annotations

import datetime as dt
from typing import TYPE_CHECKING, Any

from sqlalchemy import select

from .core.db import AssetStartup

if TYPE_CHECKING:
    from sqlalchemy.orm import Session

    from .state import AppState

__all__ = ["startup_data", "store_startup", "startups_in_force", "startup_comparison", "attach_startup",
           "startup_dict"]


def startup_data(recording: Any) -> dict[str, Any]:
    """What the service keeps of a start-up recording: ``{"evidence": StartupEvidence.to_dict(), "summary":
    transient_summary}`` (plain data). Raises ValueError with the features package's message for a run that
    cannot be tracked (a speed that reverses, a keyphasor that drops out, no speed change, ...)."""
    from rotordiag.features.transient import centreline, track_orders
    from rotordiag.models.report import transient_summary
    from rotordiag.models.startup import startup_evidence

    track = track_orders(recording)
    cl = None if recording.dc_removed else centreline(recording, track)
    ev = startup_evidence(track, cl)
    summary = transient_summary(track)
    summary["centreline"] = cl is not None
    return {"evidence": ev.to_dict(), "summary": summary}


def store_startup(state: AppState, asset_id: str, data: dict[str, Any], *, is_baseline: bool,
                  recorded_at: dt.datetime | None = None, note: str | None = None) -> int:
    """Store a start-up's :func:`startup_data` for ``asset_id``; returns its id."""
    row = AssetStartup(asset_id=asset_id, is_baseline=bool(is_baseline), evidence=data["evidence"],
                       summary=data["summary"], recorded_at=recorded_at, note=note)
    with state.sessions.begin() as s:
        s.add(row)
        s.flush()
        return int(row.id)


def startups_in_force(session: Session, asset_id: str) -> tuple[AssetStartup | None, AssetStartup | None]:
    """The asset's baseline start-up (its latest ``is_baseline`` upload) and its latest later start-up (uploaded
    after that baseline; any, when there is no baseline), each None when there is none."""
    base = session.scalars(select(AssetStartup).where(AssetStartup.asset_id == asset_id,
                                                      AssetStartup.is_baseline.is_(True))
                           .order_by(AssetStartup.id.desc()).limit(1)).first()
    q = select(AssetStartup).where(AssetStartup.asset_id == asset_id, AssetStartup.is_baseline.is_(False))
    if base is not None:
        q = q.where(AssetStartup.id > base.id)
    later = session.scalars(q.order_by(AssetStartup.id.desc()).limit(1)).first()
    return base, later


def _when(row: AssetStartup) -> str:
    return f"start-up #{row.id} of {(row.recorded_at or row.created_at):%Y-%m-%d %H:%M} UTC"


def startup_comparison(base: AssetStartup | None, later: AssetStartup,
                       verdict: dict[str, Any] | None) -> tuple[list[dict[str, Any]], list[Any]]:
    """``models.checks.startup.startup_findings`` of a stored later start-up against the stored baseline start-up,
    for ``verdict``'s call (None: no steady verdict, nothing is called)."""
    from rotordiag.models.checks.startup import StartupContext, startup_findings
    from rotordiag.models.startup import StartupEvidence, misaligned_call

    return startup_findings(StartupContext(StartupEvidence.from_dict(later.evidence),
                                           StartupEvidence.from_dict(base.evidence) if base is not None else None,
                                           misaligned_call(verdict)))


def attach_startup(session: Session, asset_id: str, verdict: dict[str, Any]) -> dict[str, Any]:
    """``verdict`` with the asset's latest later start-up as evidence (``models.startup.with_startup``)
    and a ``startup`` section naming the start-ups compared; ``verdict`` itself when the asset has no later
    start-up. Skipped for a verdict that already carries that start-up."""
    from rotordiag.models.startup import with_startup

    base, later = startups_in_force(session, asset_id)
    if later is None or (verdict.get("startup") or {}).get("startup_id") == later.id:
        return verdict
    entries, reasons = startup_comparison(base, later, verdict)
    out = with_startup(verdict, entries, reasons, source=_when(later))
    out["startup"] = {"startup_id": later.id, "baseline_startup_id": None if base is None else base.id,
                      "changed": any(e["code"] == "startup_changed" for e in entries),
                      "reasons": [r.code for r in reasons]}
    return out


def startup_dict(row: AssetStartup) -> dict[str, Any]:
    """A stored start-up as the API answers it."""
    s = row.summary or {}
    return {"startup_id": row.id, "asset_id": row.asset_id, "is_baseline": row.is_baseline,
            "created_at": row.created_at, "recorded_at": row.recorded_at, "note": row.note,
            "kind": s.get("kind"), "speed_source": s.get("speed_source"), "speed_range_rpm": s.get("speed_range_rpm"),
            "n_steps": s.get("n_steps"), "peaks": s.get("peaks") or [], "notes": s.get("notes") or [],
            "centreline": bool(s.get("centreline")), "evidence": row.evidence}
