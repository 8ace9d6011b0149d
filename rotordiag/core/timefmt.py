"""Timestamps as a plant engineer reads them: ``2026-03-02 10:00 UTC``, not ``2026-03-02T10:00:00.123456+00:00``."""
from __future__ import annotations

import datetime as dt

__all__ = ["iso_utc", "readable_time"]


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


def iso_utc(value: dt.datetime | None) -> str | None:
    """``value`` as the API writes times: ISO 8601, a naive datetime read as UTC (as the service stores it) and
    UTC written ``Z`` (``2026-03-02T10:00:00Z``); None stays None."""
    if value is None:
        return None
    if value.tzinfo is None:
        value = value.replace(tzinfo=dt.UTC)
    return value.isoformat().replace("+00:00", "Z")
