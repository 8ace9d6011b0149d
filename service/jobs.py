"""Job manager: jobs are rows in the database, claimed by any replica, run in a few job threads,
fanned out on Dask.

A job's row is the source of truth. Whatever happens to a process, a job is
in one of ``queued``, ``running``, ``succeeded``, ``failed``, ``interrupted``, ``cancelled``.

Several replicas (API processes on one or more hosts) share the database and
none owns a job: each job thread of each replica claims a ``queued`` job, or a
``running`` one whose lease has run out, in one statement (``UPDATE … WHERE id =
(SELECT … FOR UPDATE SKIP LOCKED)`` on PostgreSQL; on SQLite the same statement
runs under the database's single-writer lock). The claim writes the replica's id
(``lease_owner``), a lease end (``lease_expires_at``, now + ``job_lease_s``) and
one more attempt. The holder renews the lease every third of ``job_lease_s`` and
with each progress report; every write it makes names its own id and attempt, so
a holder that lost its lease (it stalled past the lease, or the job was cancelled
through another replica) changes nothing and stops. When a holder dies (SIGKILL,
a lost host), another replica claims the job once the lease has run out, at most
``job_lease_s + job_poll_s`` later, and runs it again: the work functions are
resumable (dataset generation completes only the missing samples of its HDF5
file; retraining reuses a finished dataset and a model an earlier attempt
registered), so finished work is not lost. Lease ends are written with the
replicas' own clocks, which must agree to well within ``job_lease_s`` (NTP).

Stopping: ``cancel`` (``POST /jobs/{id}/cancel``) and a server shutdown stop a running job
within seconds at any stage: its Dask tasks are cancelled and the workers running them
restarted, a step in a child process (model training) is killed, and every progress report
checks. At shutdown the job threads get ``shutdown_timeout_s``; the jobs this replica runs are
left ``interrupted`` (``resume`` queues them again for any replica) and the process exits anyway
(the threads are daemons).

An outcome that cannot be written (a full disk) is kept in memory, shown by ``get``/``list``
and written again every few seconds until it lands, the lease renewed meanwhile; a row left
``running`` by a thread that has ended can be resumed or cancelled.

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
from typing import Any

from sqlalchemy import and_, case, func, literal, or_, select, update
from sqlalchemy.exc import DatabaseError
from sqlalchemy.orm import sessionmaker

from .core.config import Settings
from .core.db import Job, utcnow

log = logging.getLogger("rotordiag.service.jobs")

ACTIVE = ("queued", "running")
RESUMABLE = ("interrupted", "failed", "cancelled")
STATUSES = ("queued", "running", "succeeded", "failed", "interrupted", "cancelled")

#: seconds between attempts to write an outcome the database refused
RECORD_RETRY_S = 2.0
#: seconds ``cancel`` waits for the job's thread to end before answering
CANCEL_WAIT_S = 10.0


class JobInterrupted(Exception):
    """Raised inside a job when the server is shutting down."""


class JobCancelled(Exception):
    """Raised inside a job that was cancelled (``POST /jobs/{id}/cancel``)."""


class JobLost(JobInterrupted):
    """Raised inside a job whose lease this replica no longer holds (taken over, or cancelled through
    another replica): it stops without writing anything."""


class JobContext:
    """What a work function gets: settings, Dask client, model store, progress reporting, stop checks."""

    def __init__(self, manager: JobManager, job_id: str, attempt: int = 0) -> None:
        self._manager = manager
        self.job_id = job_id
        self.attempt = attempt
        self.settings = manager.settings
        self.models = manager.models
        self.cancel_event = threading.Event()
        self.lost_event = threading.Event()
        self.done = threading.Event()
        self._on_stop: list[Callable[[], None]] = []
        self._lock = threading.Lock()
        self._futures: list[Any] = []

    def client(self) -> Any:
        """The shared ``distributed.Client`` (created on first use), seen through a wrapper that remembers
        this job's futures so that a cancel or a shutdown can cancel them."""
        return _JobClient(self._manager.client(), self)

    def check(self) -> None:
        """Raise :class:`JobInterrupted` when the server is stopping, :class:`JobCancelled` when cancelled,
        :class:`JobLost` when this replica no longer holds the job."""
        if self.lost_event.is_set():
            raise JobLost(f"job {self.job_id}: this replica no longer holds its lease")
        if self._manager.stopping.is_set():
            raise JobInterrupted("server shutting down")
        if self.cancel_event.is_set():
            raise JobCancelled("cancelled")

    def progress(self, fraction: float, stage: str | None = None, message: str | None = None) -> None:
        """Record progress (0-1) and renew the lease; raises :class:`JobInterrupted`/:class:`JobCancelled`/
        :class:`JobLost` when the job must stop."""
        self.check()
        now = utcnow()
        values: dict[str, Any] = {"progress": float(min(max(fraction, 0.0), 1.0)), "updated_at": now,
                                  "lease_expires_at": now + self._manager.lease}
        if stage is not None:
            values["stage"] = stage
        if message is not None:
            values["message"] = message
        if not self._manager._write_held(self.job_id, self.attempt, values, over=("running",)):
            self.lost_event.set()
            self.check()

    def on_stop(self, hook: Callable[[], None]) -> Callable[[], None]:
        """Call ``hook()`` (from another thread) when this job is cancelled or the server stops; runs it at
        once when that has already happened. Returns a function that unregisters it."""
        with self._lock:
            self._on_stop.append(hook)
        if self.stopping:
            _quietly(hook)

        def remove() -> None:
            with self._lock:
                if hook in self._on_stop:
                    self._on_stop.remove(hook)
        return remove

    def _stop(self) -> None:
        """Stop whatever the job is waiting on: its Dask tasks, its child processes."""
        with self._lock:
            hooks, futures = list(self._on_stop), list(self._futures)
        for hook in hooks:
            _quietly(hook)
        if futures:   # at shutdown the cluster closes anyway: no worker restart
            self._manager.cancel_futures(futures, restart=not self._manager.stopping.is_set())

    def _track(self, future: Any) -> None:
        with self._lock:
            self._futures.append(future)
            if len(self._futures) > 4096:           # keep the unfinished ones only
                self._futures = [f for f in self._futures if not f.done()]
        if self.stopping:
            self._stop()

    @property
    def stopping(self) -> bool:
        """The job must stop: cancelled, lost, or the server is shutting down."""
        return self._manager.stopping.is_set() or self.cancel_event.is_set() or self.lost_event.is_set()

    @property
    def cancelled(self) -> bool:
        return self.cancel_event.is_set()


class _JobClient:
    """A ``distributed.Client`` that records the futures one job submits (everything else passes through)."""

    def __init__(self, client: Any, ctx: JobContext) -> None:
        self._client = client
        self._ctx = ctx

    def submit(self, *args: Any, **kwargs: Any) -> Any:
        self._ctx.check()
        future = self._client.submit(*args, **kwargs)
        self._ctx._track(future)
        return future

    def __getattr__(self, name: str) -> Any:
        return getattr(self._client, name)


def _quietly(fn: Callable[[], None]) -> None:
    try:
        fn()
    except Exception:  # noqa: BLE001 - a stop hook must not stop the others
        log.exception("stopping a job")


WorkFunction = Callable[[dict[str, Any], JobContext], dict[str, Any]]


class JobManager:
    """Create, run, cancel, resume and report jobs.

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
        self.replica = settings.effective_replica_id
        self.lease = dt.timedelta(seconds=settings.job_lease_s)
        self._wake = threading.Event()                   # a job was queued here: claim at once
        self._threads: list[threading.Thread] = []
        self._held: dict[str, int] = {}                  # job id -> attempt, of the jobs this replica holds
        self.takeovers = 0                               # jobs claimed after their holder's lease ran out
        self._client = None
        self._cluster = None
        self._client_lock = threading.Lock()
        self._work: dict[str, WorkFunction] = {}
        self._live: dict[str, JobContext] = {}           # jobs whose thread runs now
        self._unrecorded: dict[str, dict[str, Any]] = {}  # outcomes the database refused, written again later
        self._lock = threading.RLock()
        self._retry_thread: threading.Thread | None = None

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
        """Start the job threads (each claims queued jobs and those whose holder died) and the lease thread
        (renews this replica's leases)."""
        if self._threads:
            return
        self._threads = [threading.Thread(target=self._thread_main, name=f"rotordiag-job-{i}", daemon=True)
                         for i in range(self.settings.job_threads)]
        self._threads.append(threading.Thread(target=self._lease_main, name="rotordiag-job-lease", daemon=True))
        for t in self._threads:
            t.start()

    def mark_interrupted(self) -> int:
        """Mark the jobs this replica holds ``interrupted`` (at shutdown); return how many."""
        with self.sessions.begin() as s:
            res = s.execute(
                update(Job).where(Job.status == "running", Job.lease_owner == self.replica).values(
                    status="interrupted", lease_expires_at=None,
                    message="the server stopped while this job was running; POST /jobs/{id}/resume continues it",
                    updated_at=utcnow()))
            return res.rowcount or 0

    def held(self) -> int:
        """Number of jobs this replica holds (running, or ended with the outcome not yet written)."""
        with self._lock:
            return len(self._held)

    def shutdown(self) -> None:
        """Stop accepting work, stop running jobs (Dask tasks cancelled, child processes killed), wait for
        the job threads at most ``settings.shutdown_timeout_s``, close the Dask client.

        The jobs this replica runs are left ``interrupted`` (resumable); queued ones stay queued for any
        replica. When the database cannot be written now, their leases run out and another replica (or this
        one, restarted) takes them over."""
        self.stopping.set()
        self._wake.set()
        with self._lock:
            live = list(self._live.values())
        for ctx in live:
            ctx._stop()
        try:
            self.mark_interrupted()   # right away, in case the process is killed while we wait below
        except DatabaseError as exc:
            log.error("cannot mark the running jobs interrupted (%s); their leases run out and another replica "
                      "(or the next start) takes them over", exc.orig)
        deadline = time.monotonic() + self.settings.shutdown_timeout_s
        for ctx in live:
            ctx.done.wait(max(0.0, deadline - time.monotonic()))
        still = [ctx.job_id for ctx in live if not ctx.done.is_set()]
        if still:
            log.warning("job(s) %s did not stop within %g s; left interrupted (resumable)", ", ".join(still),
                        self.settings.shutdown_timeout_s)
        self._flush_unrecorded()
        self._close_client()

    def client(self):
        """The Dask client shared by jobs, created on first use."""
        with self._client_lock:
            if self.stopping.is_set():
                raise JobInterrupted("server shutting down")
            if self._client is None:
                address = self.settings.dask_scheduler_address
                if address:
                    from distributed import Client

                    log.info("connecting to Dask scheduler %s", address)
                    self._client = Client(address, timeout=30, set_as_default=False)
                else:
                    from rotordiag.simulator.runner import start_local_cluster

                    log.info("starting a local Dask cluster with %d worker process(es)",
                             self.settings.dask_local_workers)
                    self._client, self._cluster = start_local_cluster(self.settings.dask_local_workers,
                                                                      dashboard_address=None)
            return self._client

    def cancel_futures(self, futures: list[Any], restart: bool = True) -> None:
        """Cancel Dask futures and, with ``restart``, restart the workers still running them (a running task
        is not interrupted by a cancel; its worker process is)."""
        with self._client_lock:
            client = self._client
        if client is None:
            return
        keys = {f.key for f in futures if not f.done()}
        if not keys:
            return
        try:
            busy = [w for w, ks in client.processing().items() if keys & set(ks)]
        except Exception:  # noqa: BLE001 - best effort: the cancel below still happens
            busy = []
        client.cancel(futures, force=True)
        if busy and restart:
            threading.Thread(target=_quietly, args=(lambda: client.restart_workers(busy, timeout=60),),
                             name="rotordiag-job-restart", daemon=True).start()

    def _close_client(self) -> None:
        with self._client_lock:
            client, cluster = self._client, self._cluster
            self._client = self._cluster = None
        for thing in (client, cluster):
            if thing is not None:
                try:
                    thing.close(timeout=5)
                except Exception:  # noqa: BLE001 - best effort at shutdown
                    log.warning("closing Dask %s did not finish cleanly", type(thing).__name__)

    # -- API ---------------------------------------------------------------------------------
    def submit(self, kind: str, params: dict[str, Any]) -> Job:
        """Store a new job and queue it."""
        self._work_for(kind)  # fail early on an unknown kind
        if self.stopping.is_set():
            raise JobInterrupted("server shutting down")
        job = Job(id=str(uuid.uuid4()), kind=kind, status="queued", params=params, progress=0.0,
                  stage="queued", message="waiting for a job slot", attempts=0)
        with self.sessions.begin() as s:
            s.add(job)
        self._wake.set()   # this replica's job threads look at once; the others' within job_poll_s
        return job

    def resume(self, job_id: str) -> Job | None:
        """Queue an interrupted, failed or cancelled job again (or one whose thread ended without its
        outcome written); ``None`` when it does not exist.

        Raises
        ------
        ValueError
            When the job is not in a resumable state.
        """
        with self._lock:
            with self.sessions.begin() as s:
                job = s.get(Job, job_id)
                if job is None:
                    return None
                status = self._status(job)
                if status not in RESUMABLE:
                    raise ValueError(f"job {job_id} is {status}; only interrupted, failed or cancelled jobs can be "
                                     "resumed")
                job.status, job.stage, job.message, job.error = "queued", "queued", "resumed; waiting for a job slot", None
                job.lease_owner = job.lease_expires_at = None
            self._unrecorded.pop(job_id, None)
            self._held.pop(job_id, None)
        self._wake.set()
        return self.get(job_id)

    def cancel(self, job_id: str, wait_s: float = CANCEL_WAIT_S) -> Job | None:
        """Stop a queued or running job; ``None`` when it does not exist. A running job's thread is given
        ``wait_s`` to end (its Dask tasks are cancelled and their workers restarted, a training child process
        killed); the job ends ``cancelled`` and can be resumed.

        Raises
        ------
        ValueError
            When the job has already finished.
        """
        with self._lock:
            ctx = self._live.get(job_id)
            job = self.get(job_id)           # with an outcome not yet written: that outcome (finished)
            if job is None:
                return None
            if ctx is None:
                if job.status not in ACTIVE:
                    raise ValueError(f"job {job_id} is {job.status}; only queued or running jobs can be cancelled")
                # queued (no replica claims it any more), running on another replica (whose next progress
                # report or lease renewal finds it cancelled and stops it), or ended with its outcome unwritten
                self._unrecorded.pop(job_id, None)
                self._held.pop(job_id, None)
                with self.sessions.begin() as s:
                    s.execute(update(Job).where(Job.id == job_id, Job.status.in_(ACTIVE)).values(
                        status="cancelled", stage="cancelled", message=_CANCELLED, finished_at=utcnow(),
                        lease_expires_at=None, updated_at=utcnow()))
                return self.get(job_id)
            ctx.cancel_event.set()
        ctx._stop()
        if not ctx.done.wait(wait_s):
            try:
                with self.sessions.begin() as s:
                    s.execute(update(Job).where(Job.id == job_id, Job.status == "running").values(
                        message="cancel requested: the job stops at its next check (feature extraction: after "
                        "the recording it is on)", updated_at=utcnow()))
            except DatabaseError:
                pass                                       # the outcome write will say it
        return self.get(job_id)

    def get(self, job_id: str) -> Job | None:
        with self.sessions() as s:
            job = s.get(Job, job_id)
        return self._overlay(job) if job is not None else None

    def list(self, limit: int = 100, status: str | None = None) -> list[Job]:
        with self.sessions() as s:
            q = select(Job).order_by(Job.created_at.desc()).limit(limit)
            if status is not None:
                q = q.where(Job.status == status)
            return [self._overlay(j) for j in s.scalars(q)]

    def counts(self) -> dict[str, int]:
        """Number of jobs per status (every status present, zero when none)."""
        with self.sessions() as s:
            rows = s.execute(select(Job.status, func.count()).group_by(Job.status)).all()
        out = {k: 0 for k in STATUSES}
        out.update({status: int(n) for status, n in rows})
        return out

    def _status(self, job: Job) -> str:
        """The job's state as this process knows it: a row ``running``/``queued`` whose thread has ended with
        its outcome unwritten counts as that outcome."""
        pending = self._unrecorded.get(job.id)
        return pending["status"] if pending is not None and job.status in ACTIVE else job.status

    def _overlay(self, job: Job) -> Job:
        """``job`` (detached) with the outcome the database has not taken yet, said so in its message."""
        pending = self._unrecorded.get(job.id)
        if pending is not None and job.status in ACTIVE:
            for k, v in pending.items():
                if k != "db_error":
                    setattr(job, k, v)
            job.message = (f"{pending['message']} (not yet written to the database: {pending['db_error']}; "
                           "retried every few seconds)")
        return job

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

    def _write_held(self, job_id: str, attempt: int, values: dict[str, Any],
                    over: tuple[str, ...] = ACTIVE) -> bool:
        """Update the row of a job this replica holds, fenced by replica id and attempt and by its state
        (``over``); False when another replica has claimed it since, or it was cancelled."""
        with self.sessions.begin() as s:
            res = s.execute(update(Job).where(Job.id == job_id, Job.lease_owner == self.replica,
                                              Job.attempts == attempt, Job.status.in_(over)).values(**values)
                            .execution_options(synchronize_session=False))
            return bool(res.rowcount)

    def _renew_leases(self) -> None:
        """Renew the leases of the jobs this replica holds; a job found taken over or cancelled is stopped."""
        with self._lock:
            held = dict(self._held)
        for job_id, attempt in held.items():
            try:
                ok = self._write_held(job_id, attempt, {"lease_expires_at": utcnow() + self.lease},
                                      over=("running",))
            except DatabaseError as exc:
                log.warning("job %s: lease not renewed (%s)", job_id, exc.orig)
                continue
            if not ok:
                with self._lock:
                    ctx = self._live.get(job_id)
                    if job_id not in self._unrecorded:
                        self._held.pop(job_id, None)
                if ctx is not None and not ctx.lost_event.is_set():
                    log.warning("job %s: lease lost (taken over, or cancelled through another replica); "
                                "stopping it here", job_id)
                    ctx.lost_event.set()
                    ctx._stop()

    def _lease_main(self) -> None:
        while not self.stopping.wait(self.settings.job_lease_s / 3.0):
            self._renew_leases()

    # -- execution ---------------------------------------------------------------------------
    def _thread_main(self) -> None:
        poll_s = self.settings.job_poll_s
        while not self.stopping.is_set():
            try:
                with self._lock:
                    claimed = None if self.stopping.is_set() else self.claim()
                    if claimed is not None:
                        job_id, kind, params, attempt = claimed
                        self._held[job_id] = attempt
                        ctx = self._live[job_id] = JobContext(self, job_id, attempt)
                if claimed is None:
                    self._wake.wait(poll_s)
                    self._wake.clear()
                    continue
                self._run(ctx, kind, params)
            except Exception:  # noqa: BLE001 - a job thread must survive whatever one job or the database did
                log.exception("job thread (replica %s)", self.replica)
                self.stopping.wait(poll_s)

    def _run(self, ctx: JobContext, kind: str, params: dict[str, Any]) -> None:
        job_id = ctx.job_id
        try:
            result = self._work_for(kind)(params, ctx)
            outcome = {"status": "succeeded", "progress": 1.0, "stage": "done", "message": "finished",
                       "result": result, "error": None}
        except BaseException as exc:  # noqa: BLE001 - every outcome must land in the row
            if ctx.lost_event.is_set() or isinstance(exc, JobLost):
                log.warning("job %s (%s): stopped here; another replica holds it, or it was cancelled", job_id,
                            kind)
                ctx._stop()
                with self._lock:
                    self._live.pop(job_id, None)
                    self._held.pop(job_id, None)
                ctx.done.set()
                if not isinstance(exc, Exception):
                    raise
                return
            if ctx.cancelled:
                outcome = {"status": "cancelled", "stage": "cancelled", "message": _CANCELLED, "error": None}
            elif self.stopping.is_set() or isinstance(exc, JobInterrupted):
                outcome = {"status": "interrupted", "message": "interrupted by a server shutdown; "
                           "POST /jobs/{id}/resume continues it", "error": None}
            else:
                outcome = {"status": "failed", "message": "failed", "error": f"{type(exc).__name__}: {exc}"}
                log.error("job %s (%s) failed:\n%s", job_id, kind, traceback.format_exc())
            if not isinstance(exc, Exception):
                self._finish(job_id, ctx, outcome)
                raise
        self._finish(job_id, ctx, outcome)

    def _finish(self, job_id: str, ctx: JobContext, outcome: dict[str, Any]) -> None:
        outcome = {**outcome, "finished_at": utcnow()}
        with self._lock:
            try:
                try:
                    self._write(job_id, outcome)
                except DatabaseError:
                    raise
                except Exception as exc:  # noqa: BLE001 - e.g. a result the JSON column cannot hold
                    log.exception("job %s: its outcome cannot be stored", job_id)
                    outcome = {"status": "failed", "message": "failed", "result": None, "finished_at": utcnow(),
                               "error": f"the job's result cannot be stored: {type(exc).__name__}: {exc}"}
                    self._write(job_id, outcome)
            except DatabaseError as exc:
                log.error("job %s ended %s but the database refused the outcome (%s); retrying every %g s",
                          job_id, outcome["status"], exc.orig, RECORD_RETRY_S)
                self._unrecorded[job_id] = {**outcome, "db_error": str(exc.orig)}
                self._start_retry()
            else:
                self._held.pop(job_id, None)
            finally:
                self._live.pop(job_id, None)
        ctx.done.set()

    def _write(self, job_id: str, outcome: dict[str, Any]) -> None:
        values = {k: v for k, v in outcome.items() if k != "db_error"}
        # only over the state this run left (a cancel in between wins), and only while this replica's attempt
        # holds the job (one that was taken over is the new holder's); at shutdown also over the
        # `interrupted` that shutdown() wrote ahead, so a job whose last step finished says so
        over = ACTIVE + ("interrupted",) if self.stopping.is_set() else ACTIVE
        attempt = self._held.get(job_id)
        if attempt is None or not self._write_held(job_id, attempt, {**values, "lease_expires_at": None,
                                                                     "updated_at": utcnow()}, over=over):
            log.warning("job %s: outcome %s not written: another replica has taken the job over, or it was "
                        "cancelled", job_id, values.get("status"))

    def _flush_unrecorded(self) -> int:
        """Write the outcomes the database refused before; returns how many are still unwritten."""
        with self._lock:
            for job_id, outcome in list(self._unrecorded.items()):
                try:
                    self._write(job_id, outcome)
                except DatabaseError:
                    continue
                del self._unrecorded[job_id]
                self._held.pop(job_id, None)
                log.info("job %s: outcome %s written to the database", job_id, outcome["status"])
            return len(self._unrecorded)

    def _start_retry(self) -> None:
        if self._retry_thread is not None and self._retry_thread.is_alive():
            return

        def loop() -> None:
            while not self.stopping.wait(RECORD_RETRY_S):
                if self._flush_unrecorded() == 0:
                    return

        self._retry_thread = threading.Thread(target=loop, name="rotordiag-job-record", daemon=True)
        self._retry_thread.start()


_CANCELLED = "cancelled by POST /jobs/{id}/cancel; POST /jobs/{id}/resume continues it"
