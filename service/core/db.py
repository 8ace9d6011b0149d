"""Database engine, session factory and the tables: jobs, asset diagnoses, asset baselines, asset
alarm settings and the health probe (SQLAlchemy 2); :func:`init_db` adds columns that an older database lacks."""
from __future__ import annotations

import datetime as dt
from typing import Any

from sqlalchemy import JSON, Boolean, DateTime, Float, Integer, String, Text, TypeDecorator, create_engine, event
from sqlalchemy.engine import Engine
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, sessionmaker


def utcnow() -> dt.datetime:
    """Timezone-aware current UTC time."""
    return dt.datetime.now(dt.UTC)


class UTCDateTime(TypeDecorator):
    """DateTime stored naive-UTC (SQLite has no time zones) and returned timezone-aware UTC."""

    impl = DateTime
    cache_ok = True

    def process_bind_param(self, value: dt.datetime | None, dialect) -> dt.datetime | None:
        if value is not None and value.tzinfo is not None:
            value = value.astimezone(dt.UTC).replace(tzinfo=None)
        return value

    def process_result_value(self, value: dt.datetime | None, dialect) -> dt.datetime | None:
        if value is not None and value.tzinfo is None:
            value = value.replace(tzinfo=dt.UTC)
        return value


class Base(DeclarativeBase):
    """Declarative base of the service tables."""


class Job(Base):
    """A dataset-generation or retraining job; survives restarts (see ``service.jobs``)."""

    __tablename__ = "jobs"

    id: Mapped[str] = mapped_column(String(36), primary_key=True)
    kind: Mapped[str] = mapped_column(String(16), index=True)            # "dataset" | "retrain"
    status: Mapped[str] = mapped_column(String(16), index=True)          # see service.jobs.JobStatus
    params: Mapped[dict[str, Any]] = mapped_column(JSON)
    progress: Mapped[float] = mapped_column(Float, default=0.0)           # 0..1
    stage: Mapped[str] = mapped_column(String(64), default="")
    message: Mapped[str] = mapped_column(Text, default="")
    result: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    error: Mapped[str | None] = mapped_column(Text, nullable=True)
    attempts: Mapped[int] = mapped_column(Integer, default=0)
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow)
    started_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime(), nullable=True)
    finished_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime(), nullable=True)
    updated_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow, onupdate=utcnow)


class AssetDiagnosis(Base):
    """One stored diagnosis of an asset (a machine train), for the trend."""

    __tablename__ = "asset_diagnoses"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    asset_id: Mapped[str] = mapped_column(String(128), index=True)
    plant: Mapped[str | None] = mapped_column(String(128), nullable=True)
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow, index=True)
    model_version: Mapped[str] = mapped_column(String(128))
    severity: Mapped[str] = mapped_column(String(32))
    misalignment: Mapped[float | None] = mapped_column(Float, nullable=True)
    misalignment_low: Mapped[float | None] = mapped_column(Float, nullable=True)
    misalignment_high: Mapped[float | None] = mapped_column(Float, nullable=True)
    speed_rpm: Mapped[float | None] = mapped_column(Float, nullable=True)
    ood: Mapped[bool | None] = mapped_column(Boolean, nullable=True)
    verdict: Mapped[dict[str, Any]] = mapped_column(JSON)             # the full verdict as returned
    key_features: Mapped[dict[str, Any]] = mapped_column(JSON)
    # features.signature of the recording (what a baseline is made of); None for rows stored before issue 17
    signature: Mapped[dict[str, Any] | None] = mapped_column(JSON(none_as_null=True), nullable=True)
    # the comparison with the asset's baseline (models.change.compare, without its evidence) and the alarm
    # state it gave: True changed, False compared and unchanged, None not compared
    change: Mapped[dict[str, Any] | None] = mapped_column(JSON(none_as_null=True), nullable=True)
    alarm: Mapped[bool | None] = mapped_column(Boolean, nullable=True)


class AssetBaseline(Base):
    """An asset's known-good reference state (issue 17): one per asset, replaced by a new one."""

    __tablename__ = "asset_baselines"

    asset_id: Mapped[str] = mapped_column(String(128), primary_key=True)
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow)
    source: Mapped[str] = mapped_column(String(16))                    # "recording" | "diagnosis" | "auto"
    diagnosis_ids: Mapped[list[int]] = mapped_column(JSON)             # the stored diagnoses it was made of
    recorded_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime(), nullable=True)  # of the (last) recording
    speed_rpm: Mapped[float | None] = mapped_column(Float, nullable=True)
    model_version: Mapped[str] = mapped_column(String(128))
    signature: Mapped[dict[str, Any]] = mapped_column(JSON)
    # the asset's own thresholds from the repeatability of the recordings it was made of (models.change.
    # repeatability_thresholds); null for a baseline of fewer than models.change.REPEAT_MIN recordings
    repeatability: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)


class AssetSettings(Base):
    """Per-asset alarm thresholds on the change (overrides of ``models.change``'s shipped ones) and probe
    configuration (``service.parsing.with_probe_config``)."""

    __tablename__ = "asset_settings"

    asset_id: Mapped[str] = mapped_column(String(128), primary_key=True)
    thresholds: Mapped[dict[str, Any]] = mapped_column(JSON, default=dict)
    updated_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow, onupdate=utcnow)
    # the asset's probe configuration (PUT /assets/{id}/probes): reader options every upload to it uses
    probes: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)


class ServiceProbe(Base):
    """One row per probe name that ``GET /health`` rewrites: proof that the database takes a real write."""

    __tablename__ = "service_probe"

    name: Mapped[str] = mapped_column(String(32), primary_key=True)
    written_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow)


def make_engine(url: str) -> Engine:
    """Create the engine; SQLite gets WAL mode and cross-thread use (the app runs sync routes in threads)."""
    if url.startswith("sqlite"):
        engine = create_engine(url, connect_args={"check_same_thread": False, "timeout": 30})

        @event.listens_for(engine, "connect")
        def _sqlite_pragmas(dbapi_connection, _record):  # pragma: no cover - trivial
            cur = dbapi_connection.cursor()
            cur.execute("PRAGMA journal_mode=WAL")
            cur.execute("PRAGMA synchronous=NORMAL")
            cur.execute("PRAGMA foreign_keys=ON")
            cur.close()
    else:
        engine = create_engine(url, pool_pre_ping=True)
    return engine


def init_db(engine: Engine) -> sessionmaker:
    """Create missing tables, add missing (nullable) columns to existing ones, return a session factory."""
    Base.metadata.create_all(engine)
    add_missing_columns(engine)
    return sessionmaker(engine, expire_on_commit=False)


def add_missing_columns(engine: Engine) -> list[str]:
    """Schema migration for databases made by an older version: ``ALTER TABLE … ADD COLUMN`` for every
    nullable column of the models that a table lacks (new columns are always nullable). Returns
    ``table.column`` of each column added."""
    from sqlalchemy import inspect, text

    added = []
    insp = inspect(engine)
    with engine.begin() as conn:
        for table in Base.metadata.sorted_tables:
            have = {c["name"] for c in insp.get_columns(table.name)}
            for col in table.columns:
                if col.name in have:
                    continue
                if not col.nullable:
                    raise RuntimeError(f"database table {table.name} lacks the required column {col.name}; "
                                       "it cannot be added in place")
                ddl = col.type.compile(dialect=engine.dialect)
                conn.execute(text(f'ALTER TABLE "{table.name}" ADD COLUMN "{col.name}" {ddl}'))
                added.append(f"{table.name}.{col.name}")
    return added
