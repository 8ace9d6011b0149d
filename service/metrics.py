"""Prometheus metrics of this replica: request latency histograms (prometheus-fastapi-instrumentator), the
replica's name (``rotordiag_replica_info{replica}``), the jobs it runs and has taken over, plus job counts and,
per asset with a baseline, the latest change against it (``rotordiag_asset_change{asset, quantity}``) and
its trend alarm (``rotordiag_asset_alarm{asset}``), the level of each setpoint alarm
(``rotordiag_asset_setpoint_level{asset, quantity}``), webhook deliveries per status
(``rotordiag_webhook_deliveries{status}``), and per asset the storage its history uses
(``rotordiag_asset_history_bytes{asset}``, ``rotordiag_asset_history_rows{asset, kind}``).

Each app gets its own ``CollectorRegistry`` so several apps (tests) can live in one process. Request
figures are per replica: scrape every replica, not the load balancer (docs/service.md).
"""
from __future__ import annotations

import collections
from typing import Any

from fastapi import FastAPI
from prometheus_client import CollectorRegistry
from prometheus_client.core import CounterMetricFamily, GaugeMetricFamily
from prometheus_fastapi_instrumentator import Instrumentator
from prometheus_fastapi_instrumentator.middleware import PrometheusInstrumentatorMiddleware

#: request routes whose handler label is kept (method, root path, path): the busy paths of a replica
_HANDLER_CACHE_SIZE = 4096


class _CachedHandlerMiddleware(PrometheusInstrumentatorMiddleware):
    """The instrumentator's middleware with each request's handler label (its route template) remembered.

    The library finds the label by matching the request against every route of the app, on every request: about
    1 ms of the server's time per ``POST /diagnose`` with this app's 80 routes. The label depends on the method, the
    root path and the path alone (the routes are fixed once the app runs), so the last
    ``_HANDLER_CACHE_SIZE`` of them are kept (least recently used out: hostile unique paths cannot grow it).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._handlers: collections.OrderedDict[tuple[str, str, str], tuple[str, bool]] = collections.OrderedDict()

    def _get_handler(self, request: Any) -> tuple[str, bool]:
        key = (request.method, request.scope.get("root_path", ""), request.scope.get("path", ""))
        found = self._handlers.get(key)
        if found is not None:
            self._handlers.move_to_end(key)
            return found
        found = super()._get_handler(request)
        self._handlers[key] = found
        if len(self._handlers) > _HANDLER_CACHE_SIZE:
            self._handlers.popitem(last=False)
        return found


class _JobCollector:
    """Reads job counts per status (and stored diagnoses) from the database at scrape time."""

    def __init__(self, app: FastAPI) -> None:
        self.app = app

    def describe(self):
        return []

    def collect(self):
        state = getattr(self.app.state, "rd", None)
        if state is None:
            return
        jobs = GaugeMetricFamily("rotordiag_jobs", "Jobs per status, from the database.", labels=["status"])
        for status, n in state.jobs.counts().items():
            jobs.add_metric([status], n)
        yield jobs
        replica = GaugeMetricFamily("rotordiag_replica_info", "This replica's name (value 1).", labels=["replica"])
        replica.add_metric([state.jobs.replica], 1)
        yield replica
        yield GaugeMetricFamily("rotordiag_replica_jobs_held", "Jobs this replica is running.",
                                value=state.jobs.held())
        yield CounterMetricFamily("rotordiag_replica_job_takeovers", "Jobs this replica claimed after their "
                                  "holder's lease ran out.", value=state.jobs.takeovers)
        model = GaugeMetricFamily("rotordiag_active_model_info", "Active model version (value 1).", labels=["version"])
        version = state.models.active_version()
        if version is not None:
            model.add_metric([version], 1)
        yield model
        yield from _asset_metrics(state)


def _asset_metrics(state):
    """The change quantities (largest over the bearings; µm, µm pk-pk or 1) of each asset's latest diagnosis
    compared with its baseline, and whether its trend alarm is raised (1) or not (0)."""
    from rotordiag.models.change import QUANTITIES

    from .store import latest_changes

    change = GaugeMetricFamily("rotordiag_asset_change", "Latest change against the asset's baseline, per quantity "
                               "(largest over the bearings; units as the quantity name).", labels=["asset", "quantity"])
    alarm = GaugeMetricFamily("rotordiag_asset_alarm", "1 while the asset's trend alarm is raised.", labels=["asset"])
    with state.sessions() as s:
        rows = latest_changes(s)
    for asset, ch in rows:
        for q, info in (ch.get("quantities") or {}).items():
            if isinstance(info, dict) and info.get("value") is not None:
                change.add_metric([asset, QUANTITIES[q][0] if q in QUANTITIES else q], float(info["value"]))
        alarm.add_metric([asset], 1.0 if ch.get("changed") else 0.0)
    yield change
    yield alarm
    yield from _setpoint_metrics(state)
    yield from _history_metrics(state)


def _setpoint_metrics(state):
    """Per asset and setpoint quantity the level it is at (0 normal, 1 alert, 2 danger; ``service.alarms``),
    and the webhook deliveries per status."""
    from sqlalchemy import func, select

    from .alarms import CHANGE, LEVELS, current_levels
    from .core.db import AlarmEvent, WebhookDelivery

    level = GaugeMetricFamily("rotordiag_asset_setpoint_level", "Alarm level per asset and setpoint quantity: "
                              "0 normal, 1 alert, 2 danger.", labels=["asset", "quantity"])
    deliveries = GaugeMetricFamily("rotordiag_webhook_deliveries", "Webhook deliveries per status, from the "
                                   "database.", labels=["status"])
    with state.sessions() as s:
        assets = list(s.scalars(select(AlarmEvent.asset_id).distinct()))
        for asset in assets:
            for q, lv in current_levels(s, asset).items():
                if q != CHANGE:
                    level.add_metric([asset, q], float(LEVELS.index(lv)))
        for status, n in s.execute(select(WebhookDelivery.status, func.count()).group_by(WebhookDelivery.status)):
            deliveries.add_metric([status], float(n))
    yield level
    yield deliveries


#: how long the per-asset storage figures are reused between scrapes, s (they scan the history table)
HISTORY_SIZES_TTL_S = 30.0
_SIZES_CACHE: dict[int, tuple[float, list]] = {}


def _history_metrics(state):
    """Per asset: the bytes its stored history holds and its full diagnoses and summaries (the retention
    settings bound both; ``service.store.apply_retention``)."""
    import time

    from .store import history_sizes

    now = time.monotonic()
    cached = _SIZES_CACHE.get(id(state))
    if cached is None or now - cached[0] > HISTORY_SIZES_TTL_S:
        with state.sessions() as s:
            cached = (now, history_sizes(s))
        _SIZES_CACHE.clear()
        _SIZES_CACHE[id(state)] = cached
    size = GaugeMetricFamily("rotordiag_asset_history_bytes", "Bytes of stored diagnoses per asset (the JSON of "
                             "verdicts, key features, signatures and changes), refreshed every 30 s.", labels=["asset"])
    rows = GaugeMetricFamily("rotordiag_asset_history_rows", "Stored diagnoses per asset: `full` (with verdict and "
                             "signature) or `summary` (past the retention of full records).", labels=["asset", "kind"])
    for asset, n_bytes, n_full, n_summary in cached[1]:
        size.add_metric([asset], float(n_bytes))
        rows.add_metric([asset, "full"], float(n_full))
        rows.add_metric([asset, "summary"], float(n_summary))
    yield size
    yield rows


def install_metrics(app: FastAPI) -> None:
    """Instrument every route and expose ``GET /metrics``."""
    registry = CollectorRegistry(auto_describe=True)
    instrumentator = Instrumentator(
        registry=registry, excluded_handlers=["/metrics"], should_group_status_codes=False,
    )
    instrumentator.instrument(
        app, latency_lowr_buckets=(0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10),
    )
    for entry in app.user_middleware:       # the same middleware, its route lookup remembered
        if entry.cls is PrometheusInstrumentatorMiddleware:
            entry.cls = _CachedHandlerMiddleware
    instrumentator.expose(app, endpoint="/metrics", include_in_schema=False)
    registry.register(_JobCollector(app))
    app.state.metrics_registry = registry
