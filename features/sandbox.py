"""Run a parser of untrusted bytes in a child process with a memory and a time limit.

The HDF5 library is C code that trusts the file it reads: a byte-flipped or crafted
file can make it loop while allocating without bound (found by this project's own fuzz
test: ~250 MiB/s inside ``H5Oget_info`` until the machine's memory is gone) or crash
the process. No Python-level check can bound that, so the decoding itself runs in a
child process:

* the child is forked from multiprocessing's *forkserver* (a single-threaded process
  started once per parent; forking a threaded server directly could copy a held lock),
* it lowers its own ``RLIMIT_AS`` to its size at start plus ``memory_bytes``, so a
  runaway allocation fails inside the child (``MemoryError``) instead of growing,
* the parent waits at most ``timeout_s`` for the answer and kills the child after that.

Whatever goes wrong in the child comes back as :class:`SandboxError` (a ``ValueError``,
so a caller answering an upload turns it into a 4xx) with a message that says what
happened; a ``ValueError`` raised by the parser itself is re-raised unchanged.

Functions run here must be importable module-level callables (they are pickled by
name) and their arguments and result picklable.
"""
from __future__ import annotations

import multiprocessing
import os
import sys
from collections.abc import Callable
from typing import Any, TypeVar

T = TypeVar("T")

#: Modules the forkserver imports once, so each child starts without importing them.
PRELOAD = ["numpy", "h5py", "rotordiag.features.sandbox"]


class SandboxError(ValueError):
    """The isolated parser ran out of memory or time, or its process died."""


def address_space_bytes() -> int | None:
    """This process's virtual size in bytes (what ``RLIMIT_AS`` bounds; Linux ``/proc``), or ``None`` where unknown."""
    try:
        with open("/proc/self/statm") as fh:
            pages = int(fh.read().split()[0])
        return pages * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return None


def limit_address_space(memory_bytes: int) -> int | None:
    """Lower this process's ``RLIMIT_AS`` to its size now plus ``memory_bytes`` (never above the hard limit).

    Returns
    -------
    int or None
        The limit set, or ``None`` where it cannot be set (not POSIX, size unknown, ``memory_bytes`` ≤ 0):
        then only a time limit applies.
    """
    try:
        import resource
    except ImportError:  # not POSIX
        return None
    size = address_space_bytes()
    if size is None or memory_bytes <= 0:
        return None
    _soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = size + memory_bytes if hard == resource.RLIM_INFINITY else min(size + memory_bytes, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    return limit


def _child(conn: Any, fn: Callable[..., Any], args: tuple, kwargs: dict[str, Any], memory_bytes: int) -> None:
    """Child process body: limit memory, run ``fn``, send ``(tag, payload)``."""
    try:
        limit_address_space(memory_bytes)
        result = fn(*args, **kwargs)
        conn.send(("ok", result))
    except MemoryError:
        conn.send(("memory", None))
    except ValueError as exc:
        conn.send(("value", exc))
    except BaseException as exc:  # noqa: BLE001 - anything else is reported, never propagated
        conn.send(("error", f"{type(exc).__name__}: {exc}"))
    finally:
        conn.close()


_CTX: Any = None


def _context() -> Any:
    global _CTX
    if _CTX is None:
        method = "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"
        _CTX = multiprocessing.get_context(method)
        if method == "forkserver":
            _CTX.set_forkserver_preload(PRELOAD)
    return _CTX


def call_isolated(fn: Callable[..., T], *args: Any, memory_bytes: int, timeout_s: float, what: str,
                  kwargs: dict[str, Any] | None = None) -> T:
    """``fn(*args, **kwargs)`` in a child process limited to ``memory_bytes`` more memory and ``timeout_s``.

    Parameters
    ----------
    fn : callable
        A module-level function (pickled by reference).
    *args
        Its arguments (picklable).
    memory_bytes : int
        Memory the child may allocate beyond its size at start.
    timeout_s : float
        Wall-clock limit for the child's answer.
    what : str
        What is being parsed, for the error messages (e.g. ``"the HDF5 file"``).
    kwargs : dict, optional
        Keyword arguments of ``fn`` (picklable).

    Returns
    -------
    The function's result.

    Raises
    ------
    ValueError
        The function's own ``ValueError``, unchanged.
    SandboxError
        The child exceeded the memory or time limit, died, or raised anything else.
    """
    if memory_bytes <= 0 or not timeout_s > 0:
        raise ValueError("memory_bytes and timeout_s must be positive")
    ctx = _context()
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(send, fn, args, kwargs or {}, memory_bytes), name="rotordiag-sandbox")
    proc.start()
    send.close()
    try:
        if not recv.poll(timeout_s):
            raise SandboxError(f"reading {what} took longer than {timeout_s:g} s and was stopped; the file is "
                               "corrupt or built to stall the reader — export it again, or send CSV or NPY")
        try:
            tag, payload = recv.recv()
        except (EOFError, OSError):
            proc.join(1.0)
            raise SandboxError(f"the reader of {what} crashed (exit code {proc.exitcode}); the file is corrupt "
                               "or built to crash the reader — export it again, or send CSV or NPY") from None
    finally:
        recv.close()
        if proc.is_alive():
            proc.kill()
        proc.join()
    if tag == "ok":
        return payload  # type: ignore[no-any-return]
    if tag == "value":
        raise payload
    if tag == "memory":
        raise SandboxError(f"reading {what} needed more than {memory_bytes / 2**20:.0f} MiB and was stopped; the "
                           "file is corrupt or built to exhaust memory — export it again, or send CSV or NPY")
    raise SandboxError(f"cannot read {what} ({payload}); it is corrupt or not what it claims to be")


def available() -> bool:
    """Whether child processes can be started from here (not in a daemonic process)."""
    return not multiprocessing.current_process().daemon and sys.platform != "emscripten"
