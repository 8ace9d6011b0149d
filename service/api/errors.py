"""Exception handlers: every client mistake becomes a 4xx whose ``detail`` says what to fix.

This module is where the service's and the lower layers' exceptions get HTTP statuses: the
features/models packages raise ``ValueError`` (a bad recording → 422) and the service's own
:class:`InputError` carries its status; :func:`raise_worker_error` maps what a diagnosis
worker answered (``service.pool``): a client mistake → its 4xx, no model → 503 (404 when the
request named a version), a request over the time limit → 422, a worker that died twice → 503; and a
database that cannot read or write (a full disk, a damaged file) → 503 saying which, never 500.
"""
from __future__ import annotations

import logging
from typing import Any, NoReturn

from fastapi import FastAPI, HTTPException, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import ValidationError
from sqlalchemy.exc import DatabaseError as SQLAlchemyDatabaseError

from ..errors import InputError, RequestInvalid, validation_detail
from ..schemas import ErrorOut

log = logging.getLogger("rotordiag.service")

#: HTTP status of each kind of client mistake (:class:`service.errors.InputError`)
STATUS_OF_KIND = {"invalid": 422, "malformed": 400, "unsupported_type": 415, "not_found": 404, "conflict": 409,
                  "too_large": 413}


#: how a route says which API key it needs (``error_responses(key=...)``): always, or only when
#: ROTORDIAG_DIAGNOSE_REQUIRES_KEY (the diagnosis routes)
_KEY_WHEN = {"always": "", "diagnose": " (only when ROTORDIAG_DIAGNOSE_REQUIRES_KEY)"}
#: what a route's body may be (``error_responses(body=...)``) as its 415 says it
_BODY_TYPES = {"json": "The body is not application/json.",
               "recording": "Content-Type is not JSON, NPY (application/octet-stream) or multipart."}


def error_responses(described: dict[int, str] | None = None, *, key: str | None = None,
                    body: str | None = None) -> dict[int | str, dict[str, Any]]:
    """A route's documented error answers (its ``responses=``), every one an ``ErrorOut``.

    Parameters
    ----------
    described : dict of int to str
        Status → what it means on this route (404, 409, 422, ...).
    key : {"always", "diagnose"}, optional
        The route needs the API key always, or only when ROTORDIAG_DIAGNOSE_REQUIRES_KEY: its 401 and 403.
    body : {"json", "recording"}, optional
        The route reads a JSON body, or a recording as /diagnose does: its 400 (cannot be decoded) and 415.
    """
    out: dict[int, str] = {}
    if body is not None:
        out[400] = "The body cannot be decoded (e.g. JSON that is not UTF-8)."
        out[415] = _BODY_TYPES[body]
    if key is not None:
        out[401] = f"No X-API-Key header{_KEY_WHEN[key]}."
        out[403] = f"Wrong API key{_KEY_WHEN[key]}."
    out.update(described or {})
    return {code: {"model": ErrorOut, "description": out[code]} for code in sorted(out)}


def raise_worker_error(answer: Any, *, version_given: bool = False) -> NoReturn:
    """Raise the HTTP error for a diagnosis worker's answer that is not ``("ok", ...)``.

    Parameters
    ----------
    answer : tuple or Exception
        The worker's tagged tuple (``service.pool._tagged``), or the pool's ``WorkerCrashed`` /
        ``DiagnosisTimeout``.
    version_given : bool
        The request named a model version (an unavailable model is then 404, not 503).
    """
    from ..pool import DiagnosisTimeout, WorkerCrashed

    if isinstance(answer, DiagnosisTimeout):
        limit = answer.args[0] if answer.args else "the"
        raise InputError(f"the recording took longer than the limit of {limit:g} s to analyse and was stopped; "
                         "send a shorter recording or fewer channels (or raise ROTORDIAG_DIAGNOSIS_TIMEOUT_S "
                         "on the server)")
    if isinstance(answer, WorkerCrashed):
        raise HTTPException(503, str(answer))
    tag = answer[0]
    if tag == "input":
        raise InputError(answer[2], answer[1])
    if tag == "request":
        raise RequestInvalid(answer[1])
    if tag == "unavailable":
        raise (InputError(answer[1], "not_found") if version_given else HTTPException(503, answer[1]))
    raise RuntimeError(f"unexpected answer from a diagnosis worker: {tag!r}")


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
        return JSONResponse(status_code=STATUS_OF_KIND[exc.kind], content={"detail": str(exc)})

    @app.exception_handler(SQLAlchemyDatabaseError)
    async def _database_error(request: Request, exc: SQLAlchemyDatabaseError) -> JSONResponse:
        # a full disk, a damaged or locked database: the server's state, not the request -> 503 saying what
        from ..store import database_error_text

        log.error("database error on %s %s: %s", request.method, request.url.path, exc.orig)
        return JSONResponse(status_code=503, headers={"Retry-After": "30"}, content={
            "detail": f"the database could not complete this request, nothing was stored: "
                      f"{database_error_text(exc)}"})

    @app.exception_handler(RequestInvalid)
    async def _request_invalid(request: Request, exc: RequestInvalid) -> JSONResponse:
        return JSONResponse(status_code=422, content={"detail": exc.errors})
