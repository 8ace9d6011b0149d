"""Job manager: jobs are rows in the database, run in a small thread pool, fan out on Dask.

A job's row is the source of truth. Whatever happens to the process, a job is
in one of ``queued``, ``running``, ``succeeded``, ``failed``, ``interrupted``.
At startup every ``queued``/``running`` row left by a previous process is
marked ``interrupted``; ``resume`` starts it again, and the work functions are
resumable (dataset generation completes only the missing samples of its HDF5
file; retraining reuses a finished dataset), so no finished work is lost.

The Dask client is created lazily on the first job: a connection to
``dask_scheduler_address`` when set, otherwise a ``distributed.LocalCluster``
with ``dask_local_workers`` single-threaded worker processes, kept for later
jobs and closed at shutdown.
"""
from __future__ import annotations

import logging
import threading
import traceback
import uuid
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from sqlalchemy import func, select, update
from sqlalchemy.orm import sessionmaker

from .core.config import Settings
from .core.db import Job, utcnow

log = logging.getLogger("rotordiag.service.jobs")

ACTIVE = ("queued", "running")
RESUMABLE = ("interrupted", "failed")
STATUSES = ("queued", "running", "succeeded", "failed", "interrupted")


class JobInterrupted(Exception):
    """Raised inside a job when the server is shutting down."""


class JobContext:
    """What a work function gets: settings, Dask client, model store, progress reporting."""

    def __init__(self, manager: JobManager, job_id: str) -> None:
        self._manager = manager
        self.job_id = job_id
        self.settings = manager.settings
        self.models = manager.models

    def client(self):
        """The shared ``distributed.Client`` (created on first use)."""
        return self._manager.client()

    def progress(self, fraction: float, stage: str | None = None, message: str | None = None) -> None:
        """Record progress (0-1); raises :class:`JobInterrupted` when the server is stopping."""
        if self._manager.stopping.is_set():
            raise JobInterrupted("server shutting down")
        values: dict[str, Any] = {"progress": float(min(max(fraction, 0.0), 1.0)), "updated_at": utcnow()}
        if stage is not None:
            values["stage"] = stage
        if message is not None:
            values["message"] = message
        with self._manager.sessions.begin() as s:
            s.execute(update(Job).where(Job.id == self.job_id).values(**values))

    @property
    def stopping(self) -> bool:
        return self._manager.stopping.is_set()


WorkFunction = Callable[[dict[str, Any], JobContext], dict[str, Any]]


class JobManager:
    """Create, run, resume and report jobs.

    Parameters
    ----------
    settings : Settings
    sessions : sessionmaker
        Session factory of the service database.
    models : service.inference.ModelStore
        Where retraining jobs register new model versions.
    """

    def __init__(self, settings: Settings, sessions: sessionmaker, models: Any) -> None:
        self.settings = settings
        self.sessions = sessions
        self.models = models
        self.stopping = threading.Event()
        self._executor = ThreadPoolExecutor(settings.job_threads, thread_name_prefix="rotordiag-job")
        self._client = None
        self._cluster = None
        self._client_lock = threading.Lock()
        self._work: dict[str, WorkFunction] = {}

    # -- registry of work functions ---------------------------------------------------------
    def register(self, kind: str, work: WorkFunction) -> None:
        """Declare the function that runs jobs of ``kind``."""
        self._work[kind] = work

    def _work_for(self, kind: str) -> WorkFunction:
        if kind not in self._work:
            from . import work  # registers the built-in kinds

            work.register_all(self)
        return self._work[kind]

    # -- lifecycle --------------------------------------------------------------------------
    def mark_interrupted(self) -> int:
        """Mark jobs a previous process left queued/running as ``interrupted``; return how many."""
        with self.sessions.begin() as s:
            res = s.execute(
                update(Job).where(Job.status.in_(ACTIVE)).values(
                    status="interrupted", message="the server stopped while this job was queued or running; "
                    "POST /jobs/{id}/resume continues it", updated_at=utcnow()))
            return res.rowcount or 0

    def shutdown(self) -> None:
        """Stop accepting work, interrupt running jobs, close the Dask client."""
        self.stopping.set()
        self._executor.shutdown(wait=False, cancel_futures=True)
        self.mark_interrupted()   # right away, in case the process is killed while we wait below
        self._close_client()      # makes running simulations fail fast
        # A job thread in a step that cannot be interrupted (a model fit) ends it first; it then records
        # its own outcome ("succeeded" when the step was the last one).
        self._executor.shutdown(wait=True)

    def client(self):
        """The Dask client shared by jobs, created on first use."""
        with self._client_lock:
            if self.stopping.is_set():
                raise JobInterrupted("server shutting down")
            if self._client is None:
                import logging as _logging

                from distributed import Client, LocalCluster

                address = self.settings.dask_scheduler_address
                if address:
                    log.info("connecting to Dask scheduler %s", address)
                    self._client = Client(address, timeout=30, set_as_default=False)
                else:
                    log.info("starting a local Dask cluster with %d worker process(es)",
                             self.settings.dask_local_workers)
                    self._cluster = LocalCluster(
                        n_workers=self.settings.dask_local_workers, threads_per_worker=1, processes=True,
                        dashboard_address=None, silence_logs=_logging.ERROR)
                    self._client = Client(self._cluster, set_as_default=False)
            return self._client

    def _close_client(self) -> None:
        with self._client_lock:
            client, cluster = self._client, self._cluster
            self._client = self._cluster = None
        for thing in (client, cluster):
            if thing is not None:
                try:
                    thing.close()
                except Exception:  # pragma: no cover - best effort at shutdown
                    log.exception("closing Dask %s", type(thing).__name__)

    # -- API ---------------------------------------------------------------------------------
    def submit(self, kind: str, params: dict[str, Any]) -> Job:
        """Store a new job and queue it."""
        self._work_for(kind)  # fail early on an unknown kind
        job = Job(id=str(uuid.uuid4()), kind=kind, status="queued", params=params, progress=0.0,
                  stage="queued", message="waiting for a job slot", attempts=0)
        with self.sessions.begin() as s:
            s.add(job)
        self._executor.submit(self._run, job.id)
        return job

    def resume(self, job_id: str) -> Job | None:
        """Queue an interrupted or failed job again; ``None`` when it does not exist.

        Raises
        ------
        ValueError
            When the job is not in a resumable state.
        """
        with self.sessions.begin() as s:
            job = s.get(Job, job_id)
            if job is None:
                return None
            if job.status not in RESUMABLE:
                raise ValueError(f"job {job_id} is {job.status}; only interrupted or failed jobs can be resumed")
            job.status, job.stage, job.message, job.error = "queued", "queued", "resumed; waiting for a job slot", None
        self._executor.submit(self._run, job_id)
        return self.get(job_id)

    def get(self, job_id: str) -> Job | None:
        with self.sessions() as s:
            return s.get(Job, job_id)

    def list(self, limit: int = 100, status: str | None = None) -> list[Job]:
        with self.sessions() as s:
            q = select(Job).order_by(Job.created_at.desc()).limit(limit)
            if status is not None:
                q = q.where(Job.status == status)
            return list(s.scalars(q))

    def counts(self) -> dict[str, int]:
        """Number of jobs per status (every status present, zero when none)."""
        with self.sessions() as s:
            rows = s.execute(select(Job.status, func.count()).group_by(Job.status)).all()
        out = {k: 0 for k in STATUSES}
        out.update({status: int(n) for status, n in rows})
        return out

    # -- execution ---------------------------------------------------------------------------
    def _run(self, job_id: str) -> None:
        if self.stopping.is_set():
            return
        with self.sessions.begin() as s:
            job = s.get(Job, job_id)
            if job is None or job.status != "queued":
                return
            job.status, job.stage, job.message = "running", "starting", "started"
            job.attempts += 1
            job.started_at = utcnow()
            kind, params = job.kind, dict(job.params)
        ctx = JobContext(self, job_id)
        try:
            result = self._work_for(kind)(params, ctx)
        except BaseException as exc:  # noqa: BLE001 - every outcome must land in the row
            if self.stopping.is_set() or isinstance(exc, JobInterrupted):
                status, error = "interrupted", None
                message = "interrupted by a server shutdown; POST /jobs/{id}/resume continues it"
            else:
                status, message = "failed", "failed"
                error = f"{type(exc).__name__}: {exc}"
                log.error("job %s (%s) failed:\n%s", job_id, kind, traceback.format_exc())
            with self.sessions.begin() as s:
                s.execute(update(Job).where(Job.id == job_id).values(
                    status=status, message=message, error=error, finished_at=utcnow(), updated_at=utcnow()))
            if not isinstance(exc, Exception):
                raise
            return
        with self.sessions.begin() as s:
            s.execute(update(Job).where(Job.id == job_id).values(
                status="succeeded", progress=1.0, stage="done", message="finished", result=result,
                finished_at=utcnow(), updated_at=utcnow()))
