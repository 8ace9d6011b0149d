"""Route class whose JSON bodies refuse non-finite numbers (``NaN``, ``Infinity``, ``1e999``).

FastAPI decodes a JSON body with ``Request.json()`` (Python's ``json.loads``, which accepts
``NaN`` and ``Infinity`` and turns ``1e999`` into infinity). Every router of the API uses
:class:`FiniteJSONRoute`, whose request decodes with :func:`features.safe_io.loads_json_finite`
instead, so a non-finite number is a 422 that says what to send — before validation, so it
never reaches a model field typed ``Any`` or a validation message that would echo it.
"""
from __future__ import annotations

from collections.abc import Callable, Coroutine
from typing import Any

from fastapi import HTTPException, Request, Response
from fastapi.routing import APIRoute


class _FiniteJSONRequest(Request):
    async def json(self) -> Any:
        if not hasattr(self, "_json"):
            from rotordiag.features.safe_io import UnsafeFileError, loads_json_finite

            body = await self.body()
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
