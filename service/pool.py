"""Diagnosis worker processes: parse + features + verdict off the server process.

A diagnosis is CPU-bound Python (parsing, feature extraction, the verdict), so threads
in one process share one core through the GIL. With ``diagnosis_workers`` > 0 the
server keeps HTTP, the database and the jobs in its own process and sends each
request body, as the bytes it received, to one of N worker processes (``spawn``: no
fork of a threaded server). Each worker keeps the model versions it has loaded from
the registry and reads the registry's ``active`` pointer on every request (or uses the
version the request names), so activating a model takes effect at once in every
worker.

Transport: one Unix socket pair per worker, driven by the server's event loop
(``loop.sock_sendall`` / ``sock_recv_into``) — no executor threads handing work and
the GIL back and forth — with two requests in flight per worker so that a worker
never waits for the server between requests. Messages are length-prefixed pickles of the server's own data (the
body bytes it read, plain query values, the verdict dict); nothing a client sent is
ever unpickled — the body travels as opaque bytes and is parsed by
:func:`service.parsing.parse_body`.

A worker that dies (killed for memory, a crash in native code) is replaced, and the
request it held is retried once on a live worker.
"""
from __future__ import annotations

import asyncio
import atexit
import collections
import logging
import multiprocessing
import os
import pickle
import socket
import struct
import traceback
import weakref
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .inference import ModelStore

log = logging.getLogger("rotordiag.service")

_STORE: ModelStore | None = None   # the worker process's ModelStore


def _store() -> ModelStore:
    """The worker's model store (set by :func:`_init_worker`)."""
    if _STORE is None:
        raise RuntimeError("diagnosis worker used before _init_worker ran")
    return _STORE
_HEADER = struct.Struct("!Q")


# -- worker side ---------------------------------------------------------------------------------
def _init_worker(registry_root: str) -> None:
    """Worker start-up: one thread for every numeric library, open the registry."""
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"
    global _STORE
    from .inference import ModelStore

    _STORE = ModelStore(Path(registry_root))


def _warm(version: str | None) -> None:
    """Load ``version`` and compile its fast predictor before the first request needs it."""
    from rotordiag import features  # noqa: F401  (numba kernels load from their cache)
    from rotordiag.models.predict import fast_predictor

    if version is not None:
        fast_predictor(_store().load(version).model)


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
        verdict = _store().diagnose(recording, version)
    except InputError as exc:
        return ("input", exc.status_code, str(exc))
    except HTTPException as exc:
        return ("http", exc.status_code, exc.detail)
    except ModelUnavailable as exc:
        return ("unavailable", str(exc))
    except ValueError as exc:   # the features/models packages' messages for bad recordings
        return ("input", 422, str(exc))
    return ("ok", verdict, asset_id, plant)


_CALLS: dict[str, Callable[..., Any]] = {"work": _work, "check": _load_check}


def _recv_exact(sock: socket.socket, n: int) -> bytes | None:
    buf = bytearray(n)
    view = memoryview(buf)
    got = 0
    while got < n:
        k = sock.recv_into(view[got:])
        if k == 0:
            return None
        got += k
    return bytes(buf)


def _worker_main(sock: socket.socket, registry_root: str, version: str | None) -> None:
    """A worker process: load the model, then answer requests until the server closes the socket."""
    _init_worker(registry_root)
    try:
        _warm(version)
    except Exception as exc:  # noqa: BLE001 - reported per request (503) by _load_check/_work
        log.warning("diagnosis worker %d: could not preload model %s: %s", os.getpid(), version, exc)
    while True:
        head = _recv_exact(sock, _HEADER.size)
        if head is None:
            return
        msg = _recv_exact(sock, _HEADER.unpack(head)[0])
        if msg is None:
            return
        name, args = pickle.loads(msg)     # from the server process only (see the module docstring)
        try:
            result = _CALLS[name](*args)
        except Exception as exc:  # noqa: BLE001 - a bug, not a client mistake: the server answers 500
            result = ("exception", f"{type(exc).__name__}: {exc}", traceback.format_exc())
        out = pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL)
        sock.sendall(_HEADER.pack(len(out)) + out)


# -- server side ---------------------------------------------------------------------------------
class WorkerCrashed(RuntimeError):
    """A diagnosis worker process died on a request (reported as 503)."""


_LIVE_WORKERS: weakref.WeakSet[_Worker] = weakref.WeakSet()
_AT_EXIT_REGISTERED = False


def _stop_workers_at_exit() -> None:
    """Close the sockets of workers still running when the server exits.

    Workers are not daemonic (a daemonic process may not start the sandbox child that
    decodes HDF5, :mod:`rotordiag.features.sandbox`), so multiprocessing would wait for
    them at exit; closing their socket makes them return at once. Registered after
    multiprocessing's own exit handler, so it runs before it.
    """
    for w in list(_LIVE_WORKERS):
        try:
            w.sock.close()
        except OSError:
            pass
        w.process.join(2.0)
        if w.process.is_alive():
            w.process.kill()


class _Worker:
    """One worker process and the server's end of its socket.

    Up to ``depth`` requests are in flight per worker: the next message is already in the
    socket while the worker computes, so it never waits for the server's event loop between
    requests. The worker answers in order; a reader task resolves the futures first-in,
    first-out, and fails them all if the worker dies.
    """

    def __init__(self, registry_root: Path, version: str | None, depth: int = 2) -> None:
        parent, child = socket.socketpair()
        ctx = multiprocessing.get_context("spawn")
        self.process = ctx.Process(target=_worker_main, args=(child, str(registry_root), version),
                                   name="rotordiag-diagnosis", daemon=False)
        self.process.start()
        child.close()
        global _AT_EXIT_REGISTERED
        if not _AT_EXIT_REGISTERED:
            atexit.register(_stop_workers_at_exit)
            _AT_EXIT_REGISTERED = True
        _LIVE_WORKERS.add(self)
        parent.setblocking(False)
        self.sock = parent
        self.depth = depth
        self.inflight = 0                # requests given to this worker and not yet answered
        self.pending: collections.deque[asyncio.Future] = collections.deque()
        self.alive = True
        self._send_lock = asyncio.Lock()
        self._reader = asyncio.ensure_future(self._read_loop())

    async def call(self, name: str, args: tuple) -> Any:
        """Send one message; the returned future resolves to the worker's answer."""
        loop = asyncio.get_running_loop()
        fut = loop.create_future()
        msg = pickle.dumps((name, args), protocol=pickle.HIGHEST_PROTOCOL)
        if not self.alive:               # its reader has finished: nobody would answer the future
            raise ConnectionResetError("diagnosis worker stopped")
        self.pending.append(fut)
        async with self._send_lock:      # messages must not interleave on the socket
            try:
                await loop.sock_sendall(self.sock, _HEADER.pack(len(msg)) + msg)
            except OSError as exc:
                self._fail(exc)
        return await fut

    async def _read_loop(self) -> None:
        loop = asyncio.get_running_loop()
        try:
            while True:
                head = await self._recv_exact(loop, _HEADER.size)
                result = pickle.loads(await self._recv_exact(loop, _HEADER.unpack(head)[0]))
                fut = self.pending.popleft()
                if not fut.done():
                    fut.set_result(result)
        except (ConnectionError, OSError, EOFError, struct.error, pickle.UnpicklingError, IndexError) as exc:
            self._fail(exc)
        except asyncio.CancelledError:
            self._fail(ConnectionResetError("diagnosis pool shutting down"))
            raise

    def _fail(self, exc: BaseException) -> None:
        self.alive = False
        while self.pending:
            fut = self.pending.popleft()
            if not fut.done():
                fut.set_exception(ConnectionResetError(f"diagnosis worker stopped: {exc}"))

    async def _recv_exact(self, loop, n: int) -> bytes:
        buf = bytearray(n)
        view = memoryview(buf)
        got = 0
        while got < n:
            k = await loop.sock_recv_into(self.sock, view[got:])
            if k == 0:
                raise ConnectionResetError("diagnosis worker closed its socket")
            got += k
        return bytes(buf)

    def stop(self, timeout_s: float = 5.0) -> None:
        self._reader.cancel()
        self.sock.close()            # the worker sees end of file and returns
        self.process.join(timeout_s)
        if self.process.is_alive():
            self.process.terminate()
            self.process.join(timeout_s)


class DiagnosisPool:
    """N diagnosis worker processes fed by the server's event loop.

    Parameters
    ----------
    registry_root : Path
        The model registry the workers load from (the server's).
    n_workers : int
    version : str, optional
        Model version every worker preloads at start (the active one).

    Must be created and used on the server's running event loop (the app's lifespan).
    """

    def __init__(self, registry_root: Path, n_workers: int, version: str | None = None) -> None:
        self.registry_root = Path(registry_root)
        self.n_workers = int(n_workers)
        self._version = version
        self._loop = asyncio.get_running_loop()
        self._workers: list[_Worker] = [_Worker(self.registry_root, version) for _ in range(self.n_workers)]
        self._free = asyncio.Condition()
        self._loadable: set[str] = set()
        self._closing = False

    def pids(self) -> list[int]:
        """Process ids of the workers."""
        return [w.process.pid for w in self._workers if w.process.pid is not None]

    def _replace(self, w: _Worker) -> None:
        if self._closing or w not in self._workers:
            return
        log.error("diagnosis worker process %s stopped (exit code %s); starting another",
                  w.process.pid, w.process.exitcode)
        self._workers[self._workers.index(w)] = _Worker(self.registry_root, self._version)
        w.stop(timeout_s=1.0)

    async def _acquire(self) -> _Worker:
        """The live worker with the fewest requests in flight, waiting while all are full."""
        async with self._free:
            while True:
                for w in list(self._workers):
                    if not w.alive:
                        self._replace(w)
                if self._closing:
                    raise WorkerCrashed("the diagnosis workers are shutting down; retry in a moment")
                live = [w for w in self._workers if w.alive and w.inflight < w.depth]
                if live:
                    w = min(live, key=lambda w: w.inflight)
                    w.inflight += 1      # reserved here, so concurrent acquires see it at once
                    return w
                await self._free.wait()

    async def _release(self) -> None:
        async with self._free:
            self._free.notify()

    async def _on(self, w: _Worker, name: str, args: tuple) -> tuple[bool, Any]:
        try:
            return True, await w.call(name, args)
        except ConnectionResetError:
            self._replace(w)
            return False, None
        finally:
            w.inflight -= 1
            await self._release()

    async def _call(self, name: str, args: tuple) -> Any:
        for _attempt in (1, 2):
            w = await self._acquire()
            # Shielded: a request cancelled meanwhile (client gone, shutdown) still lets the worker
            # answer its message, so the socket's framing stays intact and the worker is reused.
            ok, result = await asyncio.shield(asyncio.ensure_future(self._on(w, name, args)))
            if not ok:
                continue
            if isinstance(result, tuple) and result and result[0] == "exception":
                log.error("diagnosis worker raised %s\n%s", result[1], result[2])
                raise RuntimeError(f"diagnosis worker raised {result[1]}")
            return result
        raise WorkerCrashed("the diagnosis worker stopped unexpectedly twice on this request; "
                            "if the recording is very large, send a shorter one")

    async def run(self, kind: str, body: bytes, filename: str, query: dict[str, Any],
                  version: str | None) -> tuple:
        """:func:`_work` in a worker process (returns its tagged tuple)."""
        return await self._call("work", (kind, body, filename, query, version))

    def check_model(self, version: str, timeout_s: float = 60.0) -> str | None:
        """``None`` when the workers can load ``version`` (remembered once true), else why not.

        Called from ``GET /health`` (a thread of the server), so the server process itself
        never loads a model.
        """
        if version in self._loadable:
            return None
        future = asyncio.run_coroutine_threadsafe(self._call("check", (version,)), self._loop)
        try:
            problem = future.result(timeout=timeout_s)
        except TimeoutError:
            future.cancel()
            return f"diagnosis workers did not load model {version} within {timeout_s:g} s"
        except (WorkerCrashed, RuntimeError) as exc:
            return str(exc)
        if problem is None:
            self._loadable.add(version)
        return problem

    def shutdown(self) -> None:
        """Stop the workers (each finishes the request it holds first)."""
        self._closing = True
        for w in self._workers:
            w.stop()
        self._workers.clear()
