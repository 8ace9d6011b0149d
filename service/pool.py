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
ever unpickled — the body travels as opaque bytes (a multipart upload of several take files: each
file's bytes and name) and is parsed by
:func:`service.parsing.parse_body`.

Limits: each worker lowers its own ``RLIMIT_AS`` after loading the model to its size then
plus ``memory_bytes`` (``ROTORDIAG_DIAGNOSIS_WORKER_MEMORY_MB``), so a request that would
allocate more fails inside the worker (``MemoryError`` → 422) instead of growing it; and the
server gives each request ``timeout_s`` (``ROTORDIAG_DIAGNOSIS_TIMEOUT_S``) of the worker's
time, counted from when the worker starts on it: a worker over the limit is killed and
replaced, the request is answered 422 (:class:`DiagnosisTimeout`) and not retried.

Failover: a worker that dies (a crash in native code, killed from outside, or over the time
limit) is replaced by a fresh process at once, and the requests it held are retried once on a
*warm* worker — except the one it was computing when it stopped itself (an abort, e.g. an allocation
failure under its memory limit, or a crash): that request is answered 503 saying so, never handed to
the next worker to kill it too — a worker counts as ready only after it has loaded the model and said so, so
no request waits for a cold replacement while a warm worker exists. Requests go to the ready
worker with the fewest in flight, ties broken round-robin, so sequential requests spread
across the workers.
"""
from __future__ import annotations

import asyncio
import atexit
import collections
import logging
import multiprocessing
import os
import pickle
import signal
import socket
import struct
import threading
import time
import traceback
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .inference import ModelStore
    from .parsing import Body

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


def _warm_diagnosis(version: str | None) -> None:
    """Diagnose a synthetic recording (1X and 2X sines at 1800 r/min on the four bearings) once, before the
    worker says it is ready: the first real request then finds every lazily compiled kernel and lazily imported
    module in place (a fresh container's first diagnosis took 28 s without it), and /health stays `starting`
    until then."""
    if version is None:
        return
    import numpy as np

    from .parsing import recording_from_model
    from .schemas import RecordingIn

    fs_hz, f_hz = 2048.0, 30.0
    t = np.arange(int(4 * fs_hz)) / fs_hz
    channels = [{"bearing": b, "angle_deg": a, "units": "um",
                 "data": (20.0 * np.cos(2 * np.pi * f_hz * t - np.radians(a + 30 * b))
                          + 4.0 * np.cos(4 * np.pi * f_hz * t - np.radians(2 * a))).tolist()}
                for b in (1, 2, 3, 4) for a in (45.0, 135.0)]
    rec = recording_from_model(RecordingIn.model_validate(
        {"sample_rate_hz": fs_hz, "speed_rpm": 60 * f_hz, "channels": channels}))
    try:
        _store().diagnose(rec, version)
    except ValueError:
        pass                 # a refusal still ran the features; the model itself was loaded by _warm


def _load_check(version: str) -> dict[str, Any]:
    """The model this worker holds for ``version``: ``{"sha256", "problem"}`` (``problem`` is ``None``
    when a diagnosis with it would work). Reloads the file when it changed on disk."""
    from .inference import ModelUnavailable

    try:
        _warm(version)
    except ModelUnavailable as exc:
        return {"version": version, "sha256": None, "problem": str(exc)}
    return {"version": version, "sha256": _store().file_sha256(version), "problem": None}


_MEMORY_BYTES = 0   # this worker's memory allowance (for the MemoryError message)


def _tagged(fn: Callable[[], tuple]) -> tuple:
    """``fn()``, with the errors a client can cause turned into tagged tuples.

    Returns what ``fn`` returns (``("ok", ...)``), ``("input", kind, message)``,
    ``("request", errors)`` or ``("unavailable", message)`` (domain exceptions only: the API
    layer, :func:`service.api.errors.raise_worker_error`, gives them HTTP statuses).
    """
    from .errors import InputError, RequestInvalid
    from .inference import ModelUnavailable

    try:
        return fn()
    except InputError as exc:
        return ("input", exc.kind, str(exc))
    except RequestInvalid as exc:
        return ("request", exc.errors)
    except ModelUnavailable as exc:
        return ("unavailable", str(exc))
    except MemoryError:
        return ("input", "invalid", f"the recording needs more than the {_MEMORY_BYTES / 2**20:.0f} MiB of memory one "
                "diagnosis may use (ROTORDIAG_DIAGNOSIS_WORKER_MEMORY_MB); send a shorter recording or fewer "
                "channels")
    except ValueError as exc:   # the features/models packages' messages for bad recordings
        return ("input", "invalid", str(exc))


def _work(kind: str, body: Body, filename: str, query: dict[str, Any], slow_roll: tuple[bytes, str] | None,
          version: str | None) -> tuple:
    """Parse and diagnose one request in the worker: ``("ok", verdict, asset_id, plant)`` or an error
    tuple (:func:`_tagged`). ``slow_roll``: an uploaded slow-roll recording and its file name, parsed
    here like the main body (:func:`service.parsing.parse_body`)."""
    from .parsing import parse_request, plant_declared_by

    def run() -> tuple:
        recording, asset_id, plant, notes, plant_model = parse_request(kind, body, filename, query, slow_roll)
        return ("ok", {**_store().diagnose(recording, version, plant_model, query.get("plant_shaftline"),
                                           plant_declared_by(query, plant_model)),
                       "input_notes": notes,
                       "recorded_at_in_file": recording.recorded_at}, asset_id, plant)

    return _tagged(run)


def _record(record: dict[str, Any], version: str | None) -> tuple:
    """Validate and diagnose one record of a batch (a record dict of :func:`_batch_parse`)."""
    from .parsing import batch_record, checked, recording_from_model

    def run() -> tuple:
        req = batch_record(record)
        return ("ok", _store().diagnose(checked(recording_from_model, req), version, req.plant_model,
                                        declared_by="request" if req.plant_model else None), req.asset_id, req.plant)

    return _tagged(run)


def _batch_parse(body: bytes) -> tuple:
    """Parse a POST /diagnose/batch body: ``("ok", [record dict, ...])`` or an error tuple."""
    from .parsing import parse_batch

    return _tagged(lambda: ("ok", parse_batch(body)))


def _plot(kind: str, body: Body, filename: str, query: dict[str, Any]) -> tuple:
    """Parse a recording and compute the web page's plot arrays: ``("ok", data)`` or an error tuple."""
    from .parsing import parse_body
    from .plotdata import plot_data

    def run() -> tuple:
        recording = parse_body(kind, body, filename, query)[0]
        return ("ok", plot_data(recording, _store().plot_features(recording)))

    return _tagged(run)


class WorkerCall:
    """One call a diagnosis worker runs: a frozen dataclass of its arguments whose :meth:`run` (in the worker)
    returns its answer (a tagged tuple, :func:`_tagged`, for the request calls). The server sends the call object itself, so what a worker runs is
    typed and checked by the type checker, not looked up by a name."""

    def run(self) -> Any:
        raise NotImplementedError


@dataclass(frozen=True)
class DiagnoseBody(WorkerCall):
    """Parse and diagnose one ``POST /diagnose`` body (:func:`_work`)."""

    kind: str
    body: Body
    filename: str
    query: dict[str, Any]
    slow_roll: tuple[bytes, str] | None
    version: str | None

    def run(self) -> tuple:
        return _work(self.kind, self.body, self.filename, self.query, self.slow_roll, self.version)


@dataclass(frozen=True)
class DiagnoseRecord(WorkerCall):
    """Diagnose one record of a batch (:func:`_record`)."""

    record: dict[str, Any]
    version: str | None

    def run(self) -> tuple:
        return _record(self.record, self.version)


@dataclass(frozen=True)
class ParseBatch(WorkerCall):
    """Parse a ``POST /diagnose/batch`` body (:func:`_batch_parse`)."""

    body: bytes

    def run(self) -> tuple:
        return _batch_parse(self.body)


@dataclass(frozen=True)
class PlotBody(WorkerCall):
    """The web page's plot arrays of a body sent as to ``POST /diagnose`` (:func:`_plot`)."""

    kind: str
    body: Body
    filename: str
    query: dict[str, Any]

    def run(self) -> tuple:
        return _plot(self.kind, self.body, self.filename, self.query)


def _transient(kind: str, body: Body, filename: str, query: dict[str, Any], units: str,
               cascade_scale: str = "db", centreline_reference: str = "recorded") -> tuple:
    """Parse a start-up / coast-down recording and render its plots (:func:`service.plotdata.transient_plots`):
    ``("ok", data)`` or an error tuple."""
    from .parsing import parse_body, plant_of_model
    from .plotdata import transient_plots

    def run() -> tuple:
        plant = (plant_of_model(query.get("plant_model"), query.get("plant_shaftline"))
                 if query.get("plant_model") or query.get("plant_shaftline") else None)
        return ("ok", transient_plots(parse_body(kind, body, filename, query)[0], units, cascade_scale, plant=plant,
                                      centreline_reference=centreline_reference))

    return _tagged(run)


@dataclass(frozen=True)
class TransientPlots(WorkerCall):
    """The web page's start-up plots of a body sent as to ``POST /diagnose`` (:func:`_transient`)."""

    kind: str
    body: Body
    filename: str
    query: dict[str, Any]
    units: str
    cascade_scale: str = "db"
    centreline_reference: str = "recorded"

    def run(self) -> tuple:
        return _transient(self.kind, self.body, self.filename, self.query, self.units, self.cascade_scale,
                          self.centreline_reference)


@dataclass(frozen=True)
class StartupBody(WorkerCall):
    """A start-up or coast-down sent to ``POST /assets/{id}/startup``: parsed and reduced to the evidence the
    service stores (:func:`service.startups.startup_data`): ``("ok", data)`` or an error tuple."""

    kind: str
    body: Body
    filename: str
    query: dict[str, Any]

    def run(self) -> tuple:
        from .parsing import parse_body
        from .startups import startup_data

        return _tagged(lambda: ("ok", startup_data(parse_body(self.kind, self.body, self.filename, self.query)[0])))


@dataclass(frozen=True)
class AssetReport(WorkerCall):
    """An asset's report (``GET /assets/{id}/report``) as PDF or HTML bytes, from the plain data read from the
    store (:func:`service.report.asset_report_inputs`): ``("ok", bytes)`` or an error tuple."""

    inputs: dict[str, Any]
    fmt: str

    def run(self) -> tuple:
        from .report import render_asset_report

        return _tagged(lambda: ("ok", render_asset_report(self.inputs, self.fmt)))


@dataclass(frozen=True)
class TrainSimulate(WorkerCall):
    """A shaft train's simulated recording (``POST /trains/simulate``, :func:`service.trains.simulate_train_request`)
    from the validated request: ``("ok", answer)`` or an error tuple."""

    request: Any

    def run(self) -> tuple:
        from .trains import simulate_train_request

        return _tagged(lambda: ("ok", simulate_train_request(self.request)))


@dataclass(frozen=True)
class CheckModel(WorkerCall):
    """Which file of ``version`` the worker holds, and whether it can be used (:func:`_load_check`)."""

    version: str

    def run(self) -> dict[str, Any]:
        return _load_check(self.version)


def _recv_exact(sock: socket.socket, n: int) -> bytearray | None:
    """``n`` bytes from ``sock`` (None at end of file), in the buffer they were read into (not copied again: a
    request's body is half a megabyte)."""
    buf = bytearray(n)
    view = memoryview(buf)
    got = 0
    while got < n:
        k = sock.recv_into(view[got:])
        if k == 0:
            return None
        got += k
    return buf


def _worker_main(sock: socket.socket, registry_root: str, version: str | None, memory_bytes: int = 0) -> None:
    """A worker process: load the model, limit its memory, say it is ready, then answer requests until
    the server closes the socket.

    Ctrl-C in the server's terminal reaches every process of its group: a worker ignores it (from its start,
    :meth:`_Worker.__init__`) and stops when the server closes its socket (or terminates it while it is still
    loading the model), so stopping the server at any moment, warm-up included, prints no worker traceback."""
    global _MEMORY_BYTES
    signal.signal(signal.SIGINT, signal.SIG_IGN)          # (already so when started by _Worker in the main thread)
    _init_worker(registry_root)
    try:
        _warm(version)
        from .parsing import parse_body  # noqa: F401  (imported before the limit, not on the first request)
        from .plotdata import plot_data  # noqa: F401
        _warm_diagnosis(version)
    except Exception as exc:  # noqa: BLE001 - reported per request (503) by _load_check/_work
        log.warning("diagnosis worker %d: could not preload model %s: %s", os.getpid(), version, exc)
    _MEMORY_BYTES = memory_bytes
    from rotordiag.features.sandbox import limit_address_space

    limit_address_space(memory_bytes)
    ready = pickle.dumps(("ready", os.getpid()), protocol=pickle.HIGHEST_PROTOCOL)
    try:
        sock.sendall(_HEADER.pack(len(ready)) + ready)
        while True:
            head = _recv_exact(sock, _HEADER.size)
            if head is None:
                return
            msg = _recv_exact(sock, _HEADER.unpack(head)[0])
            if msg is None:
                return
            call = pickle.loads(msg)           # from the server process only (see the module docstring)
            try:
                if not isinstance(call, WorkerCall):
                    raise TypeError(f"a diagnosis worker runs WorkerCall objects, not {type(call).__name__}")
                result = call.run()
            except Exception as exc:  # noqa: BLE001 - a bug, not a client mistake: the server answers 500
                result = ("exception", f"{type(exc).__name__}: {exc}", traceback.format_exc())
            out = pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL)
            sock.sendall(_HEADER.pack(len(out)) + out)
    except (BrokenPipeError, ConnectionResetError):
        return                                 # the server closed the socket (it is stopping): nothing to answer


# -- server side ---------------------------------------------------------------------------------
class WorkerCrashed(RuntimeError):
    """A diagnosis worker process died on a request (reported as 503)."""


class DiagnosisTimeout(RuntimeError):
    """A request ran past the time limit; its worker was killed (reported as 422, not retried)."""


class _LostInFlight(ConnectionResetError):
    """The worker died while computing this request (the head of its queue): the request may have killed it."""


#: exit signals of a worker that stopped itself (an allocation failure aborts, native code crashes): the request it
#: was computing is not retried on another worker, which it would kill too. SIGKILL/SIGTERM come from outside.
_SELF_INFLICTED_SIGNALS = {6: "SIGABRT: memory allocation failed", 11: "SIGSEGV", 7: "SIGBUS", 8: "SIGFPE",
                           4: "SIGILL"}


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
    first-out, and fails them all if the worker dies. The request at the head of the queue
    (the one the worker is computing) has ``timeout_s`` from when it got there; past it the
    worker is killed.
    """

    def __init__(self, registry_root: Path, version: str | None, *, depth: int = 2, memory_bytes: int = 0,
                 timeout_s: float = 60.0, on_ready: Callable[[], Any] | None = None) -> None:
        parent, child = socket.socketpair()
        ctx = multiprocessing.get_context("spawn")
        self.process = ctx.Process(target=_worker_main, args=(child, str(registry_root), version, memory_bytes),
                                   name="rotordiag-diagnosis", daemon=False)
        # started with SIGINT ignored (a disposition a spawned interpreter keeps, unlike a blocked mask): a
        # Ctrl-C during the worker's start-up (its imports) is no KeyboardInterrupt traceback; the server's
        # own handler is put back at once (signal handlers can only be set from the main thread)
        main = threading.current_thread() is threading.main_thread()
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
        try:
            self.process.start()
        finally:
            if main:
                signal.signal(signal.SIGINT, previous)
        child.close()
        global _AT_EXIT_REGISTERED
        if not _AT_EXIT_REGISTERED:
            atexit.register(_stop_workers_at_exit)
            _AT_EXIT_REGISTERED = True
        _LIVE_WORKERS.add(self)
        parent.setblocking(False)
        self.sock = parent
        self.depth = depth
        self.timeout_s = float(timeout_s)
        self.inflight = 0                # requests given to this worker and not yet answered
        self.served = 0                  # requests sent to it (tests check that requests spread)
        self.pending: collections.deque[asyncio.Future] = collections.deque()
        self.alive = True
        self.ready = False               # set when the worker says it has loaded the model
        self.timed_out = False
        self._on_ready = on_ready
        self._timer: asyncio.TimerHandle | None = None
        self._send_lock = asyncio.Lock()
        self._reader = asyncio.ensure_future(self._read_loop())

    async def call(self, call: WorkerCall) -> Any:
        """Send one call; the returned future resolves to the worker's answer."""
        loop = asyncio.get_running_loop()
        fut = loop.create_future()
        msg = pickle.dumps(call, protocol=pickle.HIGHEST_PROTOCOL)
        if not self.alive:               # its reader has finished: nobody would answer the future
            raise ConnectionResetError("diagnosis worker stopped")
        self.pending.append(fut)
        self.served += 1
        if len(self.pending) == 1 and self.ready:
            self._arm()
        async with self._send_lock:      # messages must not interleave on the socket
            try:
                await loop.sock_sendall(self.sock, _HEADER.pack(len(msg)) + msg)
            except OSError as exc:
                self._fail(exc)
        return await fut

    def _arm(self) -> None:
        """Start the time limit of the request at the head of the queue (the one being computed)."""
        if self._timer is not None:
            self._timer.cancel()
        self._timer = asyncio.get_running_loop().call_later(self.timeout_s, self._expire, self.pending[0])

    def _expire(self, fut: asyncio.Future) -> None:
        """The head request ran past the limit: kill the worker; that request fails, the others are retried."""
        if not self.pending or self.pending[0] is not fut or fut.done():
            return
        log.error("diagnosis worker %s: a request ran past %g s; killing the worker", self.process.pid,
                  self.timeout_s)
        self.timed_out = True
        self.pending.popleft()
        fut.set_exception(DiagnosisTimeout(self.timeout_s))
        self.process.kill()
        self._fail(ConnectionResetError("worker killed: a request ran past the time limit"))

    async def _read_loop(self) -> None:
        loop = asyncio.get_running_loop()
        try:
            head = await self._recv_exact(loop, _HEADER.size)
            pickle.loads(await self._recv_exact(loop, _HEADER.unpack(head)[0]))   # ("ready", pid)
            self.ready = True
            if self.pending:
                self._arm()
            if self._on_ready is not None:
                self._on_ready()
            while True:
                head = await self._recv_exact(loop, _HEADER.size)
                result = pickle.loads(await self._recv_exact(loop, _HEADER.unpack(head)[0]))
                fut = self.pending.popleft()
                if self._timer is not None:
                    self._timer.cancel()
                    self._timer = None
                if self.pending:
                    self._arm()
                if not fut.done():
                    fut.set_result(result)
        except (ConnectionError, OSError, EOFError, struct.error, pickle.UnpicklingError, IndexError) as exc:
            self._fail(exc)
        except asyncio.CancelledError:
            self._fail(ConnectionResetError("diagnosis pool shutting down"))
            raise

    def _fail(self, exc: BaseException) -> None:
        self.alive = False
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        head = self.ready               # a ready worker was computing the head request when it died
        while self.pending:
            fut = self.pending.popleft()
            if not fut.done():
                kind = _LostInFlight if head else ConnectionResetError
                fut.set_exception(kind(f"diagnosis worker stopped: {exc}"))
            head = False
        if self._on_ready is not None:   # wake requests waiting for a worker: this one is gone
            self._on_ready()

    async def _recv_exact(self, loop, n: int) -> bytearray:
        buf = bytearray(n)
        view = memoryview(buf)
        got = 0
        while got < n:
            k = await loop.sock_recv_into(self.sock, view[got:])
            if k == 0:
                raise ConnectionResetError("diagnosis worker closed its socket")
            got += k
        return buf

    def stop(self, timeout_s: float = 5.0) -> None:
        self.close()
        self.reap(time.monotonic() + timeout_s)

    def close(self) -> None:
        """Close the socket: the worker returns once the request it computes is done."""
        self._reader.cancel()
        self.sock.close()            # the worker sees end of file and returns
        if not self.ready and self.process.is_alive():
            self.process.terminate()     # still loading the model (it reads no socket yet) and holds no request

    def reap(self, deadline: float) -> None:
        """Wait for the closed worker until ``deadline`` (``time.monotonic()``), then terminate, then kill it."""
        self.process.join(max(0.0, deadline - time.monotonic()))
        if self.process.is_alive():
            self.process.terminate()
            self.process.join(2.0)
        if self.process.is_alive():
            self.process.kill()
            self.process.join(1.0)


#: how long /health may reuse the workers' answer about the model they hold
MODEL_CHECK_INTERVAL_S = 5.0


class DiagnosisPool:
    """N diagnosis worker processes fed by the server's event loop.

    Parameters
    ----------
    registry_root : Path
        The model registry the workers load from (the server's).
    n_workers : int
    version : str, optional
        Model version every worker preloads at start (the active one).
    memory_bytes : int
        Memory each worker may allocate beyond its size after loading the model (``RLIMIT_AS``;
        0: no limit).
    timeout_s : float
        Worker time one request may take; past it the worker is killed and replaced.

    Must be created and used on the server's running event loop (the app's lifespan).
    """

    def __init__(self, registry_root: Path, n_workers: int, version: str | None = None, *,
                 memory_bytes: int = 0, timeout_s: float = 60.0) -> None:
        self.registry_root = Path(registry_root)
        self.n_workers = int(n_workers)
        self.memory_bytes = int(memory_bytes)
        self.timeout_s = float(timeout_s)
        self._version = version
        self._loop = asyncio.get_running_loop()
        self._free = asyncio.Condition()
        self._workers: list[_Worker] = [self._new_worker() for _ in range(self.n_workers)]
        self._next = 0                   # round-robin start for ties
        self._checked: dict[str, tuple[float, str | None]] = {}
        self.model_sha256: str | None = None   # of the model file the workers hold (last check)
        self.checked_version: str | None = None  # the version a worker last answered a check for
        self._closing = False

    def _new_worker(self) -> _Worker:
        return _Worker(self.registry_root, self._version, memory_bytes=self.memory_bytes, timeout_s=self.timeout_s,
                       on_ready=self._notify_soon)

    def _notify_soon(self) -> None:
        asyncio.ensure_future(self._release())

    def pids(self) -> list[int]:
        """Process ids of the workers."""
        return [w.process.pid for w in self._workers if w.process.pid is not None]

    def _replace(self, w: _Worker) -> None:
        if self._closing or w not in self._workers:
            return
        if w.timed_out:
            log.error("diagnosis worker process %s killed after a request ran past %g s; starting another",
                      w.process.pid, self.timeout_s)
        else:
            log.error("diagnosis worker process %s stopped (exit code %s); starting another",
                      w.process.pid, w.process.exitcode)
        self._workers[self._workers.index(w)] = self._new_worker()
        w.stop(timeout_s=1.0)

    @staticmethod
    async def _self_inflicted(w: _Worker, wait_s: float = 2.0) -> str | None:
        """Why ``w``'s process stopped when it stopped itself (a signal of :data:`_SELF_INFLICTED_SIGNALS` or an
        exit status other than 0); ``None`` when it was killed from outside or its status is not known in time."""
        t0 = time.monotonic()
        while w.process.exitcode is None and time.monotonic() - t0 < wait_s:
            await asyncio.sleep(0.02)
        code = w.process.exitcode
        if code is None or code == 0 or code in (-9, -15):
            return None
        if code < 0:
            return _SELF_INFLICTED_SIGNALS.get(-code, f"signal {-code}")
        return f"exit status {code}"

    def _pick(self) -> _Worker | None:
        """The ready worker with the fewest requests in flight (ties round-robin); a cold one only when
        no worker is ready."""
        n = len(self._workers)
        order = [self._workers[(self._next + i) % n] for i in range(n)]
        live = [w for w in order if w.alive]
        ready = [w for w in live if w.ready]
        if ready:
            free = [w for w in ready if w.inflight < w.depth]
        else:
            free = [w for w in live if w.inflight < w.depth]
        if not free:
            return None
        w = min(free, key=lambda w: w.inflight)
        self._next = (self._workers.index(w) + 1) % n
        return w

    async def _acquire(self) -> _Worker:
        """A worker (see :meth:`_pick`), waiting while all are full."""
        async with self._free:
            while True:
                for w in list(self._workers):
                    if not w.alive:
                        self._replace(w)
                if self._closing:
                    raise WorkerCrashed("the diagnosis workers are shutting down; retry in a moment")
                picked = self._pick()
                if picked is not None:
                    picked.inflight += 1      # reserved here, so concurrent acquires see it at once
                    return picked
                await self._free.wait()

    async def _release(self) -> None:
        async with self._free:
            self._free.notify_all()

    async def _on(self, w: _Worker, call: WorkerCall) -> tuple[bool, Any]:
        try:
            return True, await w.call(call)
        except _LostInFlight:
            cause = await self._self_inflicted(w)
            self._replace(w)
            if cause is None:
                return False, None           # killed from outside: retried once
            raise WorkerCrashed(f"the diagnosis worker stopped while reading this request ({cause}); it was "
                                "replaced and the request is not retried. Send a smaller recording (fewer samples "
                                "per channel, or an NPY array of float32)") from None
        except ConnectionResetError:
            self._replace(w)
            return False, None
        except DiagnosisTimeout:
            self._replace(w)
            raise
        finally:
            w.inflight -= 1
            await self._release()

    async def _call(self, call: WorkerCall) -> Any:
        for _attempt in (1, 2):
            w = await self._acquire()
            # Shielded: a request cancelled meanwhile (client gone, shutdown) still lets the worker
            # answer its message, so the socket's framing stays intact and the worker is reused.
            ok, result = await asyncio.shield(asyncio.ensure_future(self._on(w, call)))
            if not ok:
                continue
            if isinstance(result, tuple) and result and result[0] == "exception":
                log.error("diagnosis worker raised %s\n%s", result[1], result[2])
                raise RuntimeError(f"diagnosis worker raised {result[1]}")
            return result
        raise WorkerCrashed("the diagnosis worker stopped unexpectedly twice on this request; "
                            "if the recording is very large, send a shorter one")

    async def run(self, kind: str, body: Body, filename: str, query: dict[str, Any],
                  version: str | None, slow_roll: tuple[bytes, str] | None = None) -> tuple:
        """:func:`_work` in a worker process (returns its tagged tuple)."""
        return await self._call(DiagnoseBody(kind, body, filename, query, slow_roll, version))

    async def call(self, call: WorkerCall) -> tuple:
        """``call`` (a :class:`DiagnoseRecord`, :class:`ParseBatch`, :class:`PlotBody`, …) in a worker process."""
        return await self._call(call)

    async def _check_all(self, version: str) -> str | None:
        answers = []
        for w in [w for w in self._workers if w.alive and w.ready] or self._workers[:1]:
            if w.inflight >= w.depth:
                continue                 # busy: its answer would wait for the requests before it
            w.inflight += 1
            try:
                answers.append(await w.call(CheckModel(version)))
            except (ConnectionResetError, DiagnosisTimeout):
                self._replace(w)
            finally:
                w.inflight -= 1
                await self._release()
        if not answers:                  # every worker busy with diagnoses: the last answer stands
            return self._checked[version][1] if version in self._checked else None
        problems = sorted({a["problem"] for a in answers if a["problem"]})
        hashes = {a["sha256"] for a in answers}
        self.model_sha256 = next(iter(hashes)) if len(hashes) == 1 else None
        self.checked_version = version
        if problems:
            return "; ".join(problems)
        if len(hashes) > 1:
            return f"diagnosis workers hold different files of model {version} (sha256 {sorted(map(str, hashes))})"
        return None

    def any_ready(self) -> bool:
        """Whether a worker has started and loaded its model (a check answered at once)."""
        return any(w.alive and w.ready for w in self._workers)

    def check_model(self, version: str, timeout_s: float = 30.0) -> str | None:
        """``None`` when the workers hold ``version`` and can diagnose with it, else why not.

        Asks every ready worker which file of ``version`` it holds (each reloads it when the file
        changed on disk, so a corrupted or replaced file shows here); the answer is reused for at
        most :data:`MODEL_CHECK_INTERVAL_S`. Called from ``GET /health`` (a thread of the server),
        so the server process itself never loads a model.
        """
        now = time.monotonic()
        cached = self._checked.get(version)
        if cached is not None and now - cached[0] < MODEL_CHECK_INTERVAL_S:
            return cached[1]
        future = asyncio.run_coroutine_threadsafe(self._check_all(version), self._loop)
        try:
            problem = future.result(timeout=timeout_s)
        except TimeoutError:
            future.cancel()
            return f"diagnosis workers did not load model {version} within {timeout_s:g} s"
        except (WorkerCrashed, RuntimeError) as exc:
            return str(exc)
        self._checked = {version: (time.monotonic(), problem)}
        return problem

    def shutdown(self, timeout_s: float = 5.0) -> None:
        """Stop the workers: all are told at once, each may finish the request it holds within ``timeout_s``
        (in all, not each), then it is terminated (at most ``timeout_s`` + 3 s in all)."""
        self._closing = True
        for w in self._workers:
            w.close()
        deadline = time.monotonic() + timeout_s
        for w in self._workers:
            w.process.join(max(0.0, deadline - time.monotonic()))
        for signal_them in ("terminate", "kill"):      # whatever is left, all at once
            left = [w.process for w in self._workers if w.process.is_alive()]
            for proc in left:
                getattr(proc, signal_them)()
            deadline = time.monotonic() + 1.5
            for proc in left:
                proc.join(max(0.0, deadline - time.monotonic()))
        self._workers.clear()
