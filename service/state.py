"""Everything the running app holds: settings, database, model store, job manager."""
from __future__ import annotations

import logging
from dataclasses import dataclass

from sqlalchemy.engine import Engine
from sqlalchemy.orm import sessionmaker

from .alarms import WebhookSender
from .core.config import Settings
from .core.db import init_db, make_engine
from .inference import ModelStore
from .jobs import JobManager
from .pool import DiagnosisPool

log = logging.getLogger("rotordiag.service")


@dataclass
class AppState:
    """Resources created at startup and released at shutdown."""

    settings: Settings
    engine: Engine
    sessions: sessionmaker
    models: ModelStore
    jobs: JobManager
    diagnosis_limiter: object = None   # anyio.CapacityLimiter, created on the event loop at first use
    pool: DiagnosisPool | None = None  # diagnosis worker processes (settings.diagnosis_workers > 0)
    webhooks: WebhookSender | None = None  # sends alarm events to webhooks (service.alarms)

    @classmethod
    def start(cls, settings: Settings) -> AppState:
        """Create the data directory, migrate the database, open the registry, start claiming jobs."""
        _configure_logging(settings.log_level)
        settings.data_dir.mkdir(parents=True, exist_ok=True)
        settings.datasets_dir.mkdir(parents=True, exist_ok=True)
        _ = settings.effective_api_key  # generate + log the development key once, at startup
        engine = make_engine(settings.effective_database_url)
        sessions = init_db(engine)
        models = ModelStore.open(settings)
        jobs = JobManager(settings, sessions, models)
        jobs.start()   # claims queued jobs and those whose holder died (service.jobs)
        pool = None
        if settings.effective_diagnosis_workers > 0:
            pool = DiagnosisPool(settings.registry_dir, settings.effective_diagnosis_workers,
                                 version=models.active_version(),
                                 memory_bytes=settings.diagnosis_worker_memory_mb * 2**20,
                                 timeout_s=settings.diagnosis_timeout_s)
        webhooks = WebhookSender(sessions, settings, jobs.replica)
        webhooks.start()
        log.info("rotordiag service ready: replica=%s data_dir=%s database=%s registry=%s",
                 settings.effective_replica_id, settings.data_dir.resolve(),
                 engine.url.render_as_string(hide_password=True),
                 settings.registry_dir.resolve())
        return cls(settings=settings, engine=engine, sessions=sessions, models=models, jobs=jobs, pool=pool,
                   webhooks=webhooks)

    def stop(self) -> None:
        """Stop the job threads (running jobs are marked interrupted; at most ``shutdown_timeout_s`` + 10 s),
        the diagnosis workers (at most 8 s), the webhook sender (at most 5 s; what it has not sent stays stored
        and is sent after the next start), and close the engine."""
        if self.webhooks is not None:
            self.webhooks.stop()
        self.jobs.shutdown()
        if self.pool is not None:
            self.pool.shutdown(timeout_s=5.0)
        self.engine.dispose()


def _configure_logging(level: str) -> None:
    """Give the ``rotordiag`` loggers a stderr handler when the host (uvicorn, tests) has not."""
    logger = logging.getLogger("rotordiag")
    logger.setLevel(level.upper() if level.upper() in logging.getLevelNamesMapping() else logging.INFO)
    if not logger.handlers and not logging.getLogger().handlers:
        handler = logging.StreamHandler()
        handler.setFormatter(logging.Formatter("%(levelname)s:     %(name)s: %(message)s"))
        logger.addHandler(handler)
