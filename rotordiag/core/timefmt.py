"""Timestamps as a plant engineer reads them: ``2026-03-02 10:00 UTC``, not ``2026-03-02T10:00:00.123456+00:00``."""
from __future__ import annotations

import datetime as dt

__all__ = ["readable_time"]


def readable_time(value: str | dt.datetime | None) -> str:
    """``value`` (an ISO 8601 text or a datetime; naive means UTC, as the service stores it) as
    ``YYYY-MM-DD HH:MM UTC``; a text that is no timestamp is returned as it is, None as ``"—"``."""
    if value is None:
        return "—"
    if isinstance(value, str):
        try:
            when = dt.datetime.fromisoformat(value.strip().replace("Z", "+00:00"))
        except ValueError:
            return value
    else:
        when = value
    if when.tzinfo is not None:
        when = when.astimezone(dt.UTC)
    return when.strftime("%Y-%m-%d %H:%M UTC")
