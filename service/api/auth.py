"""The API key is checked before the request body is read (an ASGI middleware).

FastAPI reads and decodes a route's JSON body before it runs the route's dependencies, so a
key check written only as a dependency lets a client without a key make the server read and
parse a body as large as ``ROTORDIAG_MAX_BODY_BYTES``. :class:`ApiKeyGate` runs first: it finds
the route a request is for, and when that route needs the key (its dependencies include
:func:`service.api.deps.require_api_key`, or :func:`service.api.deps.diagnose_key` while
``ROTORDIAG_DIAGNOSE_REQUIRES_KEY`` is set) it answers 401/403 from the headers alone, without
reading a byte of the body. The dependencies stay on the routes: they document the key in the
OpenAPI schema and check it again.
"""
from __future__ import annotations

import json
import secrets

from starlette.routing import Match
from starlette.types import ASGIApp, Receive, Scope, Send

from .deps import diagnose_key, require_api_key


def _needs_key(route, settings) -> bool:
    calls = {getattr(d, "dependency", None) for d in getattr(route, "dependencies", ())}
    return require_api_key in calls or (diagnose_key in calls and settings.diagnose_requires_key)


class ApiKeyGate:
    """Refuse requests to key-protected routes without the right ``X-API-Key`` before the body is read."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        application = scope.get("app")
        state = getattr(getattr(application, "state", None), "rd", None)
        if state is not None and application is not None:
            for route in application.router.routes:
                match, _ = route.matches(scope)
                if match == Match.FULL:
                    if _needs_key(route, state.settings):
                        problem = _key_problem(scope, state.settings.effective_api_key)
                        if problem is not None:
                            await _refuse(send, *problem)
                            return
                    break
        await self.app(scope, receive, send)


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


async def _refuse(send: Send, status: int, detail: str) -> None:
    body = json.dumps({"detail": detail}).encode()
    headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
               (b"connection", b"close")]
    if status == 401:
        headers.append((b"www-authenticate", b"APIKey"))
    await send({"type": "http.response.start", "status": status, "headers": headers})
    await send({"type": "http.response.body", "body": body})
