"""Diagnosis worker processes: parse + features + verdict off the server process.

A diagnosis is CPU-bound Python (parsing, feature extraction, the verdict), so threads
in one process share one core through the GIL. With ``diagnosis_workers`` > 0 the
server keeps HTTP, the database and the jobs in its own process and sends each
request body, as the bytes it received, to a pool of worker processes (``spawn``:
no fork of a threaded server). Each worker keeps the model versions it has loaded
from the registry and reads the registry's ``active`` pointer on every request (or
uses the version the request names), so activating a model takes effect at once in
every worker.

What crosses the process boundary is the server's own data (the body bytes it read,
plain query values, the verdict dict): never anything unpickled from a client.
"""
from __future__ import annotations

import asyncio
import logging
import multiprocessing
import os
import threading
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any

log = logging.getLogger("rotordiag.service")

_STORE = None   # the worker process's ModelStore


def _init_worker(registry_root: str) -> None:
    """Worker start-up: one thread for every numeric library, open the registry."""
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"
    global _STORE
    from .inference import ModelStore

    _STORE = ModelStore(Path(registry_root))


def _warm(version: str | None) -> str:
    """Load ``version`` and compile its fast predictor before the first request needs it."""
    from models.predict import fast_predictor

    if version is not None:
        fast_predictor(_STORE.load(version).model)
    import features  # noqa: F401  (numba kernels load from cache)
    return f"pid {os.getpid()} ready"


def _load_check(version: str) -> str | None:
    """``None`` when this worker can load and use ``version``, else the reason it cannot."""
    from .inference import ModelUnavailable

    try:
        _warm(version)
    except ModelUnavailable as exc:
        return str(exc)
    return None


def _work(kind: str, body: bytes, filename: str, query: dict[str, Any], version: str | None) -> tuple:
    """Parse and diagnose one request in the worker; errors come back as tagged tuples.

    Returns ``("ok", verdict, asset_id, plant)``, ``("input", status, message)``,
    ``("http", status, detail)`` or ``("unavailable", message)``.
    """
    from fastapi import HTTPException

    from .api.errors import InputError
    from .inference import ModelUnavailable
    from .parsing import parse_body

    try:
        recording, asset_id, plant = parse_body(kind, body, filename, query)
        verdict = _STORE.diagnose(recording, version)
    except InputError as exc:
        return ("input", exc.status_code, str(exc))
    except HTTPException as exc:
        return ("http", exc.status_code, exc.detail)
    except ModelUnavailable as exc:
        return ("unavailable", str(exc))
    except ValueError as exc:   # the features/models packages' messages for bad recordings
        return ("input", 422, str(exc))
    return ("ok", verdict, asset_id, plant)


class WorkerCrashed(RuntimeError):
    """A diagnosis worker process died on a request (reported as 503)."""


class DiagnosisPool:
    """A ``ProcessPoolExecutor`` of diagnosis workers, restarted if a worker dies.

    Parameters
    ----------
    registry_root : Path
        The model registry the workers load from (the server's).
    n_workers : int
    """

    def __init__(self, registry_root: Path, n_workers: int) -> None:
        self.registry_root = Path(registry_root)
        self.n_workers = int(n_workers)
        self._lock = threading.Lock()
        self._loadable: set[str] = set()
        self._executor = self._new_executor()

    def _new_executor(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(max_workers=self.n_workers, mp_context=multiprocessing.get_context("spawn"),
                                   initializer=_init_worker, initargs=(str(self.registry_root),))

    def warm_up(self, version: str | None) -> None:
        """Start every worker and load ``version`` in each (in the background)."""
        for _ in range(self.n_workers):
            self._executor.submit(_warm, version)

    def check_model(self, version: str, timeout_s: float = 60.0) -> str | None:
        """``None`` when the workers can load ``version`` (remembered once true), else why not.

        Used by ``GET /health``, so the server process itself never loads a model.
        """
        if version in self._loadable:
            return None
        try:
            problem = self._executor.submit(_load_check, version).result(timeout=timeout_s)
        except TimeoutError:
            return f"diagnosis workers did not load model {version} within {timeout_s:g} s"
        except BrokenProcessPool:
            return "diagnosis worker processes stopped; the next diagnosis restarts them"
        if problem is None:
            self._loadable.add(version)
        return problem

    async def run(self, kind: str, body: bytes, filename: str, query: dict[str, Any],
                  version: str | None) -> tuple:
        """:func:`_work` in a worker process. A crashed worker (e.g. killed for memory) gets
        the pool restarted and the request retried once."""
        for attempt in (1, 2):
            executor = self._executor
            try:
                return await asyncio.wrap_future(executor.submit(_work, kind, body, filename, query, version))
            except BrokenProcessPool:
                log.error("a diagnosis worker process died; restarting the pool (attempt %d)", attempt)
                with self._lock:
                    if self._executor is executor:
                        executor.shutdown(wait=False, cancel_futures=True)
                        self._executor = self._new_executor()
        raise WorkerCrashed("the diagnosis worker stopped unexpectedly twice on this request; "
                            "if the recording is very large, send a shorter one")

    def shutdown(self) -> None:
        """Stop the workers (waits for the ones busy with a request)."""
        self._executor.shutdown(wait=True, cancel_futures=True)
