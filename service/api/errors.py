"""Exception handlers: every client mistake becomes a 4xx whose ``detail`` says what to fix."""
from __future__ import annotations

from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import ValidationError


class InputError(ValueError):
    """A client mistake found by the service itself (mapped to ``status_code``, 422 by default)."""

    def __init__(self, message: str, status_code: int = 422) -> None:
        super().__init__(message)
        self.status_code = status_code


def validation_detail(exc: ValidationError | RequestValidationError, prefix: tuple = ()) -> list[dict[str, Any]]:
    """FastAPI-style error list, with long inputs (waveforms) cut out of the echo."""
    out = []
    for err in exc.errors():
        item = {"loc": list(prefix) + list(err.get("loc", ())), "msg": err.get("msg", ""), "type": err.get("type", "")}
        inp = err.get("input")
        if isinstance(inp, (int, float, bool, type(None))) or (isinstance(inp, str) and len(inp) <= 80):
            item["input"] = inp
        ctx = err.get("ctx")
        if ctx:
            item["ctx"] = {k: (v if isinstance(v, (int, float, str, bool, type(None))) else str(v))
                           for k, v in ctx.items()}
        out.append(item)
    return out


def install_error_handlers(app: FastAPI) -> None:
    """Register the handlers on ``app``."""

    @app.exception_handler(RequestValidationError)
    async def _request_validation(request: Request, exc: RequestValidationError) -> JSONResponse:
        return JSONResponse(status_code=422, content={"detail": validation_detail(exc)})

    @app.exception_handler(ValidationError)
    async def _model_validation(request: Request, exc: ValidationError) -> JSONResponse:
        return JSONResponse(status_code=422, content={"detail": validation_detail(exc, ("body",))})

    @app.exception_handler(InputError)
    async def _input_error(request: Request, exc: InputError) -> JSONResponse:
        return JSONResponse(status_code=exc.status_code, content={"detail": str(exc)})
