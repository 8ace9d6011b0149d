"""ASGI middleware that bounds request bodies by counting the bytes as they arrive, and by time.

A ``Content-Length`` check alone is bypassed by ``Transfer-Encoding: chunked``
uploads, so the declared length is checked up front (early 413) *and* every
``http.request`` message is counted; the first byte over the limit aborts the
request with 413 whatever the application was doing with the body.

A client has ``body_timeout_s`` from the moment its headers arrived to send the whole body;
a slower one (a half-sent body, a drip-feed) is answered 408 with ``Connection: close`` and
cut off. Bodies are read before any diagnosis worker is given the request, so a slow client
holds a connection, never a worker.
"""
from __future__ import annotations

import asyncio
import json
import time

from starlette.exceptions import HTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send


class BodyTooLarge(HTTPException):
    """Raised from ``receive`` when the body passes the limit (a 413 for the exception handlers)."""

    def __init__(self, limit: int) -> None:
        super().__init__(
            status_code=413,
            detail=f"request body is larger than the limit of {limit} bytes; send fewer or shorter "
            "records (split a batch), use the binary NPY form with float32, or raise "
            "ROTORDIAG_MAX_BODY_BYTES on the server",
        )


class BodyTimeout(HTTPException):
    """Raised from ``receive`` when the body has not arrived in time (a 408 for the exception handlers)."""

    def __init__(self, timeout_s: float) -> None:
        super().__init__(
            status_code=408,
            detail=f"the request body did not arrive within {timeout_s:g} s; send it in one go (the server "
            "closes connections whose body stalls; ROTORDIAG_BODY_TIMEOUT_S)",
            headers={"Connection": "close"},
        )


class BodySizeLimitMiddleware:
    """Refuse request bodies larger than ``max_body_bytes`` with 413, and slower than ``body_timeout_s`` with 408.

    Parameters
    ----------
    app : ASGI application
    max_body_bytes : int
        Largest body accepted, in bytes.
    body_timeout_s : float, optional
        Time for the whole body, counted from when the request reached the application.
    """

    def __init__(self, app: ASGIApp, max_body_bytes: int, body_timeout_s: float | None = None) -> None:
        self.app = app
        self.max_body_bytes = int(max_body_bytes)
        self.body_timeout_s = body_timeout_s

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        limit = self.max_body_bytes
        for name, value in scope.get("headers", ()):
            if name == b"content-length":
                try:
                    declared = int(value)
                except ValueError:
                    await _send_error(send, 400, "Content-Length header is not an integer")
                    return
                if declared > limit:
                    await _send_error(send, 413, BodyTooLarge(limit).detail)
                    return
        received = 0
        response_started = False
        body_done = False
        timeout_s = self.body_timeout_s
        deadline = time.monotonic() + timeout_s if timeout_s else None

        async def counting_receive() -> Message:
            nonlocal received, body_done
            if body_done or deadline is None or timeout_s is None:
                message = await receive()       # after the body: waiting for a disconnect is not timed
            else:
                try:
                    async with asyncio.timeout(max(deadline - time.monotonic(), 0.0)):
                        message = await receive()
                except TimeoutError:
                    raise BodyTimeout(timeout_s) from None
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > limit:
                    raise BodyTooLarge(limit)
                if not message.get("more_body", False):
                    body_done = True
            return message

        async def tracking_send(message: Message) -> None:
            nonlocal response_started
            if message["type"] == "http.response.start":
                response_started = True
            await send(message)

        try:
            await self.app(scope, counting_receive, tracking_send)
        except (BodyTooLarge, BodyTimeout) as exc:
            # Reached only if nothing inside turned the exception into a response.
            if not response_started:
                await _send_error(send, exc.status_code, exc.detail)


async def _send_error(send: Send, status: int, detail: str) -> None:
    body = json.dumps({"detail": detail}).encode()
    await send({
        "type": "http.response.start", "status": status,
        "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
                    (b"connection", b"close")],
    })
    await send({"type": "http.response.body", "body": body})
