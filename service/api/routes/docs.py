"""``/docs`` (Swagger UI) served from files installed with the package: nothing from a CDN.

The Swagger UI distribution comes from the pinned ``swagger-ui-bundle-v2`` package on PyPI
(import name ``swagger_ui_bundle``; Swagger UI 5.31.0 — 4.x cannot render FastAPI's OpenAPI 3.1)
and is served under ``/docs/assets/``. ``/redoc`` sends the browser to
``/docs``: the only ReDoc build on PyPI (``drf-spectacular-sidecar``) installs Django with it.
"""
from __future__ import annotations

from pathlib import Path

from fastapi import APIRouter, FastAPI
from fastapi.openapi.docs import get_swagger_ui_html
from fastapi.responses import FileResponse, HTMLResponse, RedirectResponse

from ..errors import InputError

#: the only files served from the Swagger UI distribution (no path is built from the request)
_ASSETS = {"swagger-ui-bundle.js": "text/javascript; charset=utf-8", "swagger-ui.css": "text/css; charset=utf-8",
           "favicon-32x32.png": "image/png"}


def swagger_ui_dir() -> Path:
    """Folder of the installed Swagger UI distribution."""
    import swagger_ui_bundle

    return Path(swagger_ui_bundle.swagger_ui_path)


def install_docs(app: FastAPI) -> None:
    """Add ``/docs``, its assets and ``/redoc`` to an app created with ``docs_url=None, redoc_url=None``."""
    router = APIRouter(include_in_schema=False)

    @router.get("/docs")
    def docs() -> HTMLResponse:
        return get_swagger_ui_html(openapi_url=app.openapi_url or "/openapi.json", title=f"{app.title} — API",
                                   swagger_js_url="/docs/assets/swagger-ui-bundle.js",
                                   swagger_css_url="/docs/assets/swagger-ui.css",
                                   swagger_favicon_url="/docs/assets/favicon-32x32.png")

    @router.get("/docs/assets/{name}")
    def asset(name: str) -> FileResponse:
        media = _ASSETS.get(name)
        if media is None:
            raise InputError(f"no documentation asset {name!r}", 404)
        return FileResponse(swagger_ui_dir() / name, media_type=media,
                            headers={"Cache-Control": "public, max-age=86400"})

    @router.get("/redoc")
    def redoc() -> RedirectResponse:
        return RedirectResponse("/docs", status_code=307)

    app.include_router(router)
