"""Turn request bodies (JSON model, NPY bytes, CSV/NPY/HDF5 uploads) into ``features.Recording``.

Only shape/format problems are checked here (what the features package cannot
see: a file that is not NPY, a CSV with text in it, too many channels); the
physics checks on the waveforms (finite values, equal lengths, units, enough
revolutions for 2X, Nyquist for 3X) are the features package's and reach the
client as 422 with its message.
"""
from __future__ import annotations

import io
from dataclasses import dataclass
from typing import Any

import numpy as np

from fastapi import HTTPException
from pydantic import ValidationError

from .api.errors import InputError, validation_detail
from .schemas import MAX_CHANNELS, MAX_KEYPHASOR_PULSES, MAX_POINTS, DiagnoseRequest, RecordingIn

#: Default probe layout for an 8-channel array: bearings 1-4, an XY pair each.
DEFAULT_BEARINGS = (1, 1, 2, 2, 3, 3, 4, 4)
DEFAULT_PAIR_ANGLES_DEG = (45.0, 135.0)


@dataclass
class BinaryMeta:
    """Metadata that comes with an array body (query parameters)."""

    sample_rate_hz: float
    speed_rpm: float | None = None
    clearance_um: float | None = None
    asset_id: str | None = None
    plant: str | None = None
    units: str = "um"
    bearings: str | None = None
    angles_deg: str | None = None
    keyphasor_times_s: str | None = None


def recording_from_model(req: RecordingIn) -> Any:
    """``features.Recording`` from the JSON form."""
    from features import ProbeChannel, Recording

    channels = [ProbeChannel(bearing=c.bearing, angle_deg=c.angle_deg, units=c.units,
                             data=np.asarray(c.data, dtype=np.float64)) for c in req.channels]
    kp = None if req.keyphasor_times_s is None else np.asarray(req.keyphasor_times_s, dtype=np.float64)
    return Recording(sample_rate_hz=req.sample_rate_hz, channels=channels, speed_rpm=req.speed_rpm,
                     keyphasor_times_s=kp, clearance_um=req.clearance_um)


def _parse_list(text: str | None, name: str, kind: type, n: int | None = None) -> list | None:
    if text is None or text.strip() == "":
        return None
    try:
        values = [kind(v) for v in text.split(",")]
    except ValueError:
        raise InputError(f"{name}: expected comma-separated {'integers' if kind is int else 'numbers'}, "
                         f"got {text[:80]!r}") from None
    if n is not None and len(values) != n:
        raise InputError(f"{name}: {len(values)} values given but the array has {n} channels; "
                         "give one value per channel (row)")
    if kind is float and not all(np.isfinite(values)):
        raise InputError(f"{name}: values must be finite")
    return values


def recording_from_array(array: np.ndarray, meta: BinaryMeta) -> Any:
    """``features.Recording`` from an ``(n_channels, n_points)`` array plus query metadata."""
    from features import ProbeChannel, Recording

    if array.dtype.kind not in "fiu":
        raise InputError(f"array dtype {array.dtype} is not numeric; send float32 or float64 values", 422)
    if array.ndim == 1:
        array = array[None, :]
    if array.ndim == 3 and array.shape[0] == 1:
        array = array[0]
    if array.ndim != 2:
        raise InputError(f"array has shape {array.shape}; expected (n_channels, n_points) with one row per probe")
    n_ch, n_pts = array.shape
    if not 1 <= n_ch <= MAX_CHANNELS:
        hint = " (did you send (n_points, n_channels)? transpose it)" if n_pts <= MAX_CHANNELS < n_ch else ""
        raise InputError(f"array has {n_ch} channels (rows); 1 to {MAX_CHANNELS} are accepted{hint}")
    if not 1 <= n_pts <= MAX_POINTS:
        raise InputError(f"array has {n_pts} points per channel; 1 to {MAX_POINTS} are accepted")
    bearings = _parse_list(meta.bearings, "bearings", int, n_ch)
    angles = _parse_list(meta.angles_deg, "angles_deg", float, n_ch)
    if bearings is None:
        if n_ch != len(DEFAULT_BEARINGS):
            raise InputError(f"bearings: required for a {n_ch}-channel array (the default layout is for 8 channels: "
                             "bearings 1,1,2,2,3,3,4,4); give one bearing number per row, e.g. bearings=2,2,3,3")
        bearings = list(DEFAULT_BEARINGS)
    if angles is None:
        angles = [DEFAULT_PAIR_ANGLES_DEG[i % 2] for i in range(n_ch)]
    kp = _parse_list(meta.keyphasor_times_s, "keyphasor_times_s", float)
    if kp is not None and len(kp) > MAX_KEYPHASOR_PULSES:
        raise InputError(f"keyphasor_times_s: at most {MAX_KEYPHASOR_PULSES} pulses")
    data = np.asarray(array, dtype=np.float64)
    channels = [ProbeChannel(bearing=int(b), angle_deg=float(a), units=meta.units, data=data[i])
                for i, (b, a) in enumerate(zip(bearings, angles))]
    return Recording(sample_rate_hz=meta.sample_rate_hz, channels=channels, speed_rpm=meta.speed_rpm,
                     keyphasor_times_s=None if kp is None else np.asarray(kp), clearance_um=meta.clearance_um)


def load_npy(body: bytes) -> np.ndarray:
    """Array from NPY bytes; never unpickles (object arrays are refused)."""
    if not body:
        raise InputError("empty body: send an NPY file (numpy.save) with an (n_channels, n_points) array")
    if not body.startswith(b"\x93NUMPY"):
        raise InputError("body is not an NPY file (it must start with the \\x93NUMPY magic); "
                         "write it with numpy.save, or send JSON with Content-Type application/json", 422)
    try:
        return np.load(io.BytesIO(body), allow_pickle=False)
    except ValueError as exc:
        if "allow_pickle" in str(exc):
            raise InputError("the NPY body holds Python objects (pickle); only numeric arrays are accepted "
                             "— save a float32/float64 array") from None
        raise InputError(f"cannot read the NPY body (truncated or corrupt?): {exc}") from None
    except (OSError, EOFError) as exc:
        raise InputError(f"cannot read the NPY body (truncated or corrupt?): {exc}") from None


def load_csv(body: bytes) -> np.ndarray:
    """``(n_channels, n_points)`` array from CSV text with one column per probe (an optional header row is skipped)."""
    try:
        text = body.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError("CSV upload is not UTF-8 text") from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise InputError("CSV upload has no data rows; put one probe per column and one sample per row")
    try:
        [float(v) for v in lines[0].split(",")]
    except ValueError:
        lines = lines[1:]  # a header row (probe names)
    if not lines:
        raise InputError("CSV upload has a header but no data rows")
    try:
        rows = np.loadtxt(io.StringIO("\n".join(lines)), delimiter=",", ndmin=2, dtype=np.float64)
    except ValueError as exc:
        raise InputError(f"CSV upload: {exc}; expected numbers only, one probe per column, comma-separated") from None
    return rows.T


def load_hdf5(body: bytes, sample_index: int = 0) -> tuple[np.ndarray, dict[str, Any]]:
    """Array and metadata from an HDF5 upload.

    Layout: a dataset ``waveforms`` of shape ``(n_channels, n_points)``, or
    ``(n_samples, n_channels, n_points)`` as in a rotordiag dataset file (then
    ``sample_index`` picks one); ``sample_rate_hz`` and ``units`` as file or
    dataset attributes; optional channel table ``channels/bearing`` and
    ``channels/angle_deg`` (or datasets ``bearing`` / ``angle_deg``).
    """
    import h5py

    if not body.startswith(b"\x89HDF\r\n\x1a\n"):
        raise InputError("upload is not an HDF5 file (missing the HDF5 signature)")
    meta: dict[str, Any] = {}
    try:
        with h5py.File(io.BytesIO(body), "r") as f:
            if "waveforms" not in f or not isinstance(f["waveforms"], h5py.Dataset):
                raise InputError("HDF5 upload has no dataset 'waveforms' of shape (n_channels, n_points)")
            ds = f["waveforms"]
            if ds.ndim == 3:
                if not 0 <= sample_index < ds.shape[0]:
                    raise InputError(f"sample_index={sample_index} is out of range: the file holds {ds.shape[0]} samples")
                if ds.shape[1] > MAX_CHANNELS or ds.shape[2] > MAX_POINTS:
                    raise InputError(f"HDF5 'waveforms' has shape {ds.shape}; at most {MAX_CHANNELS} channels "
                                     f"of {MAX_POINTS} points are accepted")
                array = ds[sample_index]
            elif ds.ndim in (1, 2):
                if ds.size > MAX_CHANNELS * MAX_POINTS:
                    raise InputError(f"HDF5 'waveforms' has shape {ds.shape}; too large")
                array = ds[()]
            else:
                raise InputError(f"HDF5 'waveforms' has shape {ds.shape}; expected (n_channels, n_points)")
            for src in (f.attrs, ds.attrs):
                for key in ("sample_rate_hz", "units"):
                    if key in src:
                        value = src[key]
                        meta[key] = value.decode() if isinstance(value, bytes) else (
                            str(value) if key == "units" else float(value))
            for key, names in (("bearings", ("channels/bearing", "bearing")),
                               ("angles_deg", ("channels/angle_deg", "angle_deg"))):
                for name in names:
                    if name in f and isinstance(f[name], h5py.Dataset) and f[name].ndim == 1 \
                            and f[name].shape[0] <= MAX_CHANNELS:
                        meta[key] = ",".join(str(v) for v in np.asarray(f[name][()]).ravel().tolist())
                        break
    except InputError:
        raise
    except (OSError, KeyError, ValueError, TypeError) as exc:
        raise InputError(f"cannot read the HDF5 upload: {exc}") from None
    return np.asarray(array), meta


def checked(build, *args):
    """Call a recording constructor, turning its ValueError (bad recording) into a 422."""
    try:
        return build(*args)
    except ValueError as exc:
        if isinstance(exc, InputError):
            raise
        raise InputError(str(exc)) from None


def parse_body(kind: str, body: bytes, filename: str, query: dict[str, Any]) -> tuple[Any, str | None, str | None]:
    """Recording, asset_id, plant from a request body.

    Parameters
    ----------
    kind : {"json", "npy", "upload"}
        How the body came (``service.api.routes.diagnose._read_body``).
    body : bytes
    filename : str
        The uploaded file's name (``upload`` only).
    query : dict
        The binary/multipart metadata query parameters (``None`` = not given).

    Raises
    ------
    InputError, HTTPException
        4xx with a message that says what to fix.
    """
    if kind == "json":
        try:
            req = DiagnoseRequest.model_validate_json(body)
        except ValidationError as exc:
            raise HTTPException(422, validation_detail(exc, ("body",))) from None
        return checked(recording_from_model, req), req.asset_id, req.plant
    if kind == "npy":
        array, file_meta = load_npy(body), {}
    else:
        array, file_meta = load_upload(body, filename, query.get("sample_index", 0))
    given = {k: v for k, v in query.items() if v is not None and k != "sample_index"}
    merged = {**file_meta, **given}  # query parameters win over metadata stored in the file
    if "sample_rate_hz" not in merged:
        raise InputError("sample_rate_hz: required as a query parameter with a binary or multipart body, "
                         "e.g. /diagnose?sample_rate_hz=4096")
    meta = BinaryMeta(**merged)
    return checked(recording_from_array, array, meta), meta.asset_id, meta.plant


def load_upload(data: bytes, filename: str, sample_index: int):
    name = filename.lower()
    if data.startswith(b"\x93NUMPY") or name.endswith(".npy"):
        return load_npy(data), {}
    if data.startswith(b"\x89HDF") or name.endswith((".h5", ".hdf5")):
        return load_hdf5(data, sample_index)
    if name.endswith((".csv", ".txt")) or not name:
        return load_csv(data), {}
    raise InputError(f"multipart upload {filename!r}: unknown file type; send .csv, .npy, .h5 or .hdf5", 415)
