"""HDF5 storage of a dataset: layout, crash-safe writer with resume, reader.

The layout is documented in ``docs/dataset-format.md``.

Crash safety
------------
* The file is created complete (every dataset, fixed ``n_samples`` rows, all
  attributes) under a temporary name and renamed into place, so the output
  path never holds a half-built structure.
* Samples are written by the parent process only, in HDF5's single-writer /
  multiple-reader (SWMR) mode (``libver="latest"``): SWMR orders metadata
  writes so the file on disk is consistent at every moment, which also makes it
  survive a SIGKILL of the writer. The file is opened straight into SWMR-write
  mode (never plain read-write) and no attribute is changed after creation
  (the resume history is a dataset, ``resume_log``). Each sample's rows are written and flushed,
  then its ``done`` flag is set and flushed: ``done[i] == 1`` implies that
  sample ``i`` is completely on disk.
* After a crash HDF5 leaves the "open for writing" flag set in the superblock:
  the file then opens with ``h5py.File(path, "r", swmr=True)`` (and with
  :func:`open_dataset`, which falls back to that), but a plain
  ``h5py.File(path, "r")`` refuses it until the run is resumed. Resuming
  copies the finished samples (compressed chunks copied as they are) into a
  fresh file built beside it and renames it into place, so a crash during the
  repair loses nothing either.
* An exclusive ``fcntl`` lock on ``<out>.lock`` (released by the OS when the
  process dies) keeps two runs from writing one file.
"""
from __future__ import annotations

import datetime as _dt
import errno
import fcntl
import json
import os
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["FORMAT", "FORMAT_VERSION", "StoreError", "DatasetWriter", "open_dataset", "layout", "sample_kind",
           "require_kind", "TRANSIENT_GROUP",
           "MECHANISM_CODES", "SIMULATED_MECHANISM_CODES", "EncodedChunk", "encode_waveform_chunk",
           "decode_waveform_chunk"]

FORMAT = "rotordiag-dataset"
FORMAT_VERSION = 1
MECHANISM_CODES: dict[str, int] = {"pin": 0, "rigid": 1, "offset": 2, "flexible": 3}
SIMULATED_MECHANISM_CODES: dict[str, int] = {"pin": 0, "rigid": 1, "aligned": 2, "offset": 3, "flexible": 4}
_MESSAGE_LEN = 256
RESUME_LOG_SLOTS = 64
RESUME_LOG_LEN = 512
_KIND_LEN = 16
_NOTE_LEN = 96
#: The waveforms' filter pipeline, in HDF5's write order: byte shuffle, then deflate (gzip) at this level.
WAVEFORM_GZIP_LEVEL = 4
WAVEFORM_DTYPE = "<f4"


class StoreError(RuntimeError):
    """A dataset file that cannot be used as asked (other spec, locked, not a dataset); clear message."""


#: Bytes of ``parameters/plant_source`` (the base plant's label, e.g. ``preset:gen200_2pole``).
PLANT_SOURCE_LEN = 64


def _utcnow() -> str:
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


def _plant_layout(plant_dict: dict[str, Any]) -> dict[str, tuple[tuple[int, ...], str]]:
    out: dict[str, tuple[tuple[int, ...], str]] = {}
    for name, v in plant_dict.items():
        if isinstance(v, dict):  # a train's base shaft line: recorded once per source (plant_sources_json)
            continue
        if isinstance(v, str):
            out[f"parameters/plant/{name}"] = ((), f"S{_KIND_LEN}")
        else:
            out[f"parameters/plant/{name}"] = (np.asarray(v, dtype=float).shape, "f8")
    return out


#: Per-sample datasets that only files whose spec sets ``operating.angular_misalignment_mrad`` have,
#: so that files written before the angular offset keep their layout (and can be resumed and merged).
ANGULAR_DATASETS: tuple[str, ...] = ("parameters/angular_misalignment_mrad", "parameters/plant/exciter_bearing_span_m")


#: Per-sample datasets that only shaft-train files have (``plant.model = "train"``): the offset at the coupling
#: in µm (Δ·c), the generator's unbalance from its balance grade, and the stability margin at the sample's speed.
TRAIN_DATASETS: dict[str, tuple[tuple[int, ...], str]] = {
    "labels/offset_um": ((), "f8"),
    "labels/unbalance_kg_m": ((), "f8"),
    "diagnostics/log_decrement": ((), "f8"),
}


#: The group that only run-up / coast-down files have (a ``[transient]`` spec); its presence marks such a file.
TRANSIENT_GROUP = "transient"


def transient_datasets(n_profile_points: int, n_marks: int) -> dict[str, tuple[tuple[int, ...], str]]:
    """Per-sample datasets of a transient file: its speed profile's points and its keyphasor marks (s from the
    record's start; NaN past the end of a run that stopped early)."""
    return {f"{TRANSIENT_GROUP}/profile_times_s": ((n_profile_points,), "f8"),
            f"{TRANSIENT_GROUP}/profile_speeds_rpm": ((n_profile_points,), "f8"),
            f"{TRANSIENT_GROUP}/keyphasor_times_s": ((n_marks,), "f8")}


def sample_kind(f: Any) -> str:
    """``"transient"`` for a file of run-ups / coast-downs (it has the :data:`TRANSIENT_GROUP`), else ``"steady"``."""
    return "transient" if TRANSIENT_GROUP in f else "steady"


def require_kind(f: Any, kind: str, what: str) -> None:
    """Refuse a file whose samples are not of ``kind`` (``"steady"`` | ``"transient"``) for ``what`` reads them.

    Raises
    ------
    StoreError
        Saying what the file holds and what reads it.
    """
    have = sample_kind(f)
    if have == kind:
        return
    if have == "transient":
        raise StoreError(f"{what} reads steady samples (one speed each); {f.filename} holds run-ups or coast-downs "
                         "(a [transient] spec: a speed profile and a keyphasor per sample): read them with "
                         "DatasetReader.transient_sample (docs/dataset-format.md)")
    raise StoreError(f"{what} reads run-up / coast-down samples; {f.filename} holds steady samples (one speed each, "
                     "no keyphasor): read them with DatasetReader.waveforms")


def layout(n_channels: int, n_points: int, n_bearings: int,
           plant_dict: dict[str, Any], *, angular: bool = False,
           transient: tuple[int, int] | None = None) -> dict[str, tuple[tuple[int, ...], str]]:
    """Per-sample datasets: name → (shape after the sample axis, dtype); ``angular``: the spec uses
    an angular offset (adds :data:`ANGULAR_DATASETS`); a train's plant adds :data:`TRAIN_DATASETS`;
    ``transient`` = (profile points, keyphasor marks) of a run-up file adds :func:`transient_datasets`."""
    L: dict[str, tuple[tuple[int, ...], str]] = {
        "waveforms": ((n_channels, n_points), "f4"),
        "done": ((), "u1"),
    }
    for name in ("speed_rpm", "misalignment", "unbalance", "unbalance_phase_rad", "exciter_unbalance",
                 "exciter_unbalance_phase_rad", "offset_angle_rad", "coupling_phase_rad",
                 "angular_misalignment_mrad"):
        L[f"parameters/{name}"] = ((), "f8")
    L["parameters/mechanism"] = ((), "i1")
    L["parameters/simulated_mechanism"] = ((), "i1")
    L["parameters/sample_seed"] = ((), "u8")
    L["parameters/plant_id"] = ((), "S16")
    L["parameters/plant_source"] = ((), f"S{PLANT_SOURCE_LEN}")
    L["parameters/record_revs"] = ((), "i4")
    L.update(_plant_layout(plant_dict))
    if not angular:
        for name in ANGULAR_DATASETS:
            L.pop(name, None)
    L["measurement/snr_db"] = ((), "f8")
    L["measurement/start_angle_rad"] = ((), "f8")
    L["measurement/speed_fluctuation_phase_rad"] = ((), "f8")
    for name in ("runout_1x_um", "runout_1x_phase_rad", "runout_2x_um", "runout_2x_phase_rad"):
        L[f"measurement/{name}"] = ((n_bearings,), "f8")
    L["labels/misalignment"] = ((), "f8")
    L["labels/severity"] = ((), "i1")
    L["labels/status"] = ((), "i1")
    L["labels/motion_kind"] = ((), f"S{_KIND_LEN}")
    L["labels/motion_period"] = ((), "i2")
    L["diagnostics/nfev"] = ((), "i8")
    L["diagnostics/wall_time_s"] = ((), "f8")
    L["diagnostics/message"] = ((), f"S{_MESSAGE_LEN}")
    L["diagnostics/steady_start"] = ((), f"S{_KIND_LEN}")
    L["diagnostics/steady_start_note"] = ((), f"S{_NOTE_LEN}")
    if plant_dict.get("model") == "train":
        L.update(TRAIN_DATASETS)
    if transient is not None:
        L.update(transient_datasets(*transient))
    return L


@dataclass(frozen=True)
class EncodedChunk:
    """One waveform chunk, already through the shuffle + deflate pipeline (what HDF5 stores on disk)."""

    data: bytes
    shape: tuple[int, ...]     # the chunk's shape without the sample axis, e.g. (C, P)
    dtype: str = WAVEFORM_DTYPE
    gzip_level: int = WAVEFORM_GZIP_LEVEL

    def decode(self) -> np.ndarray:
        return decode_waveform_chunk(self)


def encode_waveform_chunk(values: np.ndarray, level: int = WAVEFORM_GZIP_LEVEL) -> EncodedChunk:
    """HDF5's shuffle filter (byte k of every element together, k = 0..3) then zlib deflate at ``level``.

    The bytes are what ``H5Z_filter_shuffle`` + ``H5Z_filter_deflate`` produce for the chunk, so
    :meth:`DatasetWriter.write_sample` can store them with ``write_direct_chunk``.
    """
    import zlib

    a = np.ascontiguousarray(values, dtype=WAVEFORM_DTYPE)
    shuffled = a.reshape(-1).view(np.uint8).reshape(-1, a.dtype.itemsize).T.tobytes()
    return EncodedChunk(zlib.compress(shuffled, level), tuple(a.shape), WAVEFORM_DTYPE, level)


def decode_waveform_chunk(chunk: EncodedChunk) -> np.ndarray:
    """Inverse of :func:`encode_waveform_chunk` (inflate, then unshuffle)."""
    import zlib

    dt = np.dtype(chunk.dtype)
    raw = np.frombuffer(zlib.decompress(chunk.data), dtype=np.uint8)
    return raw.reshape(dt.itemsize, -1).T.copy().view(dt).reshape(chunk.shape)


def _fill(dtype: str) -> Any:
    if dtype.startswith("f"):
        return np.nan
    if dtype.startswith("S"):
        return b""
    if dtype == "i1" or dtype == "i2":
        return -1
    return 0


def create_file(path: Path, n_samples: int, L: dict[str, tuple[tuple[int, ...], str]],
                channels: list[tuple[int, float]], attrs: dict[str, Any],
                dataset_attrs: dict[str, dict[str, Any]], compression: str = "gzip") -> None:
    """Create the full, empty structure at ``path`` (atomically: temp file + rename)."""
    import h5py

    tmp = path.with_name(path.name + ".creating")
    tmp.unlink(missing_ok=True)
    with h5py.File(tmp, "w", libver="latest") as f:
        for name, (tail, dtype) in L.items():
            shape = (n_samples, *tail)
            if name == "waveforms":
                kw = dict(chunks=(1, *tail), shuffle=True, compression=compression,
                          compression_opts=WAVEFORM_GZIP_LEVEL if compression == "gzip" else None)
            else:
                rows = max(1, min(n_samples, 4096 // max(1, int(np.prod(tail)))))
                kw = dict(chunks=(rows, *tail))
            f.create_dataset(name, shape=shape, dtype=dtype, fillvalue=_fill(dtype), **kw)
            for k, v in dataset_attrs.get(name, {}).items():
                f[name].attrs[k] = v
        f.create_dataset("resume_log", shape=(RESUME_LOG_SLOTS,), dtype=f"S{RESUME_LOG_LEN}", fillvalue=b"")
        f["resume_log"].attrs["description"] = "one JSON entry per resumed run (time_utc, code_version, n_done, repaired)"
        ch = np.array(channels, dtype=[("bearing", "i1"), ("angle_deg", "f8")])
        f.create_dataset("channels", data=ch)
        f["channels"].attrs["description"] = "probe channels: bearing 1-4, angle in degrees CCW from +x (90 = top)"
        for k, v in attrs.items():
            f.attrs[k] = v
        f.flush()
        os.fsync(f.id.get_vfd_handle())
    os.replace(tmp, path)
    _fsync_dir(path.parent)


def _fsync_dir(d: Path) -> None:
    try:
        fd = os.open(d, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


@contextmanager
def open_dataset(path: str | os.PathLike) -> Iterator[Any]:
    """Open a dataset file read-only, also while it is being written or after a crash.

    Yields
    ------
    h5py.File
    """
    import h5py

    path = Path(path)
    if not path.is_file():
        raise StoreError(f"{str(path)!r} does not exist")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        if "h5clear" not in str(exc) and "already open" not in str(exc):
            raise StoreError(f"{str(path)!r} is not a readable HDF5 file: {exc}") from None
        f = h5py.File(path, "r", swmr=True)  # being written, or its writer was killed
    try:
        if f.attrs.get("format") != FORMAT:
            raise StoreError(f"{str(path)!r} is an HDF5 file but not a rotordiag dataset (no format attribute)")
        yield f
    finally:
        f.close()


class _Lock:
    """Exclusive advisory lock on ``<path>.lock`` (released by the OS if the process dies)."""

    def __init__(self, path: Path):
        self.path = path.with_name(path.name + ".lock")
        self.fd: int | None = None

    def acquire(self) -> None:
        for _ in range(20):
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                os.close(fd)
                if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    try:
                        holder = self.path.read_text().strip() or "?"
                    except OSError:
                        holder = "?"
                    raise StoreError(f"another process (pid {holder}) is writing {str(self.path)[:-5]!r}; "
                                     "wait for it to finish or stop it, then rerun to resume") from None
                raise
            try:  # the previous holder may have unlinked the file between our open and flock
                same = os.stat(self.path).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if same:
                os.ftruncate(fd, 0)
                os.write(fd, str(os.getpid()).encode())
                self.fd = fd
                return
            os.close(fd)
        raise StoreError(f"could not lock {str(self.path)!r}; retry")

    def release(self) -> None:
        if self.fd is not None:
            try:
                self.path.unlink(missing_ok=True)
            finally:
                os.close(self.fd)
                self.fd = None


class DatasetWriter:
    """Open (create, resume or repair) a dataset file and write finished samples into it.

    Use :meth:`open` as a context manager. ``done`` is the boolean mask of
    finished samples; :meth:`write_sample` writes one sample and flushes.
    """

    def __init__(self, path: Path, f: Any, lock: _Lock, resumed: bool, repaired: bool):
        self.path = path
        self.f = f
        self._lock = lock
        self.resumed = resumed
        self.repaired = repaired
        self.done = f["done"][...].astype(bool)
        self._ds = {name: f[name] for name in _dataset_names(f)}
        self._direct_waveforms = _takes_encoded_chunks(self._ds["waveforms"])

    # ------------------------------------------------------------------ opening
    @classmethod
    def open(cls, path: str | os.PathLike, *, n_samples: int, spec_hash: str,
             L: dict[str, tuple[tuple[int, ...], str]], channels: list[tuple[int, float]],
             attrs: dict[str, Any], dataset_attrs: dict[str, dict[str, Any]],
             code_version: str) -> DatasetWriter:
        """Create ``path``, or reopen it to resume when it was made from the same spec.

        Raises
        ------
        StoreError
            If the file was made from another spec, is not a dataset, is a
            merged file, or is being written by another process.
        """

        path = Path(path)
        if path.parent and not path.parent.exists():
            raise StoreError(f"output folder {str(path.parent)!r} does not exist")
        lock = _Lock(path)
        lock.acquire()
        try:
            path.with_name(path.name + ".creating").unlink(missing_ok=True)
            path.with_name(path.name + ".repair").unlink(missing_ok=True)
            resumed = repaired = False
            if not path.exists():
                create_file(path, n_samples, L, channels, attrs, dataset_attrs)
            else:
                resumed = True
                crashed = _check_existing(path, spec_hash, n_samples, L)
                if crashed:
                    _repair(path, n_samples, L)
                    repaired = True
            f = _open_swmr_write(path)
            try:
                if resumed:
                    _append_resume_log(f, {"time_utc": _utcnow(), "code_version": code_version,
                                           "n_done": int(np.count_nonzero(f["done"][...])), "repaired": repaired})
            except BaseException:
                f.close()
                raise
            return cls(path, f, lock, resumed, repaired)
        except BaseException:
            lock.release()
            raise

    # ------------------------------------------------------------------ writing
    def write_sample(self, index: int, rows: dict[str, Any]) -> None:
        """Write one sample's values (dataset name → value) and mark it done, flushing in between.

        ``rows["waveforms"]`` may be an array or an :class:`EncodedChunk` (stored as it is when
        the file's waveform filters are the ones it was encoded for, else decoded and written).
        """
        for name, value in rows.items():
            if isinstance(value, EncodedChunk):
                self._write_encoded(name, index, value)
            else:
                self._write_row(name, index, value)
        self.f.flush()
        self._write_row("done", index, 1)
        self.f.flush()
        self.done[index] = True

    def _write_row(self, name: str, index: int, value: Any) -> None:
        # low-level H5Dwrite of one row: ~3x less overhead than h5py's ds[index] = value,
        # which matters with ~50 small datasets per sample written by one parent process
        from h5py import h5s

        ds = self._ds[name]
        tail = ds.shape[1:]
        arr = np.ascontiguousarray(np.asarray(value, dtype=ds.dtype).reshape((1, *tail)))
        fspace = ds.id.get_space()
        fspace.select_hyperslab((int(index), *(0,) * len(tail)), (1, *tail))
        ds.id.write(h5s.create_simple(arr.shape), fspace, arr)

    def _write_encoded(self, name: str, index: int, chunk: EncodedChunk) -> None:
        ds = self._ds[name]
        if (name == "waveforms" and self._direct_waveforms and chunk.shape == ds.shape[1:]
                and np.dtype(chunk.dtype) == ds.dtype and chunk.gzip_level == ds.compression_opts):
            ds.id.write_direct_chunk((int(index), *(0,) * (ds.ndim - 1)), chunk.data, 0)
        else:
            self._write_row(name, index, chunk.decode())

    def close(self) -> None:
        """Close the file (clears HDF5's writing flag) and release the lock."""
        if self.f is None:
            return
        try:
            self.f.close()
            self.f = None
        finally:
            self._lock.release()

    def __enter__(self) -> DatasetWriter:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def _takes_encoded_chunks(ds: Any) -> bool:
    """True when ``ds`` stores one sample per chunk through exactly shuffle, then deflate."""
    from h5py import h5z

    dcpl = ds.id.get_create_plist()
    filters = [dcpl.get_filter(k)[0] for k in range(dcpl.get_nfilters())]
    return (ds.chunks == (1, *ds.shape[1:]) and filters == [h5z.FILTER_SHUFFLE, h5z.FILTER_DEFLATE]
            and ds.dtype == np.dtype(WAVEFORM_DTYPE))


def _open_swmr_write(path: Path) -> Any:
    """Open straight into SWMR-write mode: the file is never open for plain (non-SWMR) writing."""
    import h5py
    from h5py import h5f, h5p

    fapl = h5p.create(h5p.FILE_ACCESS)
    fapl.set_libver_bounds(h5f.LIBVER_LATEST, h5f.LIBVER_LATEST)
    # A reader that opened the file just before us (``dataset info``, a monitoring
    # script) holds HDF5's file lock for a moment: wait for it rather than fail.
    deadline = time.monotonic() + SWMR_OPEN_WAIT_S
    while True:
        try:
            fid = h5f.open(os.fsencode(path), h5f.ACC_RDWR | h5f.ACC_SWMR_WRITE, fapl=fapl)
            return h5py.File(fid)
        except BlockingIOError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.05)


#: How long the writer waits for a concurrent reader's HDF5 file lock to clear.
SWMR_OPEN_WAIT_S = 10.0


def _append_resume_log(f: Any, entry: dict[str, Any]) -> None:
    log = f["resume_log"]
    used = [bool(x) for x in log[...]]
    slot = used.index(False) if False in used else len(used) - 1  # full: the last slot keeps the latest
    log[slot] = json.dumps(entry).encode()[:RESUME_LOG_LEN]
    f.flush()


def _dataset_names(f: Any) -> list[str]:
    names: list[str] = []

    def visit(name: str, obj: Any) -> None:
        import h5py

        if isinstance(obj, h5py.Dataset) and name not in ("channels", "resume_log"):
            names.append(name)

    f.visititems(visit)
    return names


def _check_existing(path: Path, spec_hash: str, n_samples: int, L: dict) -> bool:
    """Validate an existing output file for resuming; return True if its writer crashed."""
    import h5py

    crashed = False
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        if "h5clear" not in str(exc) and "already open" not in str(exc):
            raise StoreError(f"{str(path)!r} exists but is not a readable HDF5 file ({exc}); "
                             "choose another --out or remove it") from None
        f = h5py.File(path, "r", swmr=True)
        crashed = True
    with f:
        if f.attrs.get("format") != FORMAT:
            raise StoreError(f"{str(path)!r} exists and is not a rotordiag dataset; choose another --out")
        if f.attrs.get("merged", False):
            raise StoreError(f"{str(path)!r} is a merged dataset and cannot be resumed; choose another --out")
        old = str(f.attrs.get("spec_hash", ""))
        if old != spec_hash:
            raise StoreError(
                f"{str(path)!r} was generated from a different spec (spec hash {old[:12]}…, this spec "
                f"{spec_hash[:12]}…); use the spec it was made with to resume, or choose another --out")
        if f["done"].shape != (n_samples,) or set(_dataset_names(f)) != set(L):
            raise StoreError(f"{str(path)!r} has another layout than this spec produces (older format or "
                             "code); choose another --out")
    return crashed


def _repair(path: Path, n_samples: int, L: dict) -> None:
    """Copy the finished samples of a crashed file into a fresh one and rename it into place."""
    import h5py

    tmp = path.with_name(path.name + ".repair")
    with h5py.File(path, "r", swmr=True) as src:
        done = src["done"][...].astype(bool)
        channels = [tuple(r) for r in src["channels"][...].tolist()]
        attrs = {k: src.attrs[k] for k in src.attrs}
        dattrs = {name: {k: src[name].attrs[k] for k in src[name].attrs} for name in L}
        comp = src["waveforms"].compression or "gzip"
        create_file(tmp, n_samples, L, channels, attrs, dattrs, compression=comp)
        with h5py.File(tmp, "r+", libver="latest") as dst:
            idx = np.flatnonzero(done)
            sw, dw = src["waveforms"], dst["waveforms"]
            tail = (0,) * (sw.ndim - 1)
            for i in idx:
                filter_mask, chunk = sw.id.read_direct_chunk((int(i), *tail))
                dw.id.write_direct_chunk((int(i), *tail), chunk, filter_mask)
            dst["resume_log"][...] = src["resume_log"][...]
            for name in L:
                if name == "waveforms":
                    continue
                data = src[name][...]
                keep = done.reshape((-1,) + (1,) * (data.ndim - 1))
                dst[name][...] = np.where(keep, data, np.asarray(dst[name].fillvalue, dtype=data.dtype))
            dst.flush()
            os.fsync(dst.id.get_vfd_handle())
    os.replace(tmp, path)
    _fsync_dir(path.parent)


def repair_file(path: str | os.PathLike) -> tuple[bool, int]:
    """Make the file of a killed run open with plain ``h5py.File(path, "r")`` again.

    Copies the finished samples into a fresh file and renames it into place
    (what resuming does, without computing anything).

    Returns
    -------
    (bool, int)
        Whether a repair was needed, and the number of finished samples.
    """
    import h5py

    path = Path(path)
    lock = _Lock(path)
    lock.acquire()
    try:
        path.with_name(path.name + ".repair").unlink(missing_ok=True)
        with open_dataset(path) as f:
            L = {name: (f[name].shape[1:], f[name].dtype.str.lstrip("<>|=")) for name in _dataset_names(f)}
            n_samples = f["done"].shape[0]
            spec_hash = str(f.attrs["spec_hash"])
            merged = bool(f.attrs.get("merged", False))
        crashed = False if merged else _check_existing(path, spec_hash, n_samples, L)
        if crashed:
            _repair(path, n_samples, L)
        with h5py.File(path, "r") as f:
            return crashed, int(np.count_nonzero(f["done"][...]))
    finally:
        lock.release()
