"""The FastAPI application: ``service.main:app`` (``rotordiag serve`` runs it with uvicorn).

``create_app(settings)`` builds an app; the module-level ``app`` reads its
settings from the environment. Side effects (data directory, database tables,
registry seeding, marking jobs interrupted by a previous shutdown) happen at
startup in the lifespan, not at import.
"""
from __future__ import annotations

import logging
from contextlib import asynccontextmanager

from fastapi import FastAPI

from rotordiag.core.version import __version__

from .api.auth import ApiKeyGate
from .api.errors import install_error_handlers
from .api.routes import alarms, assets, diagnose, health, jobs, models, trains
from .api.routes.docs import install_docs
from .api.routing import RelativeSlashRedirect
from .core.config import Settings
from .core.limits import BodySizeLimitMiddleware
from .metrics import install_metrics
from .web import router as web_router

log = logging.getLogger("rotordiag.service")

DESCRIPTION = """
Coupling-misalignment diagnosis for generator-exciter rotors from shaft-vibration waveforms.

* `POST /diagnose` — probe waveforms (JSON, binary NPY or a CSV/NPY/HDF5 upload) → severity class,
  probabilities, misalignment Δ = δ/c with an interval (and δ in µm when the clearance is given),
  motion type, key features, out-of-distribution flag.
* Jobs — `POST /datasets`, `POST /models/retrain`, `GET /jobs/{id}`: labelled datasets and models for your plant,
  run on Dask, kept in the database across restarts.
* `GET /assets/{id}/history` — the trend of an asset's diagnoses. `GET /health`, `GET /metrics`.

Write endpoints (jobs, activation) need the `X-API-Key` header. Units are in field names
(`_hz`, `_rpm`, `_um`, `_s`) or stated in each field's description.
"""


def create_app(settings: Settings | None = None) -> FastAPI:
    """Build the application.

    Parameters
    ----------
    settings : Settings, optional
        Defaults to ``Settings()`` read from the environment / ``.env``.
    """
    settings = settings if settings is not None else Settings()

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        from .state import AppState

        state = AppState.start(settings)
        app.state.rd = state
        try:
            yield
        finally:
            state.stop()

    app = FastAPI(
        title="rotordiag",
        version=__version__,
        description=DESCRIPTION,
        lifespan=lifespan,
        docs_url=None,       # /docs from the installed Swagger UI (service/api/routes/docs.py), never a CDN
        redoc_url=None,
        redirect_slashes=False,  # RelativeSlashRedirect: no Host header copied into Location
        openapi_tags=[
            {"name": "diagnose", "description": "Diagnose probe waveforms."},
            {"name": "jobs", "description": "Dataset generation and retraining jobs (run on Dask)."},
            {"name": "models", "description": "Model registry: list and activate versions."},
            {"name": "assets", "description": "Per-asset diagnosis history."},
            {"name": "trains", "description": "Shaft trains: presets, static bearing loads, stability margin."},
            {"name": "health", "description": "Liveness for orchestration."},
        ],
    )
    app.state.settings = settings
    install_error_handlers(app)
    for router in (diagnose.router, jobs.router, models.router, assets.router, alarms.router, trains.router,
                   health.router):
        app.include_router(router)
    app.include_router(web_router)  # the web page at / (issue 7; service/web, docs/web.md)
    install_docs(app)
    install_metrics(app)
    # Added last = outermost of the user middleware: bytes are counted (and timed) before anything reads
    # them, and the API key is checked from the headers before any body is read (service/api/auth.py).
    app.add_middleware(RelativeSlashRedirect)
    app.add_middleware(BodySizeLimitMiddleware, max_body_bytes=settings.max_body_bytes,
                       body_timeout_s=settings.body_timeout_s)
    app.add_middleware(ApiKeyGate)
    _document_auth(app, settings)
    return app


def _document_auth(app: FastAPI, settings: Settings) -> None:
    """OpenAPI schema as the server behaves: /diagnose and /diagnose/batch list the API key only when
    ROTORDIAG_DIAGNOSE_REQUIRES_KEY is set; the batch body (read raw, parsed in a worker) is described
    by ``BatchRequest``."""
    from fastapi.openapi.utils import get_openapi

    from .schemas import BatchRequest, DiagnoseRequest

    def openapi() -> dict:
        if app.openapi_schema is None:
            schema = get_openapi(title=app.title, version=app.version, description=app.description,
                                 routes=app.routes, tags=app.openapi_tags)
            components = schema.setdefault("components", {}).setdefault("schemas", {})
            for model in (DiagnoseRequest, BatchRequest):     # bodies read raw (parsed in a worker)
                extra = model.model_json_schema(ref_template="#/components/schemas/{model}")
                for name, sub in extra.pop("$defs", {}).items():
                    components.setdefault(name, sub)
                components.setdefault(model.__name__, extra)
            if not settings.diagnose_requires_key:
                for path in ("/diagnose", "/diagnose/batch"):
                    op = schema["paths"].get(path, {}).get("post", {})
                    op.pop("security", None)
                    op.get("responses", {}).pop("401", None)
                    op.get("responses", {}).pop("403", None)
            app.openapi_schema = schema
        return app.openapi_schema

    app.openapi = openapi  # type: ignore[method-assign]


app = create_app()
