"""GET /models, GET /models/{version}, POST /models/{version}/activate and POST /models/rollback."""
from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Path, Query

from ...schemas import ErrorOut, ModelDetail, ModelList
from ..deps import ApiKeyDep, ModelsDep
from ..errors import InputError
from ..routing import FiniteJSONRoute

router = APIRouter(tags=["models"], route_class=FiniteJSONRoute)


@router.get("/models", response_model=ModelList, summary="Registered model versions")
def list_models(models: ModelsDep) -> dict[str, Any]:
    return {"active": models.active_version(), "versions": models.versions()}


_Version = Annotated[str, Path(min_length=1, max_length=128)]


def _unknown(version: str, models: Any) -> InputError:
    known = [v["version"] for v in models.versions()]
    return InputError(f"model version {version!r} is not registered; known versions: {known}", "not_found")


@router.get("/models/{version}", response_model=ModelDetail, summary="One version: its card and plant report",
            responses={404: {"model": ErrorOut, "description": "Unknown version."}})
def show(version: _Version, models: ModelsDep) -> dict[str, Any]:
    """The card of ``version`` and, for a plant-retrained version, its quality report (``plant_report.json``)."""
    import json

    from rotordiag.models.plant_retrain import REPORT_FILE

    card = next((v for v in models.versions() if v["version"] == version), None)
    if card is None:
        raise _unknown(version, models)
    path = models.root / version / REPORT_FILE
    try:
        report = json.loads(path.read_text(encoding="utf-8")) if path.is_file() else None
    except (OSError, ValueError):
        report = {"error": f"{REPORT_FILE} unreadable"}
    return {**card, "plant_report": report}


@router.post("/models/{version}/activate", response_model=ModelList, dependencies=[ApiKeyDep],
             summary="Make a registered version the active model (API key required)",
             responses={401: {"model": ErrorOut}, 403: {"model": ErrorOut},
                        404: {"model": ErrorOut, "description": "Unknown version."},
                        409: {"model": ErrorOut, "description": "A plant-retrained version whose quality report says "
                              "it is not better (or is not written yet), without `force=true`; `detail` says why."}})
def activate(version: _Version, models: ModelsDep,
             force: Annotated[bool, Query(description="Activate a plant-retrained version even if its quality report "
                                                      "says it is not better (recorded: `activated_by` = `forced`).")]
             = False) -> dict[str, Any]:
    from rotordiag.models.registry import ActivationRefused

    try:
        models.activate(version, force=force)
    except KeyError:
        raise _unknown(version, models) from None
    except ActivationRefused as exc:
        raise InputError(str(exc), "conflict") from None
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
