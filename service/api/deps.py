"""Typed dependencies shared by the routes (``Annotated`` aliases, as in the FastAPI template).

The dependencies that do no blocking I/O are ``async def``: FastAPI runs a plain ``def`` dependency in its thread
pool, and the hand-over to a thread and back cost the diagnosis route ~2 ms of the server's time per request under
load (five of them per request); ``get_db`` opens a database session and stays in the pool."""
from __future__ import annotations

import secrets
from collections.abc import Iterator
from typing import Annotated

from fastapi import Depends, HTTPException, Query, Request, Security
from fastapi.security import APIKeyHeader
from sqlalchemy.orm import Session

from rotordiag.core.input_bounds import CLEARANCE_RANGE_UM, SAMPLE_RATE_RANGE_HZ, SPEED_RANGE_RPM

from ..core.config import Settings
from ..inference import ModelStore
from ..jobs import JobManager
from ..state import AppState

_api_key_header = APIKeyHeader(
    name="X-API-Key", auto_error=False,
    description="The service's API key (ROTORDIAG_API_KEY; in development mode a generated key is logged at startup).",
)


async def get_state(request: Request) -> AppState:
    state = getattr(request.app.state, "rd", None)
    if state is None:  # pragma: no cover - only if the lifespan did not run
        raise HTTPException(503, "the service is starting up; retry in a moment")
    return state


StateDep = Annotated[AppState, Depends(get_state)]


async def get_settings(state: StateDep) -> Settings:
    return state.settings


def get_db(state: StateDep) -> Iterator[Session]:
    with state.sessions() as session:
        yield session


async def get_models(state: StateDep) -> ModelStore:
    return state.models


async def get_jobs(state: StateDep) -> JobManager:
    return state.jobs


async def require_api_key(state: StateDep, key: Annotated[str | None, Security(_api_key_header)]) -> None:
    """401 without a key, 403 with a wrong one."""
    _check_api_key(state, key)


def _check_api_key(state: AppState, key: str | None) -> None:
    """:func:`require_api_key`'s test, for the dependencies that apply it."""
    if not key:
        raise HTTPException(401, "this endpoint needs the API key in the X-API-Key header",
                            headers={"WWW-Authenticate": "APIKey"})
    if not secrets.compare_digest(key.encode(), state.settings.effective_api_key.encode()):
        raise HTTPException(403, "the X-API-Key header does not match the server's API key")


async def diagnose_key(state: StateDep, key: Annotated[str | None, Security(_api_key_header)]) -> None:
    """The API key on the diagnose endpoints, when ROTORDIAG_DIAGNOSE_REQUIRES_KEY is set."""
    if state.settings.diagnose_requires_key:
        _check_api_key(state, key)


async def may_store(state: StateDep, key: Annotated[str | None, Security(_api_key_header)]) -> bool:
    """Whether a diagnosis request may write to an asset's history: it carries the API key (403 when the key it
    carries is wrong). Without one the diagnosis is answered and not stored."""
    if not key:
        return False
    _check_api_key(state, key)
    return True


SettingsDep = Annotated[Settings, Depends(get_settings)]
MayStoreDep = Annotated[bool, Depends(may_store)]
SessionDep = Annotated[Session, Depends(get_db)]
ModelsDep = Annotated[ModelStore, Depends(get_models)]
JobsDep = Annotated[JobManager, Depends(get_jobs)]
ApiKeyDep = Depends(require_api_key)
DiagnoseKeyDep = Depends(diagnose_key)


async def require_json(request: Request) -> None:
    """415 unless the body is declared as JSON (routes whose body is a JSON model)."""
    media = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if media != "application/json" and not media.endswith("+json"):
        raise HTTPException(415, f"unsupported Content-Type {media or '(none)'!r}: this endpoint takes "
                            "application/json")


JsonBodyDep = Depends(require_json)


# The query parameters that describe an uploaded recording's layout (binary or multipart uploads:
# /diagnose, /assets/{id}/baseline, /ui/plot-data), declared once.
SampleRateQuery = Annotated[float | None, Query(ge=SAMPLE_RATE_RANGE_HZ[0], le=SAMPLE_RATE_RANGE_HZ[1], allow_inf_nan=False,
                                                description="Binary/multipart only: sample rate, Hz.")]
SpeedQuery = Annotated[float | None, Query(ge=SPEED_RANGE_RPM[0], le=SPEED_RANGE_RPM[1], allow_inf_nan=False,
                                           description="Binary/multipart only: running speed, r/min.")]
ClearanceQuery = Annotated[float | None, Query(ge=CLEARANCE_RANGE_UM[0], le=CLEARANCE_RANGE_UM[1], allow_inf_nan=False,
                                               description="Binary/multipart only: radial clearance, µm.")]
UnitsQuery = Annotated[str | None, Query(min_length=1, max_length=16,
                                         description="Binary/multipart only: units of the array (`um`, `mm`, `m`, "
                                         "`mil`, or `V` with `sensitivity_v_per_mm`); "
                                         "default `um` (or the HDF5 file's `units` attribute).")]
BearingsQuery = Annotated[str | None, Query(max_length=64, pattern=r"^[0-9, ;]*$",
                                            description="Binary/multipart only: bearing (1-4) of each row, "
                                            "comma-separated; default 1,1,2,2,3,3,4,4 for 8 rows.")]
AnglesQuery = Annotated[str | None, Query(max_length=256,
                                          description="Binary/multipart only: probe angle of each row in degrees "
                                          "from horizontal x towards vertical-up y, comma-separated; "
                                          "default 45,135 repeated.")]
SpeedRangeQuery = Annotated[str | None, Query(max_length=64, description=(
    "Binary/multipart only: the running speed's range `min,max` in r/min (e.g. `2900,3100` for a 3000 r/min "
    "generator) when it is not known exactly: the speed estimate is sought only there."))]
AcquisitionsQuery = Annotated[str | None, Query(max_length=32, description=(
    "Binary/multipart only: groups of bearings sampled together when the channels come from separate acquisitions "
    "(takes), e.g. `1,2;3,4`: the phase differences between takes are not measured, and with bearings 2 and 3 in "
    "different takes the verdict is never confident. Leave it out when every channel was sampled together."))]
KeyphasorQuery = Annotated[str | None, Query(max_length=200_000,
                                             description="Binary/multipart only: keyphasor pulse times, s, "
                                             "comma-separated; with `acquisitions`, one list per acquisition "
                                             "separated by semicolons (each on its take's clock).")]
