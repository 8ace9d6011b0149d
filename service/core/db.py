"""Database engine, session factory and the tables: jobs, asset diagnoses, asset baselines, asset
alarm settings and the health probe (SQLAlchemy 2). One URL selects the backend: SQLite (the embedded
default) or PostgreSQL (``postgresql://…``, driven by psycopg 3). :func:`init_db` brings the schema to
the newest version with Alembic (``service/migrations``), adopting a database made before Alembic."""
from __future__ import annotations

import contextlib
import datetime as dt
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from sqlalchemy import (
    JSON,
    Boolean,
    DateTime,
    Float,
    Index,
    Integer,
    String,
    Text,
    TypeDecorator,
    create_engine,
    event,
    text,
)
from sqlalchemy.engine import Connection, Engine
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
    # the replica running the job and until when its hold is good (issue 47): a running job whose lease
    # has run out is claimed again by any replica (service.jobs)
    lease_owner: Mapped[str | None] = mapped_column(String(128), nullable=True)
    lease_expires_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime(), nullable=True)

    __table_args__ = (Index("ix_jobs_status_lease", "status", "lease_expires_at"),)


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
    # when the recording was made, as the upload gave it (null: not given; the trend then uses created_at), the
    # operating state it was made at (load_mw, field_current_a, temperatures, ...) and a note ("aligned on ...")
    recorded_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime(), nullable=True)
    tags: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    note: Mapped[str | None] = mapped_column(Text, nullable=True)


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


class AssetBaselineRecording(Base):
    """One recording an asset's baseline is made of (v0008): its own signature, kept whatever the history's
    retention does to the diagnosis, so the baseline's average and its repeatability thresholds can be
    recomputed when a recording is added or removed (``service.baseline``)."""

    __tablename__ = "asset_baseline_recordings"

    asset_id: Mapped[str] = mapped_column(String(128), primary_key=True)
    diagnosis_id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=False)
    added_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow)
    recorded_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime(), nullable=True)
    speed_rpm: Mapped[float | None] = mapped_column(Float, nullable=True)
    model_version: Mapped[str] = mapped_column(String(128))
    signature: Mapped[dict[str, Any]] = mapped_column(JSON)


class AssetSettings(Base):
    """Per-asset alarm thresholds on the change (overrides of ``models.change``'s shipped ones) and probe
    configuration (``service.parsing.with_probe_config``)."""

    __tablename__ = "asset_settings"

    asset_id: Mapped[str] = mapped_column(String(128), primary_key=True)
    thresholds: Mapped[dict[str, Any]] = mapped_column(JSON, default=dict)
    updated_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow, onupdate=utcnow)
    # the asset's probe configuration (PUT /assets/{id}/probes): reader options every upload to it uses
    probes: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    # alert/danger setpoints on overall pk-pk, 1X, 2X and Δ (PUT /assets/{id}/setpoints; service.alarms)
    setpoints: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    # where the asset sits: site → unit → train (PUT /assets/{id}/hierarchy)
    site: Mapped[str | None] = mapped_column(String(128), nullable=True)
    unit: Mapped[str | None] = mapped_column(String(128), nullable=True)
    train: Mapped[str | None] = mapped_column(String(128), nullable=True)


class AssetStartup(Base):
    """A start-up or coast-down of an asset, as evidence (``service.startups``): what ``models.checks.startup``
    read of it (``evidence``: 1X criticals, coupling-end centreline rise) and its summary (speed range, peaks,
    notes); ``is_baseline`` marks the asset's baseline start-up (the latest such row). No waveform is kept."""

    __tablename__ = "asset_startups"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    asset_id: Mapped[str] = mapped_column(String(128))
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow)
    recorded_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime(), nullable=True)
    is_baseline: Mapped[bool] = mapped_column(Boolean)
    evidence: Mapped[dict[str, Any]] = mapped_column(JSON)
    summary: Mapped[dict[str, Any]] = mapped_column(JSON)
    note: Mapped[str | None] = mapped_column(Text, nullable=True)

    __table_args__ = (Index("ix_asset_startups_asset_id", "asset_id", "id"),)


class AlarmEvent(Base):
    """A raised or cleared alarm of an asset (a setpoint level or the baseline-change alarm), with its
    acknowledgement (``service.alarms``)."""

    __tablename__ = "alarm_events"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    asset_id: Mapped[str] = mapped_column(String(128))
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow)
    quantity: Mapped[str] = mapped_column(String(32))        # overall_um_pp | x1_um_pp | x2_um_pp | misalignment | change
    level: Mapped[str] = mapped_column(String(16))           # normal | alert | danger
    event: Mapped[str] = mapped_column(String(16))           # raised | cleared
    value: Mapped[float | None] = mapped_column(Float, nullable=True)
    setpoint: Mapped[float | None] = mapped_column(Float, nullable=True)
    diagnosis_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    message: Mapped[str] = mapped_column(Text, default="")
    acked_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime(), nullable=True)
    ack_note: Mapped[str | None] = mapped_column(Text, nullable=True)

    __table_args__ = (Index("ix_alarm_events_asset_quantity", "asset_id", "quantity", "id"),)


class Webhook(Base):
    """A receiver of alarm events (``POST /webhooks``): every event of ``asset_id`` (all assets when null)
    is POSTed to ``url``, signed with ``secret`` (``service.alarms``)."""

    __tablename__ = "webhooks"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    url: Mapped[str] = mapped_column(Text)
    secret: Mapped[str] = mapped_column(String(256))
    asset_id: Mapped[str | None] = mapped_column(String(128), nullable=True)
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow)


class WebhookDelivery(Base):
    """One event to send to one webhook and how far its delivery got: ``pending`` (waiting, or retrying at
    ``next_attempt_at``), ``sending`` (claimed by ``claimed_by`` until ``claim_expires_at``), ``delivered``,
    ``failed`` (attempts used up) or ``dropped`` (the queue was full)."""

    __tablename__ = "webhook_deliveries"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    webhook_id: Mapped[int] = mapped_column(Integer)
    event_id: Mapped[int | None] = mapped_column(Integer, nullable=True)   # null: a test delivery
    payload: Mapped[dict[str, Any]] = mapped_column(JSON)
    status: Mapped[str] = mapped_column(String(16))
    attempts: Mapped[int] = mapped_column(Integer, default=0)
    last_error: Mapped[str | None] = mapped_column(Text, nullable=True)
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow)
    next_attempt_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow)
    claimed_by: Mapped[str | None] = mapped_column(String(128), nullable=True)
    claim_expires_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime(), nullable=True)
    delivered_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime(), nullable=True)

    __table_args__ = (Index("ix_webhook_deliveries_status_next", "status", "next_attempt_at"),)


class ServiceProbe(Base):
    """One row per probe name that ``GET /health`` rewrites: proof that the database takes a real write."""

    __tablename__ = "service_probe"

    name: Mapped[str] = mapped_column(String(32), primary_key=True)
    written_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utcnow)


def normalize_url(url: str) -> str:
    """``url`` with PostgreSQL spelled for psycopg 3 (``postgres://`` and ``postgresql://`` would select
    psycopg2, which is not a dependency); other URLs unchanged."""
    for prefix in ("postgres://", "postgresql://"):
        if url.startswith(prefix):
            return "postgresql+psycopg://" + url[len(prefix):]
    return url


def make_engine(url: str) -> Engine:
    """Create the engine; SQLite gets WAL mode and cross-thread use (the app runs sync routes in threads)."""
    url = normalize_url(url)
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
        engine = create_engine(url, pool_pre_ping=True, pool_size=10, max_overflow=10)
    return engine


def init_db(engine: Engine) -> sessionmaker:
    """Migrate the database to the newest schema version, return a session factory."""
    migrate(engine)
    return sessionmaker(engine, expire_on_commit=False)


#: Alembic's folder (env.py, versions/) inside the installed package.
MIGRATIONS_DIR = Path(__file__).resolve().parents[1] / "migrations"
#: PostgreSQL advisory-lock key held while one replica migrates (the others wait, then find nothing to do).
_MIGRATION_LOCK_KEY = 4747_0001


def _alembic_config(connection: Connection | None = None):
    from alembic.config import Config

    cfg = Config()
    cfg.set_main_option("script_location", str(MIGRATIONS_DIR))
    cfg.attributes["connection"] = connection
    return cfg


def head_revision() -> str:
    """The newest schema version the code knows."""
    from alembic.script import ScriptDirectory

    head = ScriptDirectory.from_config(_alembic_config()).get_current_head()
    assert head is not None
    return head


def current_revision(engine: Engine) -> str | None:
    """The schema version the database is at (None: never migrated, e.g. a pre-Alembic database)."""
    with engine.connect() as conn:
        return _current(conn)


def migrate(engine: Engine, revision: str = "head") -> None:
    """Upgrade (or, for an older ``revision``, downgrade) the schema with Alembic.

    Several replicas may start at once: on PostgreSQL the first holds an advisory lock while it
    migrates and the others wait for it, then find the schema current; on SQLite a lock file
    next to the database does the same for processes on one host.
    """
    from alembic import command

    with _migration_lock(engine), engine.begin() as conn:
        if conn.dialect.name == "postgresql":
            conn.execute(text("SELECT pg_advisory_xact_lock(:k)"), {"k": _MIGRATION_LOCK_KEY})
        cfg = _alembic_config(conn)
        have = _current(conn)
        if revision == "head" or have is None or _is_ahead(revision, have):
            command.upgrade(cfg, revision)
        else:
            command.downgrade(cfg, revision)


def _current(conn: Connection) -> str | None:
    from alembic.runtime.migration import MigrationContext

    return MigrationContext.configure(conn).get_current_revision()


def _is_ahead(target: str, have: str) -> bool:
    """True when ``target`` comes after ``have`` in the version chain."""
    from alembic.script import ScriptDirectory

    script = ScriptDirectory.from_config(_alembic_config())
    return any(rev.revision == have for rev in script.iterate_revisions(target, "base") if rev.revision != target)


@contextlib.contextmanager
def _migration_lock(engine: Engine) -> Iterator[None]:
    database = engine.url.database if engine.url.get_backend_name() == "sqlite" else None
    if not database or database == ":memory:":
        yield
        return
    import fcntl

    with open(f"{database}.migrate-lock", "a+b") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


class CopyError(RuntimeError):
    """The store cannot be copied (the target already holds rows, or the source is newer than the code)."""


def copy_store(source: Engine, target: Engine, batch_rows: int = 500) -> dict[str, int]:
    """Copy every row of a service database (e.g. the SQLite file) into another (e.g. PostgreSQL).

    Both are migrated to the newest schema first (the source in place, as the server would at its
    start); the target must hold no rows. Rows keep their ids; on PostgreSQL the id sequence of
    ``asset_diagnoses`` is moved past the largest copied id. One transaction on the target: it
    has all the rows or none. Returns the rows copied per table.
    """
    from sqlalchemy import func, select

    migrate(source)
    migrate(target)
    tables = Base.metadata.sorted_tables
    with target.connect() as tconn:
        busy = {t.name: tconn.execute(select(func.count()).select_from(t)).scalar_one() for t in tables}
    busy = {k: v for k, v in busy.items() if v}
    if busy:
        raise CopyError(f"the target database already holds rows ({busy}); copy into an empty database")
    copied: dict[str, int] = {}
    with source.connect() as sconn, target.begin() as tconn:
        for table in tables:
            n = 0
            result = sconn.execution_options(stream_results=True).execute(select(table))
            while rows := result.fetchmany(batch_rows):
                tconn.execute(table.insert(), [dict(r._mapping) for r in rows])
                n += len(rows)
            copied[table.name] = n
        if tconn.dialect.name == "postgresql":
            tconn.execute(text("SELECT setval(pg_get_serial_sequence('asset_diagnoses', 'id'), "
                               "COALESCE((SELECT MAX(id) FROM asset_diagnoses), 0) + 1, false)"))
    return copied
