"""Job manager: jobs are rows in the database, claimed by any replica, run in a small thread pool,
fanned out on Dask.

A job's row is the source of truth. Whatever happens to a process, a job is
in one of ``queued``, ``running``, ``succeeded``, ``failed``, ``interrupted``.

Several replicas (API processes on one or more hosts) share the database and
none owns a job: each replica's claim loop takes a ``queued`` job, or a
``running`` one whose lease has run out, in one statement (``UPDATE … WHERE id =
(SELECT … FOR UPDATE SKIP LOCKED)`` on PostgreSQL; on SQLite the same statement
runs under the database's single-writer lock). The claim writes the replica's id
(``lease_owner``), a lease end (``lease_expires_at``, now + ``job_lease_s``) and
one more attempt. The holder renews the lease every third of ``job_lease_s`` and
with each progress report; every write it makes names its own id and attempt, so
a holder that lost its lease (stalled past the lease, then woke up) changes
nothing and stops. When a holder dies (SIGKILL, a lost host), another replica
claims the job once the lease has run out, at most ``job_lease_s +
job_poll_s`` later, and runs it again: the work functions are resumable
(dataset generation completes only the missing samples of its HDF5 file;
retraining reuses a finished dataset), so finished work is not lost. Lease ends
are written with the replicas' own clocks, which must agree to well within
``job_lease_s`` (NTP).

A graceful shutdown marks the jobs this replica holds ``interrupted``;
``resume`` queues them again for any replica.

The Dask client is created lazily on the first job: a connection to
``dask_scheduler_address`` when set, otherwise a ``distributed.LocalCluster``
with ``dask_local_workers`` single-threaded worker processes, kept for later
jobs and closed at shutdown.
"""
from __future__ import annotations

import datetime as dt
import logging
import threading
import time
import traceback
import uuid
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from sqlalchemy import and_, case, func, literal, or_, select, update
from sqlalchemy.orm import sessionmaker

from .core.config import Settings
from .core.db import Job, utcnow

log = logging.getLogger("rotordiag.service.jobs")

ACTIVE = ("queued", "running")
RESUMABLE = ("interrupted", "failed")
STATUSES = ("queued", "running", "succeeded", "failed", "interrupted")


class JobInterrupted(Exception):
    """Raised inside a job when the server is shutting down."""


class JobLost(JobInterrupted):
    """Raised inside a job whose lease this replica no longer holds (another replica took it over)."""


class JobContext:
    """What a work function gets: settings, Dask client, model store, progress reporting."""

    def __init__(self, manager: JobManager, job_id: str, attempt: int) -> None:
        self._manager = manager
        self.job_id = job_id
        self.attempt = attempt
        self.settings = manager.settings
        self.models = manager.models

    def client(self):
        """The shared ``distributed.Client`` (created on first use)."""
        return self._manager.client()

    def progress(self, fraction: float, stage: str | None = None, message: str | None = None) -> None:
        """Record progress (0-1) and renew the lease; raises :class:`JobInterrupted` when the server is
        stopping and :class:`JobLost` when another replica has taken the job over."""
        if self._manager.stopping.is_set():
            raise JobInterrupted("server shutting down")
        now = utcnow()
        values: dict[str, Any] = {"progress": float(min(max(fraction, 0.0), 1.0)), "updated_at": now,
                                  "lease_expires_at": now + self._manager.lease}
        if stage is not None:
            values["stage"] = stage
        if message is not None:
            values["message"] = message
        if not self._manager._write_held(self.job_id, self.attempt, values, running_only=True):
            raise JobLost(f"job {self.job_id}: this replica no longer holds its lease")

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
        self.replica = settings.effective_replica_id
        self.lease = dt.timedelta(seconds=settings.job_lease_s)
        self._held: dict[str, int] = {}          # job id -> attempt, of the jobs this replica runs
        self._held_lock = threading.Lock()
        self._wake = threading.Event()
        self._loop: threading.Thread | None = None
        self.takeovers = 0                       # jobs this replica claimed from a holder whose lease ran out

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
    def start(self) -> None:
        """Start the claim loop (claims queued and orphaned jobs, renews this replica's leases)."""
        if self._loop is None:
            self._loop = threading.Thread(target=self._claim_loop, name="rotordiag-job-claim", daemon=True)
            self._loop.start()

    def mark_interrupted(self) -> int:
        """Mark the jobs this replica holds ``interrupted`` (at shutdown); return how many."""
        with self.sessions.begin() as s:
            res = s.execute(
                update(Job).where(Job.status == "running", Job.lease_owner == self.replica).values(
                    status="interrupted", lease_expires_at=None,
                    message="the server stopped while this job was running; POST /jobs/{id}/resume continues it",
                    updated_at=utcnow()))
            return res.rowcount or 0

    def shutdown(self) -> None:
        """Stop claiming, interrupt the jobs this replica runs, close the Dask client."""
        self.stopping.set()
        self._wake.set()
        if self._loop is not None:
            self._loop.join(timeout=30)
        self._executor.shutdown(wait=False, cancel_futures=True)
        self.mark_interrupted()   # right away, in case the process is killed while we wait below
        self._close_client()      # makes running simulations fail fast
        # A job thread in a step that cannot be interrupted (a model fit) ends it first; it then records
        # its own outcome ("succeeded" when the step was the last one).
        self._executor.shutdown(wait=True)

    def held(self) -> int:
        """Number of jobs this replica is running."""
        with self._held_lock:
            return len(self._held)

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
        self._wake.set()   # this replica's claim loop looks at once; the others within job_poll_s
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
            job.lease_owner = job.lease_expires_at = None
        self._wake.set()
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

    # -- claiming ----------------------------------------------------------------------------
    def _claimable(self, now: dt.datetime):
        expired = or_(Job.lease_expires_at.is_(None), Job.lease_expires_at < now)
        return or_(Job.status == "queued", and_(Job.status == "running", expired))

    def claim(self) -> tuple[str, str, dict[str, Any], int] | None:
        """Claim the oldest queued job, or a running one whose lease ran out, for this replica.

        One ``UPDATE … WHERE id = (SELECT … LIMIT 1 FOR UPDATE SKIP LOCKED) AND <still claimable>``:
        on PostgreSQL replicas skip the rows others are claiming; SQLite ignores ``FOR UPDATE`` and runs
        the statement under its single-writer lock. Returns ``(id, kind, params, attempt)`` or None.
        """
        now = utcnow()
        claimable = self._claimable(now)
        oldest = (select(Job.id).where(claimable).order_by(Job.created_at, Job.id).limit(1)
                  .with_for_update(skip_locked=True).scalar_subquery())
        taken_over = Job.status == "running"
        stmt = (update(Job).where(Job.id == oldest, claimable).values(
            status="running", lease_owner=self.replica, lease_expires_at=now + self.lease,
            attempts=Job.attempts + 1, started_at=now, updated_at=now, error=None,
            stage=case((taken_over, literal("taken over")), else_=literal("starting")),
            message=case((taken_over, literal("taken over by ") + literal(self.replica)
                          + literal(" after the lease of ") + func.coalesce(Job.lease_owner, literal("a replica"))
                          + literal(" ran out")), else_=literal("started on ") + literal(self.replica)),
        ).returning(Job.id, Job.kind, Job.params, Job.attempts, Job.stage)
            .execution_options(synchronize_session=False))
        with self.sessions.begin() as s:
            row = s.execute(stmt).first()
        if row is None:
            return None
        job_id, kind, params, attempt, stage = row
        if stage == "taken over":
            self.takeovers += 1
            log.warning("job %s (%s): taken over (attempt %d) from a replica whose lease ran out", job_id, kind,
                        attempt)
        return str(job_id), str(kind), dict(params or {}), int(attempt)

    def _write_held(self, job_id: str, attempt: int, values: dict[str, Any], running_only: bool = False) -> bool:
        """Update the row of a job this replica holds (fenced by replica id and attempt); False when
        another replica has claimed it since."""
        cond = [Job.id == job_id, Job.lease_owner == self.replica, Job.attempts == attempt]
        if running_only:
            cond.append(Job.status == "running")
        with self.sessions.begin() as s:
            res = s.execute(update(Job).where(*cond).values(**values)
                            .execution_options(synchronize_session=False))
            return bool(res.rowcount)

    def _renew_leases(self) -> None:
        with self._held_lock:
            held = dict(self._held)
        for job_id, attempt in held.items():
            if not self._write_held(job_id, attempt, {"lease_expires_at": utcnow() + self.lease},
                                    running_only=True):
                log.warning("job %s: lease lost (claimed by another replica or stopped)", job_id)

    def _claim_loop(self) -> None:
        poll_s = self.settings.job_poll_s
        renew_every_s = self.settings.job_lease_s / 3.0
        last_renew = 0.0
        while not self.stopping.is_set():
            try:
                if time.monotonic() - last_renew >= renew_every_s:
                    self._renew_leases()
                    last_renew = time.monotonic()
                claimed = None
                if self.held() < self.settings.job_threads:
                    claimed = self.claim()
                if claimed is not None:
                    job_id, kind, params, attempt = claimed
                    with self._held_lock:
                        self._held[job_id] = attempt
                    self._executor.submit(self._run, job_id, kind, params, attempt)
                    continue
            except Exception:  # noqa: BLE001 - the database may be away for a moment; try again
                log.exception("job claim loop (replica %s)", self.replica)
            self._wake.wait(min(poll_s, renew_every_s))
            self._wake.clear()

    # -- execution ---------------------------------------------------------------------------
    def _run(self, job_id: str, kind: str, params: dict[str, Any], attempt: int) -> None:
        try:
            self._run_held(job_id, kind, params, attempt)
        finally:
            with self._held_lock:
                self._held.pop(job_id, None)
            self._wake.set()   # a slot is free

    def _run_held(self, job_id: str, kind: str, params: dict[str, Any], attempt: int) -> None:
        if self.stopping.is_set():
            return
        ctx = JobContext(self, job_id, attempt)
        try:
            result = self._work_for(kind)(params, ctx)
        except BaseException as exc:  # noqa: BLE001 - every outcome must land in the row
            if isinstance(exc, JobLost):
                log.warning("job %s (%s): stopped, another replica holds it now", job_id, kind)
                return
            if self.stopping.is_set() or isinstance(exc, JobInterrupted):
                status, error = "interrupted", None
                message = "interrupted by a server shutdown; POST /jobs/{id}/resume continues it"
            else:
                status, message = "failed", "failed"
                error = f"{type(exc).__name__}: {exc}"
                log.error("job %s (%s) failed:\n%s", job_id, kind, traceback.format_exc())
            self._write_held(job_id, attempt, dict(status=status, message=message, error=error,
                                                   lease_expires_at=None, finished_at=utcnow(),
                                                   updated_at=utcnow()))
            if not isinstance(exc, Exception):
                raise
            return
        if not self._write_held(job_id, attempt, dict(
                status="succeeded", progress=1.0, stage="done", message="finished", result=result,
                lease_expires_at=None, finished_at=utcnow(), updated_at=utcnow())):
            log.warning("job %s (%s): finished, but another replica had taken it over; its outcome stands",
                        job_id, kind)
