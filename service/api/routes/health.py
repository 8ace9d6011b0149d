"""GET /health (polled by docker-compose's healthcheck): `ok` only when a diagnosis would work and be stored."""
from __future__ import annotations

import shutil

from fastapi import APIRouter, Response

from rotordiag.core.version import code_version

from ...inference import ModelUnavailable
from ...schemas import HealthOut
from ...store import database_problem, disk_problem
from ..deps import StateDep

router = APIRouter(tags=["health"])


@router.get("/health", response_model=HealthOut, summary="Liveness and readiness",
            responses={503: {"model": HealthOut, "description": "Starting (no worker has checked the model yet) or "
                             "degraded: model, database or data disk unusable; `detail` says which."}})
def health(state: StateDep, response: Response) -> HealthOut:
    """`starting` until a diagnosis worker (or, without workers, this process) has loaded the active model and
    read its checksum; `degraded` when the model or its checksum is missing, the database cannot read a table
    and take a write, or the data disk is nearly full; `ok` otherwise."""
    problems = []
    db_problem = database_problem(state)
    if db_problem:
        problems.append(db_problem)
    disk = disk_problem(state.settings)
    if disk:
        problems.append(disk)
    version = state.models.active_version()
    sha256 = None
    starting = False
    if version is None:
        problems.append("no active model in the registry")
    elif state.pool is not None:                # the workers' model (checked at most every 5 s), not this process's
        pool = state.pool
        if pool.checked_version != version and not pool.any_ready():
            starting = True                     # no worker has loaded a model yet: asking would wait for one
        else:
            problem = pool.check_model(version)
            if problem:
                problems.append(problem)
            elif pool.checked_version != version:
                starting = True                 # every worker busy before its first check
            elif pool.model_sha256 is None:
                problems.append(f"model {version}: the checksum of the file the diagnosis workers hold is unknown")
            else:
                sha256 = pool.model_sha256
    else:
        try:
            state.models.load(version)          # cached; loaded again when the file changed on disk
            sha256 = state.models.file_sha256(version)
        except ModelUnavailable as exc:
            problems.append(str(exc))
        else:
            if sha256 is None:
                problems.append(f"model {version}: the checksum of its file is unknown")
    status = "degraded" if problems else "starting" if starting else "ok"
    if starting:
        problems.append("starting: no diagnosis worker has loaded and checked the model yet")
    if status != "ok":
        response.status_code = 503
    try:
        free_mb: float | None = shutil.disk_usage(state.settings.data_dir).free / 2**20
    except OSError:
        free_mb = None
    return HealthOut(status=status, version=code_version(), database=db_problem is None, disk_free_mb=free_mb,
                     model_version=version, model_sha256=sha256, detail="; ".join(problems),
                     replica=state.jobs.replica, jobs_held=state.jobs.held())
