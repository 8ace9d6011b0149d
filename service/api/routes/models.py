"""GET /models and POST /models/{version}/activate."""
from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Path

from ...schemas import ErrorOut, ModelList
from ..deps import ApiKeyDep, ModelsDep
from ..errors import InputError
from ..routing import FiniteJSONRoute

router = APIRouter(tags=["models"], route_class=FiniteJSONRoute)


@router.get("/models", response_model=ModelList, summary="Registered model versions")
def list_models(models: ModelsDep) -> dict[str, Any]:
    return {"active": models.active_version(), "versions": models.versions()}


@router.post("/models/{version}/activate", response_model=ModelList, dependencies=[ApiKeyDep],
             summary="Make a registered version the active model (API key required)",
             responses={401: {"model": ErrorOut}, 403: {"model": ErrorOut},
                        404: {"model": ErrorOut, "description": "Unknown version."}})
def activate(version: Annotated[str, Path(min_length=1, max_length=128)], models: ModelsDep) -> dict[str, Any]:
    try:
        models.activate(version)
    except KeyError:
        known = [v["version"] for v in models.versions()]
        raise InputError(f"model version {version!r} is not registered; known versions: {known}", "not_found") from None
    return {"active": models.active_version(), "versions": models.versions()}
