"""Domain exceptions of the service: what went wrong, in the client's terms, with no HTTP in them.

Parsing (:mod:`service.parsing`), the job and retraining work (:mod:`service.work`), the
diagnosis workers (:mod:`service.pool`) and the stores raise these; only the API layer
(:mod:`service.api.errors`) turns them into HTTP answers, choosing the status from the
exception's ``kind``. So a worker process never handles a FastAPI type, and the same
exception can be reported by the CLI or a job without a web framework.
"""
from __future__ import annotations

import math
from typing import Any, Literal

#: what kind of client mistake an :class:`InputError` is (the API maps each to a status)
InputKind = Literal["invalid", "malformed", "unsupported_type", "not_found", "conflict", "too_large"]


class InputError(ValueError):
    """A client mistake found by the service; the message says what to fix.

    Parameters
    ----------
    message : str
    kind : {"invalid", "malformed", "unsupported_type", "not_found", "conflict", "too_large"}
        ``invalid``: the content cannot be used (default); ``malformed``: the request itself is
        broken; ``unsupported_type``: a file or content type that is not read; ``not_found``: a
        named model, job, asset or diagnosis does not exist; ``conflict``: the state does not allow it;
        ``too_large``: the request holds more values than the service reads (refused before decoding).
    """

    def __init__(self, message: str, kind: InputKind = "invalid") -> None:
        super().__init__(message)
        self.kind: InputKind = kind


class RequestInvalid(ValueError):
    """A request body failed its schema; ``errors`` is the field-by-field list (nothing non-finite echoed)."""

    def __init__(self, errors: list[dict[str, Any]]) -> None:
        super().__init__(f"{len(errors)} invalid field(s)")
        self.errors = errors


def _echoable(value: Any) -> bool:
    """A value safe to echo in JSON: no NaN or infinity (JSON has none; rendering one would fail)."""
    if isinstance(value, float):
        return math.isfinite(value)
    return isinstance(value, (int, bool, type(None))) or (isinstance(value, str) and len(value) <= 80)


def validation_detail(exc: Any, prefix: tuple = ()) -> list[dict[str, Any]]:
    """Field-by-field error list of a pydantic/FastAPI validation error, long inputs (waveforms) cut out.

    Parameters
    ----------
    exc : pydantic.ValidationError or fastapi.exceptions.RequestValidationError
        Anything with an ``errors()`` method giving pydantic's error dicts.
    prefix : tuple
        Prepended to every ``loc`` (e.g. ``("body",)``).
    """
    out = []
    for err in exc.errors():
        item = {"loc": list(prefix) + list(err.get("loc", ())), "msg": err.get("msg", ""), "type": err.get("type", "")}
        inp = err.get("input")
        if _echoable(inp):
            item["input"] = inp
        ctx = err.get("ctx")
        if ctx:
            item["ctx"] = {k: (v if _echoable(v) else str(v)) for k, v in ctx.items()}
        out.append(item)
    return out
