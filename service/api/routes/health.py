"""GET /health (polled by docker-compose's healthcheck)."""
from __future__ import annotations

from fastapi import APIRouter, Response
from sqlalchemy import text

from rotordiag.core.version import code_version

from ...inference import ModelUnavailable
from ...schemas import HealthOut
from ..deps import StateDep

router = APIRouter(tags=["health"])


@router.get("/health", response_model=HealthOut, summary="Liveness and readiness",
            responses={503: {"model": HealthOut, "description": "Degraded: database or model unavailable."}})
def health(state: StateDep, response: Response) -> HealthOut:
    problems = []
    try:
        with state.engine.connect() as conn:
            conn.execute(text("SELECT 1"))
        db_ok = True
    except Exception as exc:  # noqa: BLE001 - reported, not raised
        db_ok = False
        problems.append(f"database: {type(exc).__name__}: {exc}")
    version = state.models.active_version()
    sha256 = None
    if version is None:
        problems.append("no active model in the registry")
    elif state.pool is not None:                # the workers' model (checked at most every 5 s), not this process's
        problem = state.pool.check_model(version)
        sha256 = state.pool.model_sha256
        if problem:
            problems.append(problem)
    else:
        try:
            state.models.load(version)          # cached; loaded again when the file changed on disk
            sha256 = state.models.file_sha256(version)
        except ModelUnavailable as exc:
            problems.append(str(exc))
    if problems:
        response.status_code = 503
    return HealthOut(status="degraded" if problems else "ok", version=code_version(), database=db_ok,
                     model_version=version, model_sha256=sha256, detail="; ".join(problems),
                     replica=state.jobs.replica, jobs_held=state.jobs.held())
