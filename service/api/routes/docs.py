"""``/docs`` (Swagger UI) and ``/redoc`` (ReDoc) served from files installed with the package.

Both distributions come from the pinned ``fastapi-standalone-docs`` package on PyPI
(Swagger UI 5.x, which renders FastAPI's OpenAPI 3.1, and ReDoc 2.5 standalone). Only its
static files are used, through the fixed table :data:`_ASSETS` below — its
``StandaloneDocs`` helper patches ``fastapi.applications`` globally and is not called.
Nothing is fetched from a CDN; ReDoc is told not to load Google fonts.
"""
from __future__ import annotations

from pathlib import Path

from fastapi import APIRouter, FastAPI
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
from fastapi.responses import FileResponse, HTMLResponse

from ..errors import InputError

#: the only files served from the Swagger UI distribution (no path is built from the request)
_ASSETS = {"swagger-ui-bundle.js": ("swagger", "text/javascript; charset=utf-8"),
           "swagger-ui.css": ("swagger", "text/css; charset=utf-8"),
           "redoc.standalone.js": ("redoc", "text/javascript; charset=utf-8"),
           "favicon.png": ("fastapi", "image/png")}


def docs_static_dir() -> Path:
    """Folder of the installed Swagger UI / ReDoc distributions (``fastapi-standalone-docs``)."""
    import fastapi_standalone_docs

    return Path(fastapi_standalone_docs.__path__[0]) / "static"


def install_docs(app: FastAPI) -> None:
    """Add ``/docs``, ``/redoc`` and their assets to an app created with ``docs_url=None, redoc_url=None``."""
    router = APIRouter(include_in_schema=False)

    @router.get("/docs")
    def docs() -> HTMLResponse:
        return get_swagger_ui_html(openapi_url=app.openapi_url or "/openapi.json", title=f"{app.title} — API",
                                   swagger_js_url="/docs/assets/swagger-ui-bundle.js",
                                   swagger_css_url="/docs/assets/swagger-ui.css",
                                   swagger_favicon_url="/docs/assets/favicon.png")

    @router.get("/docs/assets/{name}")
    def asset(name: str) -> FileResponse:
        found = _ASSETS.get(name)
        if found is None:
            raise InputError(f"no documentation asset {name!r}", "not_found")
        folder, media = found
        return FileResponse(docs_static_dir() / folder / name, media_type=media,
                            headers={"Cache-Control": "public, max-age=86400"})

    @router.get("/redoc")
    def redoc() -> HTMLResponse:
        return get_redoc_html(openapi_url=app.openapi_url or "/openapi.json", title=f"{app.title} — API reference",
                              redoc_js_url="/docs/assets/redoc.standalone.js",
                              redoc_favicon_url="/docs/assets/favicon.png", with_google_fonts=False)

    app.include_router(router)
