"""Jobs: POST /datasets, POST /models/retrain, GET /jobs, GET /jobs/{id}, POST /jobs/{id}/resume,
POST /jobs/{id}/cancel."""
from __future__ import annotations

import datetime as dt
from collections.abc import Callable
from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Path, Query
from fastapi.concurrency import run_in_threadpool

from ...jobs import JobInterrupted
from ...schemas import DatasetJobRequest, JobCreated, JobList, JobOut, JobStatus, RetrainRequest
from ...work import prepare_dataset_job, prepare_retrain_job
from ..deps import ApiKeyDep, JobsDep, JsonBodyDep
from ..errors import InputError, error_responses
from ..routing import FiniteJSONRoute

router = APIRouter(tags=["jobs"], route_class=FiniteJSONRoute)

_NO_JOB = "No job with this id."
_JobId = Annotated[str, Path(min_length=1, max_length=64, description="Job id returned by the creating POST.")]


def _submit(jobs, kind: str, params: dict[str, Any]):
    try:
        return jobs.submit(kind, params)
    except JobInterrupted:
        raise HTTPException(503, "the server is shutting down; submit the job again once it is back") from None


def _out(job) -> JobOut:
    out = JobOut.model_validate(job, from_attributes=True)
    out.eta_s = eta_seconds(out.status, out.progress, out.started_at)
    return out


def eta_seconds(status: str, progress: float, started_at: dt.datetime | None,
                now: dt.datetime | None = None) -> float | None:
    """Seconds left of a running job: elapsed × (1 − progress) / progress (None below 1 % or not running)."""
    if status != "running" or started_at is None or progress < 0.01:
        return None
    now = now or dt.datetime.now(dt.UTC)
    start = started_at if started_at.tzinfo is not None else started_at.replace(tzinfo=dt.UTC)
    elapsed = max((now - start).total_seconds(), 0.0)
    return round(elapsed * (1.0 - progress) / progress, 1)


async def _created(jobs, kind: str, params: dict[str, Any]) -> JobCreated:
    """Submit a prepared job (in a thread: it writes the database) and answer where to follow it."""
    job = await run_in_threadpool(_submit, jobs, kind, params)
    return JobCreated(id=job.id, status=job.status, url=f"/jobs/{job.id}")


def _found(job_id: str, job) -> JobOut:
    """``job`` as the API shows it, a 404 naming ``job_id`` when there is none."""
    if job is None:
        raise InputError(f"no job with id {job_id!r}", "not_found")
    return _out(job)


def _acted(action: Callable[[str], Any], job_id: str) -> JobOut:
    """``action(job_id)`` (resume, cancel): a 409 with the job store's reason when the job's state refuses it."""
    try:
        job = action(job_id)
    except ValueError as exc:
        raise InputError(str(exc), "conflict") from None
    return _found(job_id, job)


@router.post("/datasets", status_code=202, response_model=JobCreated, dependencies=[ApiKeyDep, JsonBodyDep],
             responses=error_responses({422: "Invalid spec; `detail` names the key."}, key="always", body="json"),
             summary="Generate a labelled dataset from a sweep spec (job)")
async def create_dataset(body: DatasetJobRequest, jobs: JobsDep) -> JobCreated:
    return await _created(jobs, "dataset", await run_in_threadpool(prepare_dataset_job, body, jobs.settings))


@router.post("/models/retrain", status_code=202, response_model=JobCreated, dependencies=[ApiKeyDep, JsonBodyDep],
             tags=["models"],
             responses=error_responses({422: "Invalid plant, sweep or training options."}, key="always", body="json"),
             summary="Retrain the model for a plant (job)")
async def create_retrain(body: RetrainRequest, jobs: JobsDep) -> JobCreated:
    return await _created(jobs, "retrain", await run_in_threadpool(prepare_retrain_job, body, jobs.settings))


@router.get("/jobs", response_model=JobList, summary="Recent jobs")
def list_jobs(jobs: JobsDep, limit: Annotated[int, Query(ge=1, le=1000)] = 100,
              status: Annotated[JobStatus | None, Query(description="Only jobs in this state.")] = None) -> JobList:
    items = [_out(j) for j in jobs.list(limit, status)]
    return JobList(count=len(items), jobs=items)


@router.get("/jobs/{job_id}", response_model=JobOut, responses=error_responses({404: _NO_JOB}),
            summary="A job's status, progress and result")
def get_job(job_id: _JobId, jobs: JobsDep) -> JobOut:
    return _found(job_id, jobs.get(job_id))


@router.post("/jobs/{job_id}/resume", response_model=JobOut, dependencies=[ApiKeyDep],
             responses=error_responses({404: _NO_JOB, 409: "Not resumable."}, key="always"),
             summary="Resume an interrupted (or failed) job")
def resume_job(job_id: _JobId, jobs: JobsDep) -> JobOut:
    return _acted(jobs.resume, job_id)


@router.post("/jobs/{job_id}/cancel", response_model=JobOut, dependencies=[ApiKeyDep],
             responses=error_responses({404: _NO_JOB, 409: "The job has already finished."}, key="always"),
             summary="Stop a queued or running job",
             description="Stops the job at any stage within seconds (its Dask tasks are cancelled and the workers "
             "running them restarted; a model fit in progress is killed) and answers its state, `cancelled` once "
             "its thread has ended (at most 10 s). A cancelled job keeps its finished work: "
             "POST /jobs/{id}/resume continues it.")
def cancel_job(job_id: _JobId, jobs: JobsDep) -> JobOut:
    return _acted(jobs.cancel, job_id)
