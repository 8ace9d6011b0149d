"""Jobs: POST /datasets, POST /models/retrain, GET /jobs, GET /jobs/{id}, POST /jobs/{id}/resume,
POST /jobs/{id}/cancel."""
from __future__ import annotations

import datetime as dt
from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Path, Query
from fastapi.concurrency import run_in_threadpool

from ...jobs import JobInterrupted
from ...schemas import DatasetJobRequest, ErrorOut, JobCreated, JobList, JobOut, JobStatus, RetrainRequest
from ...work import prepare_dataset_job, prepare_retrain_job
from ..deps import ApiKeyDep, JobsDep, JsonBodyDep
from ..errors import InputError
from ..routing import FiniteJSONRoute

router = APIRouter(tags=["jobs"], route_class=FiniteJSONRoute)

_AUTH: dict[int | str, dict[str, Any]] = {400: {"model": ErrorOut, "description": "The body cannot be decoded (e.g. JSON that is not UTF-8)."},
         401: {"model": ErrorOut, "description": "No X-API-Key header."},
         403: {"model": ErrorOut, "description": "Wrong API key."},
         415: {"model": ErrorOut, "description": "Body is not application/json."}}
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


@router.post("/datasets", status_code=202, response_model=JobCreated, dependencies=[ApiKeyDep, JsonBodyDep],
             responses={**_AUTH, 422: {"model": ErrorOut, "description": "Invalid spec; `detail` names the key."}},
             summary="Generate a labelled dataset from a sweep spec (job)")
async def create_dataset(body: DatasetJobRequest, jobs: JobsDep) -> JobCreated:
    params = await run_in_threadpool(prepare_dataset_job, body, jobs.settings)
    job = await run_in_threadpool(_submit, jobs, "dataset", params)
    return JobCreated(id=job.id, status=job.status, url=f"/jobs/{job.id}")


@router.post("/models/retrain", status_code=202, response_model=JobCreated, dependencies=[ApiKeyDep, JsonBodyDep],
             tags=["models"],
             responses={**_AUTH, 422: {"model": ErrorOut, "description": "Invalid plant, sweep or training options."}},
             summary="Retrain the model for a plant (job)")
async def create_retrain(body: RetrainRequest, jobs: JobsDep) -> JobCreated:
    params = await run_in_threadpool(prepare_retrain_job, body, jobs.settings)
    job = await run_in_threadpool(_submit, jobs, "retrain", params)
    return JobCreated(id=job.id, status=job.status, url=f"/jobs/{job.id}")


@router.get("/jobs", response_model=JobList, summary="Recent jobs")
def list_jobs(jobs: JobsDep, limit: Annotated[int, Query(ge=1, le=1000)] = 100,
              status: Annotated[JobStatus | None, Query(description="Only jobs in this state.")] = None) -> JobList:
    items = [_out(j) for j in jobs.list(limit, status)]
    return JobList(count=len(items), jobs=items)


@router.get("/jobs/{job_id}", response_model=JobOut, responses={404: {"model": ErrorOut}},
            summary="A job's status, progress and result")
def get_job(job_id: _JobId, jobs: JobsDep) -> JobOut:
    job = jobs.get(job_id)
    if job is None:
        raise InputError(f"no job with id {job_id!r}", "not_found")
    return _out(job)


@router.post("/jobs/{job_id}/resume", response_model=JobOut, dependencies=[ApiKeyDep],
             responses={**_AUTH, 404: {"model": ErrorOut}, 409: {"model": ErrorOut, "description": "Not resumable."}},
             summary="Resume an interrupted (or failed) job")
def resume_job(job_id: _JobId, jobs: JobsDep) -> JobOut:
    try:
        job = jobs.resume(job_id)
    except ValueError as exc:
        raise InputError(str(exc), "conflict") from None
    if job is None:
        raise InputError(f"no job with id {job_id!r}", "not_found")
    return _out(job)


@router.post("/jobs/{job_id}/cancel", response_model=JobOut, dependencies=[ApiKeyDep],
             responses={**_AUTH, 404: {"model": ErrorOut},
                        409: {"model": ErrorOut, "description": "The job has already finished."}},
             summary="Stop a queued or running job",
             description="Stops the job at any stage within seconds (its Dask tasks are cancelled and the workers "
             "running them restarted; a model fit in progress is killed) and answers its state, `cancelled` once "
             "its thread has ended (at most 10 s). A cancelled job keeps its finished work: "
             "POST /jobs/{id}/resume continues it.")
def cancel_job(job_id: _JobId, jobs: JobsDep) -> JobOut:
    try:
        job = jobs.cancel(job_id)
    except ValueError as exc:
        raise InputError(str(exc), "conflict") from None
    if job is None:
        raise InputError(f"no job with id {job_id!r}", "not_found")
    return _out(job)
