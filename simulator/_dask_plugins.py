"""Worker plugins of the local Dask clusters rotordiag starts (:func:`simulator.runner.start_local_cluster`).

Imported by the worker processes when the plugin is registered; kept apart from the runner so that importing the
runner does not import ``distributed``.
"""
from __future__ import annotations

import logging
from typing import Any

from distributed.diagnostics.plugin import WorkerPlugin

__all__ = ["HEARTBEAT_RACE_MESSAGE", "HeartbeatRaceFilter", "QuietHeartbeatRace"]

#: the start of what ``distributed.Worker.heartbeat`` logs, at ERROR with a traceback, when its heartbeat meets a
#: closed comm; at shutdown that is the scheduler closing while the worker is busy in a task (a race inside
#: ``distributed``'s shutdown, known upstream: dask/distributed#9032), not a fault of the run
HEARTBEAT_RACE_MESSAGE = "Failed to communicate with scheduler during heartbeat"


class HeartbeatRaceFilter(logging.Filter):
    """A failed heartbeat logged as a one-line warning, without its traceback; other records unchanged.

    A worker whose heartbeat finds the scheduler's comm closed keeps running and tries again at the next beat
    (``distributed`` handles a scheduler that is gone elsewhere); at ERROR with a traceback, the shutdown race
    reads as a crash in the server's log. The record is dropped when its logger does not log warnings (the local
    clusters log errors only).
    """

    def filter(self, record: logging.LogRecord) -> bool:
        if not str(record.msg).startswith(HEARTBEAT_RACE_MESSAGE):
            return True
        record.levelno, record.levelname = logging.WARNING, logging.getLevelName(logging.WARNING)
        record.exc_info, record.exc_text = None, None
        return logging.getLogger(record.name).isEnabledFor(logging.WARNING)


class QuietHeartbeatRace(WorkerPlugin):
    """:class:`HeartbeatRaceFilter` on the worker process's ``distributed.worker`` logger while the worker lives."""

    name = "rotordiag-heartbeat-race"

    def __init__(self) -> None:
        self.log_filter = HeartbeatRaceFilter()

    def setup(self, worker: Any) -> None:
        logging.getLogger("distributed.worker").addFilter(self.log_filter)

    def teardown(self, worker: Any) -> None:
        logging.getLogger("distributed.worker").removeFilter(self.log_filter)
