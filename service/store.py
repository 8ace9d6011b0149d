"""Writing and reading asset diagnoses (the per-asset trend), baselines, alarm thresholds and probe configurations;
the history's retention (full diagnoses for a while, summaries longer) and the checks ``GET /health`` makes of the
storage."""
from __future__ import annotations

import datetime as dt
from typing import TYPE_CHECKING, Any

from sqlalchemy import Text, cast, delete, func, select, update

from rotordiag.models.output_units import with_typed_texts

from .alarms import evaluate
from .core.db import AssetBaseline, AssetBaselineRecording, AssetDiagnosis, AssetSettings, Job, ServiceProbe, utcnow

if TYPE_CHECKING:
    from sqlalchemy.orm import Session

    from .state import AppState


def _num(value: Any) -> float | None:
    try:
        return None if value is None else float(value)
    except (TypeError, ValueError):
        return None


def trend_time() -> Any:
    """The time a stored diagnosis sits at on the trend: when its recording was made, else when it was stored."""
    return func.coalesce(AssetDiagnosis.recorded_at, AssetDiagnosis.created_at)


def store_diagnosis(state: AppState, asset_id: str, plant: str | None, verdict: dict[str, Any],
                    signature: dict[str, Any] | None = None, meta: dict[str, Any] | None = None) -> int:
    """Store one verdict for ``asset_id`` (time, verdict, key features, model version, the recording's
    signature, the comparison with the baseline when the verdict has one) and, in the same transaction, the
    alarm events it raises or clears (``service.alarms.evaluate``); returns the row id. ``meta``: the
    recording's ``recorded_at``, ``tags`` and ``note`` when given. A backfilled recording (made before the
    asset's latest stored one) takes its place on the trend but raises and clears no alarm."""
    meta = meta or {}
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
        verdict=with_typed_texts(verdict), key_features=dict(verdict.get("key_features") or {}),
        signature=signature, change=change, alarm=None if change is None else bool(change.get("changed")),
        recorded_at=meta.get("recorded_at"), tags=meta.get("tags") or None, note=meta.get("note") or None,
    )
    with state.sessions.begin() as s:
        latest = s.scalar(select(func.max(trend_time())).where(AssetDiagnosis.asset_id == asset_id))
        s.add(row)
        s.flush()
        row_id = int(row.id)
        when = row.recorded_at or row.created_at
        backfill = latest is not None and when is not None and _aware(when) < _aware(latest)
        events = [] if backfill else evaluate(s, state.settings, asset_id, row_id, verdict, row.alarm)
        apply_retention(s, state.settings, asset_id)
    sender = getattr(state, "webhooks", None)
    if events and sender is not None:
        sender.wake()
    return row_id


#: recordings an automatic baseline is made of (default of ``?n=``; ``service.baseline`` takes them)
AUTO_N = 3


def apply_retention(session: Session, settings: Any, asset_id: str) -> tuple[int, int]:
    """Bound the stored history of ``asset_id`` (runs in the transaction that stores a diagnosis).

    A diagnosis keeps its full record (verdict, key features, signature: about 30 kB) while it is among the
    asset's latest ``history_keep_recordings`` and younger than ``history_keep_days``; after that only its
    summary columns (time, severity, Δ and interval, speed, OOD, alarm, change) stay, for
    ``history_summary_days``, then the row is deleted; beyond ``history_max_rows`` rows the oldest are deleted
    too. While the asset has no baseline, the recordings an
    automatic baseline would be made of (its first ``AUTO_N`` with a signature) keep their signature.
    Returns ``(trimmed, deleted)``.
    """
    now = utcnow()
    keep_n = int(settings.history_keep_recordings)
    keep_days = float(settings.history_keep_days)
    full = (AssetDiagnosis.asset_id == asset_id) & AssetDiagnosis.signature.is_not(None)
    old: list[int] = []
    if keep_n > 0:
        old += list(session.scalars(select(AssetDiagnosis.id).where(full)
                                    .order_by(AssetDiagnosis.created_at.desc(), AssetDiagnosis.id.desc())
                                    .offset(keep_n)))
    if keep_days > 0:
        cutoff = now - dt.timedelta(days=keep_days)
        old += list(session.scalars(select(AssetDiagnosis.id).where(full, AssetDiagnosis.created_at < cutoff)))
    trimmed = 0
    if old:
        if session.get(AssetBaseline, asset_id) is None:
            keep = {r.id for r in first_diagnoses(session, asset_id, AUTO_N)}
            old = [i for i in old if i not in keep]
        ids = sorted(set(old))
        if ids:
            trimmed = _rowcount(session.execute(update(AssetDiagnosis).where(AssetDiagnosis.id.in_(ids)).values(
                verdict={}, key_features={}, signature=None)))
    deleted = 0
    if settings.history_summary_days > 0:
        cutoff = now - dt.timedelta(days=float(settings.history_summary_days))
        deleted = _rowcount(session.execute(delete(AssetDiagnosis).where(
            AssetDiagnosis.asset_id == asset_id, AssetDiagnosis.created_at < cutoff)))
    max_rows = int(getattr(settings, "history_max_rows", 0) or 0)
    if max_rows > 0:
        beyond = list(session.scalars(select(AssetDiagnosis.id).where(AssetDiagnosis.asset_id == asset_id)
                                      .order_by(AssetDiagnosis.created_at.desc(), AssetDiagnosis.id.desc())
                                      .offset(max_rows)))
        if beyond:
            deleted += _rowcount(session.execute(delete(AssetDiagnosis).where(AssetDiagnosis.id.in_(beyond))))
    return trimmed, deleted


def _aware(t: Any) -> dt.datetime:
    """``t`` as UTC-aware (an aggregate over a ``UTCDateTime`` column comes back naive; SQLite may give text)."""
    if isinstance(t, str):
        t = dt.datetime.fromisoformat(t)
    return t.replace(tzinfo=dt.UTC) if t.tzinfo is None else t.astimezone(dt.UTC)


def _rowcount(result: Any) -> int:
    """Rows an UPDATE/DELETE touched (a ``CursorResult``'s ``rowcount``)."""
    return int(getattr(result, "rowcount", 0) or 0)


def history_sizes(session: Session) -> list[tuple[str, int, int, int]]:
    """``(asset_id, stored bytes, full diagnoses, summaries)`` per asset: the bytes are the length of the
    JSON the rows hold (verdict, key features, signature, change), the bulk of what an asset's history uses
    on disk (for the metrics)."""
    def size(col: Any) -> Any:
        return func.coalesce(func.length(cast(col, Text)), 0)

    q = (select(AssetDiagnosis.asset_id,
                func.sum(size(AssetDiagnosis.verdict) + size(AssetDiagnosis.key_features)
                         + size(AssetDiagnosis.signature) + size(AssetDiagnosis.change)),
                func.count(AssetDiagnosis.signature), func.count())
         .group_by(AssetDiagnosis.asset_id))
    return [(a, int(b or 0), int(n_full), int(n) - int(n_full)) for a, b, n_full, n in session.execute(q)]


def database_problem(state: AppState) -> str | None:
    """``None`` when the database reads a real table and takes a write (the health probe row), else what
    failed, in words (``SELECT 1`` alone answers from a truncated file or a full disk)."""
    try:
        with state.sessions.begin() as s:
            s.execute(select(Job.id).limit(1)).all()
            s.execute(select(AssetDiagnosis.id).order_by(AssetDiagnosis.id.desc()).limit(1)).all()
            s.merge(ServiceProbe(name="health", written_at=utcnow()))
    except Exception as exc:  # noqa: BLE001 - reported, not raised
        return f"database: cannot read and write ({database_error_text(exc)})"
    return None


def database_error_text(exc: BaseException) -> str:
    """What a database error means for the user, with the driver's own message (no SQL, no parameters)."""
    orig = getattr(exc, "orig", None) or exc
    msg = str(orig).splitlines()[0] if str(orig) else type(orig).__name__
    low = msg.lower()
    if "full" in low:
        return f"the data disk is full: {msg}; free space on it"
    if "not a database" in low or "malformed" in low or "disk i/o" in low:
        return f"the database file is damaged or unreadable: {msg}; restore it from a backup"
    if "locked" in low or "busy" in low:
        return f"the database is busy: {msg}; retry in a moment"
    return msg


def disk_problem(settings: Any) -> str | None:
    """``None`` unless the disk holding ``data_dir`` has less than ``min_free_disk_mb`` MiB free."""
    import shutil

    limit = int(settings.min_free_disk_mb)
    if limit <= 0:
        return None
    try:
        usage = shutil.disk_usage(settings.data_dir)
    except OSError as exc:
        return f"data disk: cannot be read ({exc.strerror or exc})"
    free_mb = usage.free / 2**20
    if free_mb < limit:
        return (f"data disk nearly full: {free_mb:.0f} MiB free of {usage.total / 2**20:.0f} MiB "
                f"(below ROTORDIAG_MIN_FREE_DISK_MB = {limit}); free space on it")
    return None


def asset_history(session: Session, asset_id: str, limit: int, since: dt.datetime | None) -> list[AssetDiagnosis]:
    """The latest ``limit`` diagnoses of ``asset_id`` (at or after ``since``) by recording time (the time
    stored when none was given), oldest first: a backfilled recording lands in its place."""
    q = select(AssetDiagnosis).where(AssetDiagnosis.asset_id == asset_id)
    if since is not None:
        if since.tzinfo is None:
            since = since.replace(tzinfo=dt.UTC)
        q = q.where(trend_time() >= since.astimezone(dt.UTC).replace(tzinfo=None))
    q = q.order_by(trend_time().desc(), AssetDiagnosis.id.desc()).limit(limit)
    rows = list(session.scalars(q))
    rows.reverse()
    return rows


def history_dicts(rows: list[AssetDiagnosis]) -> list[dict[str, Any]]:
    """Stored diagnoses (:func:`asset_history`) as the plain dicts of :mod:`rotordiag.models.report`'s trend:
    time (UTC, to the minute), severity, Δ and its interval, speed and the verdict's status."""
    return [{"created_at": r.created_at.strftime("%Y-%m-%d %H:%M"), "severity": r.severity,
             "misalignment": r.misalignment, "misalignment_low": r.misalignment_low,
             "misalignment_high": r.misalignment_high, "speed_rpm": r.speed_rpm,
             "status": (r.verdict or {}).get("status")} for r in rows]


def get_diagnosis(session: Session, asset_id: str, diagnosis_id: int) -> AssetDiagnosis | None:
    """The stored diagnosis ``diagnosis_id`` of ``asset_id`` (None when there is none)."""
    row = session.get(AssetDiagnosis, diagnosis_id)
    return row if row is not None and row.asset_id == asset_id else None


def first_diagnoses(session: Session, asset_id: str, limit: int) -> list[AssetDiagnosis]:
    """The oldest ``limit`` diagnoses of ``asset_id`` that carry a signature, oldest first."""
    q = (select(AssetDiagnosis).where(AssetDiagnosis.asset_id == asset_id, AssetDiagnosis.signature.is_not(None))
         .order_by(AssetDiagnosis.created_at, AssetDiagnosis.id).limit(limit))
    return list(session.scalars(q))


def get_baseline(session: Session, asset_id: str, *, lock: bool = False) -> AssetBaseline | None:
    """The asset's baseline row; ``lock``: held until the transaction ends (PostgreSQL ``FOR UPDATE``; SQLite
    serialises writers itself), so a read-modify-write of the baseline cannot lose a concurrent one."""
    if lock:
        return session.scalars(select(AssetBaseline).where(AssetBaseline.asset_id == asset_id)
                               .with_for_update()).first()
    return session.get(AssetBaseline, asset_id)


def baseline_recordings(session: Session, asset_id: str) -> list[AssetBaselineRecording]:
    """The recordings the asset's baseline is made of, in the order they were added (empty: no baseline, or one
    set before v0008 whose recordings' signatures were no longer kept)."""
    q = (select(AssetBaselineRecording).where(AssetBaselineRecording.asset_id == asset_id)
         .order_by(AssetBaselineRecording.added_at, AssetBaselineRecording.diagnosis_id))
    return list(session.scalars(q))


#: the columns of a baseline that a replacement writes (the asset id stays)
_BASELINE_VALUES = ("source", "diagnosis_ids", "recorded_at", "speed_rpm", "model_version", "signature", "repeatability")


def replace_baseline(session: Session, row: AssetBaseline, recordings: list[AssetBaselineRecording]) -> AssetBaseline:
    """In ``session``'s transaction: ``row`` becomes the asset's baseline and ``recordings`` what it is made of,
    replacing any previous baseline and its recordings. An existing baseline row is updated in place (not deleted
    and inserted again), so a transaction waiting on its lock (:func:`get_baseline` ``lock``) reads the new one."""
    for m in baseline_recordings(session, row.asset_id):
        session.delete(m)
    old = session.get(AssetBaseline, row.asset_id)
    if old is None:
        session.add(row)
    else:
        for name in _BASELINE_VALUES:
            setattr(old, name, getattr(row, name))
        old.created_at = utcnow()
        row = old
    session.flush()
    session.add_all(recordings)
    return row


def put_baseline(state: AppState, row: AssetBaseline,
                 recordings: list[AssetBaselineRecording] | None = None) -> AssetBaseline:
    """Store ``row`` as the asset's baseline and ``recordings`` as what it is made of, replacing any previous
    baseline and its recordings, in one transaction; returns the stored row."""
    with state.sessions.begin() as s:
        return replace_baseline(s, row, list(recordings or []))


def delete_baseline(state: AppState, asset_id: str) -> bool:
    """Remove the asset's baseline and its recordings' rows; False when it had none."""
    with state.sessions.begin() as s:
        old = s.get(AssetBaseline, asset_id)
        if old is None:
            return False
        s.delete(old)
        s.execute(delete(AssetBaselineRecording).where(AssetBaselineRecording.asset_id == asset_id))
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
    last = (select(AssetDiagnosis.asset_id, func.max(AssetDiagnosis.id).label("id"))
            .where(AssetDiagnosis.change.is_not(None)).group_by(AssetDiagnosis.asset_id).subquery())
    q = select(AssetDiagnosis).join(last, AssetDiagnosis.id == last.c.id)
    return [(r.asset_id, r.change or {}) for r in session.scalars(q)]


def get_hierarchy(session: Session, asset_id: str) -> dict[str, str | None]:
    """Where the asset sits: ``site``, ``unit``, ``train`` (None where not set)."""
    row = session.get(AssetSettings, asset_id)
    return {k: getattr(row, k) if row is not None else None for k in ("site", "unit", "train")}


def put_hierarchy(state: AppState, asset_id: str, place: dict[str, str | None]) -> None:
    """Set the asset's site, unit and train (each None clears it)."""
    with state.sessions.begin() as s:
        row = s.get(AssetSettings, asset_id)
        if row is None:
            row = AssetSettings(asset_id=asset_id, thresholds={})
            s.add(row)
        row.site, row.unit, row.train = place.get("site"), place.get("unit"), place.get("train")


def list_assets(session: Session, site: str | None = None) -> list[dict[str, Any]]:
    """Every asset with a stored diagnosis or settings: its place, stored diagnoses and latest trend time,
    ordered by site, unit, train and id (those without a place last); only ``site``'s when given."""
    counts = {a: (int(n), t) for a, n, t in session.execute(
        select(AssetDiagnosis.asset_id, func.count(), func.max(trend_time())).group_by(AssetDiagnosis.asset_id))}
    places = {r.asset_id: r for r in session.scalars(select(AssetSettings))}
    out = []
    for a in sorted(set(counts) | set(places)):
        p = places.get(a)
        n, t = counts.get(a, (0, None))
        row = {"asset_id": a, "site": getattr(p, "site", None), "unit": getattr(p, "unit", None),
               "train": getattr(p, "train", None), "diagnoses": n, "latest": _aware(t) if t is not None else None}
        if site is None or row["site"] == site:
            out.append(row)
    out.sort(key=lambda r: (r["site"] is None, r["site"] or "", r["unit"] or "", r["train"] or "", r["asset_id"]))
    return out
