"""GET /models, POST /models/{version}/activate and POST /models/rollback."""
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


@router.post("/models/rollback", response_model=ModelList, dependencies=[ApiKeyDep],
             summary="Re-activate the version that was active before the current one (API key required)",
             responses={401: {"model": ErrorOut}, 403: {"model": ErrorOut},
                        409: {"model": ErrorOut, "description": "No earlier activation to return to."}})
def rollback(models: ModelsDep) -> dict[str, Any]:
    """One call back to the previous model, as ``rotordiag models rollback`` (the registry's activation history)."""
    from rotordiag.models.registry import RegistryError

    try:
        models.registry.rollback()
    except RegistryError as exc:
        raise InputError(f"no rollback: {exc}", "conflict") from None
    return {"active": models.active_version(), "versions": models.versions()}
