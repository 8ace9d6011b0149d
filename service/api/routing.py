"""Route class whose JSON bodies refuse non-finite numbers (``NaN``, ``Infinity``, ``1e999``).

FastAPI decodes a JSON body with ``Request.json()`` (Python's ``json.loads``, which accepts
``NaN`` and ``Infinity`` and turns ``1e999`` into infinity). Every router of the API uses
:class:`FiniteJSONRoute`, whose request decodes with :func:`features.safe_io.loads_json_finite`
instead, so a non-finite number is a 422 that says what to send — before validation, so it
never reaches a model field typed ``Any`` or a validation message that would echo it. A body that may hold
more values than ``schemas.MAX_BATCH_VALUES`` is a 413, counted before it is decoded; nesting deeper than
``features.safe_io.MAX_JSON_DEPTH`` is a 422.
"""
from __future__ import annotations

from collections.abc import Callable, Coroutine
from typing import Any

from fastapi import HTTPException, Request, Response
from fastapi.routing import APIRoute


class _FiniteJSONRequest(Request):
    async def json(self) -> Any:
        if not hasattr(self, "_json"):
            from rotordiag.features.safe_io import UnsafeFileError, count_json_values, loads_json_finite

            from ..schemas import MAX_BATCH_VALUES

            body = await self.body()
            try:
                count_json_values(body, MAX_BATCH_VALUES)
            except UnsafeFileError as exc:
                raise HTTPException(413, str(exc)) from None
            try:
                self._json = loads_json_finite(body)
            except UnsafeFileError as exc:
                raise HTTPException(422, str(exc)) from None
        return self._json


class FiniteJSONRoute(APIRoute):
    """``APIRoute`` whose JSON bodies are decoded by ``loads_json_finite`` (see the module docstring)."""

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        handler = super().get_route_handler()

        async def finite_json_handler(request: Request) -> Response:
            return await handler(_FiniteJSONRequest(request.scope, request.receive))

        return finite_json_handler


class RelativeSlashRedirect:
    """Redirect ``/path/`` to ``/path`` with a *relative* ``Location`` (Starlette's own redirect builds an absolute
    URL from the request's ``Host`` header, which a client chooses: the answer would point wherever it said).

    Used with ``redirect_slashes=False`` on the app; only paths whose slash-less form is a route are redirected
    (307, the method and body kept), everything else goes on to the app (a 404 for an unknown path).
    """

    def __init__(self, app: Any) -> None:
        self.app = app

    async def __call__(self, scope: Any, receive: Any, send: Any) -> None:
        path = scope.get("path", "") if scope["type"] == "http" else ""
        if len(path) > 1 and path.endswith("/"):
            from starlette.routing import Match

            stripped = path.rstrip("/") or "/"
            probe = {**scope, "path": stripped}
            router = scope["app"].router if "app" in scope else None
            if router is not None and any(r.matches(probe)[0] != Match.NONE for r in router.routes):
                query = scope.get("query_string", b"")
                location = stripped + ("?" + query.decode("latin-1") if query else "")
                await send({"type": "http.response.start", "status": 307,
                            "headers": [(b"location", location.encode("latin-1")), (b"content-length", b"0")]})
                await send({"type": "http.response.body", "body": b""})
                return
        await self.app(scope, receive, send)
