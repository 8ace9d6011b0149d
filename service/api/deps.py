"""Typed dependencies shared by the routes (``Annotated`` aliases, as in the FastAPI template)."""
from __future__ import annotations

import secrets
from collections.abc import Iterator
from typing import Annotated

from fastapi import Depends, HTTPException, Request, Security
from fastapi.security import APIKeyHeader
from sqlalchemy.orm import Session

from ..core.config import Settings
from ..inference import ModelStore
from ..jobs import JobManager
from ..state import AppState

_api_key_header = APIKeyHeader(
    name="X-API-Key", auto_error=False,
    description="The service's API key (ROTORDIAG_API_KEY; in development mode a generated key is logged at startup).",
)


def get_state(request: Request) -> AppState:
    state = getattr(request.app.state, "rd", None)
    if state is None:  # pragma: no cover - only if the lifespan did not run
        raise HTTPException(503, "the service is starting up; retry in a moment")
    return state


StateDep = Annotated[AppState, Depends(get_state)]


def get_settings(state: StateDep) -> Settings:
    return state.settings


def get_db(state: StateDep) -> Iterator[Session]:
    with state.sessions() as session:
        yield session


def get_models(state: StateDep) -> ModelStore:
    return state.models


def get_jobs(state: StateDep) -> JobManager:
    return state.jobs


def require_api_key(state: StateDep, key: Annotated[str | None, Security(_api_key_header)]) -> None:
    """401 without a key, 403 with a wrong one."""
    if not key:
        raise HTTPException(401, "this endpoint needs the API key in the X-API-Key header",
                            headers={"WWW-Authenticate": "APIKey"})
    if not secrets.compare_digest(key.encode(), state.settings.effective_api_key.encode()):
        raise HTTPException(403, "the X-API-Key header does not match the server's API key")


def diagnose_key(state: StateDep, key: Annotated[str | None, Security(_api_key_header)]) -> None:
    """The API key on the diagnose endpoints, when ROTORDIAG_DIAGNOSE_REQUIRES_KEY is set."""
    if state.settings.diagnose_requires_key:
        require_api_key(state, key)


SettingsDep = Annotated[Settings, Depends(get_settings)]
SessionDep = Annotated[Session, Depends(get_db)]
ModelsDep = Annotated[ModelStore, Depends(get_models)]
JobsDep = Annotated[JobManager, Depends(get_jobs)]
ApiKeyDep = Depends(require_api_key)
DiagnoseKeyDep = Depends(diagnose_key)


def require_json(request: Request) -> None:
    """415 unless the body is declared as JSON (routes whose body is a JSON model)."""
    media = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if media != "application/json" and not media.endswith("+json"):
        raise HTTPException(415, f"unsupported Content-Type {media or '(none)'!r}: this endpoint takes "
                            "application/json")


JsonBodyDep = Depends(require_json)
