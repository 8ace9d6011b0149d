"""The API key is checked before the request body is read (an ASGI middleware).

FastAPI reads and decodes a route's JSON body before it runs the route's dependencies, so a
key check written only as a dependency lets a client without a key make the server read and
parse a body as large as ``ROTORDIAG_MAX_BODY_BYTES``. :class:`ApiKeyGate` wraps ``receive``:
the first time anything asks for the body, the router has already chosen the route
(``scope["route"]``, set by Starlette's router); when that route needs the key (its
dependencies include :func:`service.api.deps.require_api_key`, or
:func:`service.api.deps.diagnose_key` while ``ROTORDIAG_DIAGNOSE_REQUIRES_KEY`` is set) and the
``X-API-Key`` header is missing or wrong, the request is answered 401/403 (with
``Connection: close``) without a byte of the body read. The dependencies stay on the routes:
they document the key in the OpenAPI schema and refuse requests that carry no body.
"""
from __future__ import annotations

import secrets

from starlette.exceptions import HTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from .deps import diagnose_key, require_api_key


def _needs_key(route, settings) -> bool:
    calls = {getattr(d, "dependency", None) for d in getattr(route, "dependencies", ()) or ()}
    return require_api_key in calls or (diagnose_key in calls and settings.diagnose_requires_key)


class ApiKeyGate:
    """Refuse requests to key-protected routes without the right ``X-API-Key`` before their body is read."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        checked = False

        async def gated_receive() -> Message:
            nonlocal checked
            if not checked:
                checked = True
                state = getattr(getattr(scope.get("app"), "state", None), "rd", None)
                route = scope.get("route")
                if state is not None and route is not None and _needs_key(route, state.settings):
                    problem = _key_problem(scope, state.settings.effective_api_key)
                    if problem is not None:
                        headers = {"Connection": "close"}
                        if problem[0] == 401:
                            headers["WWW-Authenticate"] = "APIKey"
                        raise HTTPException(problem[0], problem[1], headers=headers)
            return await receive()

        await self.app(scope, gated_receive, send)


def _key_problem(scope: Scope, expected: str) -> tuple[int, str] | None:
    key = None
    for name, value in scope.get("headers", ()):
        if name == b"x-api-key":
            key = value
            break
    if not key:
        return 401, "this endpoint needs the API key in the X-API-Key header"
    if not secrets.compare_digest(key, expected.encode()):
        return 403, "the X-API-Key header does not match the server's API key"
    return None
