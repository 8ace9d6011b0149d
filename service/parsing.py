"""Turn request bodies (JSON model, NPY bytes, CSV/NPY/HDF5/JSON uploads) into ``features.Recording``.

Every format is decoded by the one reader, :mod:`rotordiag.features.reader` (the CLI uses it
too, so a file means the same recording through either door); this module maps the request's
query parameters to the reader's options and its ``ValueError`` messages to 4xx answers.
The physics checks on the waveforms (finite values, equal lengths, units, enough revolutions
for 2X, Nyquist for 3X) are the features package's and reach the client as 422 with its message.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from pydantic import ValidationError

from .errors import InputError, RequestInvalid, validation_detail
from .schemas import MAX_CHANNELS, MAX_KEYPHASOR_PULSES, MAX_POINTS, BatchRequest, DiagnoseRequest, RecordingIn

#: Default probe layout for an 8-channel array: bearings 1-4, an XY pair each (the reader's default).
DEFAULT_BEARINGS = (1, 1, 2, 2, 3, 3, 4, 4)
DEFAULT_PAIR_ANGLES_DEG = (45.0, 135.0)
#: the query parameters that become reader options (``service.api.routes.diagnose``)
OPTION_QUERY_KEYS = ("sample_rate_hz", "speed_rpm", "speed_range_rpm", "clearance_um", "units", "sensitivity_v_per_mm",
                     "gap_voltage_v", "rotation", "viewed_from", "keyphasor_channel", "keyphasor_edge",
                     "keyphasor_threshold_v", "dc_removed", "acquisitions")


def service_limits() -> Any:
    """What one upload may make the reader allocate (one recording: the request schema's bounds)."""
    from rotordiag.features.reader import ReadLimits

    return ReadLimits(max_channels=MAX_CHANNELS, max_points=MAX_POINTS, max_file_bytes=512 * 2**20,
                      max_hdf5_bytes=64 * 2**20, max_keyphasor_pulses=MAX_KEYPHASOR_PULSES)


def _read_error(exc: ValueError) -> InputError:
    """The reader's (or ``safe_io``'s) message as a 422."""
    return exc if isinstance(exc, InputError) else InputError(str(exc))


def recording_from_model(req: RecordingIn) -> Any:
    """``features.Recording`` from the JSON form (validated by pydantic), through the reader."""
    from rotordiag.features.reader import recording_from_dict

    return recording_from_dict(req.model_dump(), limits=service_limits()).recording


def _parse_list(text: str | None, name: str, kind: type) -> list | None:
    if text is None or text.strip() == "":
        return None
    try:
        values = [kind(v) for v in text.split(",")]
    except ValueError:
        raise InputError(f"{name}: expected comma-separated {'integers' if kind is int else 'numbers'}, "
                         f"got {text[:80]!r}") from None
    if kind is float and not all(np.isfinite(values)):
        raise InputError(f"{name}: values must be finite")
    return values


def options_from_query(query: dict[str, Any]) -> Any:
    """The reader's options from the binary/multipart query parameters (``None`` = not given)."""
    from rotordiag.features.reader import ReadOptions

    q = {k: v for k, v in query.items() if v is not None}
    opts: dict[str, Any] = {k: q[k] for k in OPTION_QUERY_KEYS if k in q}
    kc = opts.get("keyphasor_channel")
    if isinstance(kc, str) and kc.strip().isdigit():
        opts["keyphasor_channel"] = int(kc)
    bearings = _parse_list(q.get("bearings"), "bearings", int)
    angles = _parse_list(q.get("angles_deg"), "angles_deg", float)
    if angles is not None and bearings is None:
        raise InputError("angles_deg: give bearings= too (one bearing number per row, e.g. bearings=2,2,3,3)")
    if bearings is not None:
        if angles is None:
            angles = [DEFAULT_PAIR_ANGLES_DEG[i % 2] for i in range(len(bearings))]
        if len(angles) != len(bearings):
            raise InputError(f"angles_deg: {len(angles)} values for {len(bearings)} bearings; give one angle per row")
        opts["channels"] = list(zip(bearings, angles))
    text = q.get("keyphasor_times_s")
    parts = [_parse_list(part, "keyphasor_times_s", float) for part in text.split(";")] if text else []
    trains: list[list[float]] = [t for t in parts if t is not None]
    if trains:
        if sum(len(t) for t in trains) > MAX_KEYPHASOR_PULSES:
            raise InputError(f"keyphasor_times_s: at most {MAX_KEYPHASOR_PULSES} pulses")
        opts["keyphasor_times_s"] = trains[0] if len(trains) == 1 else trains
    if "sample_index" in q:
        opts["sample_index"] = int(q["sample_index"])
    try:
        return ReadOptions(**opts)
    except TypeError as exc:
        raise InputError(f"query parameters: {exc}") from None


def checked(build, *args):
    """Call a recording constructor, turning its ValueError (bad recording) into a 422."""
    try:
        return build(*args)
    except ValueError as exc:
        raise _read_error(exc) from None


def _validated_json(model: Any, body: bytes) -> Any:
    """``model`` validated from a JSON body; non-finite numbers refused first (422 saying so)."""
    from rotordiag.features.safe_io import UnsafeFileError, loads_json_finite

    try:
        loads_json_finite(body)
    except UnsafeFileError as exc:
        raise InputError(str(exc)) from None
    except (ValueError, UnicodeDecodeError):
        pass                                   # pydantic reports malformed JSON with its location
    try:
        return model.model_validate_json(body)
    except ValidationError as exc:
        raise RequestInvalid(validation_detail(exc, ("body",))) from None


def parse_batch(body: bytes) -> Any:
    """The ``BatchRequest`` of a POST /diagnose/batch body (4xx as for :func:`parse_body`)."""
    return _validated_json(BatchRequest, body)


#: query parameters that apply to the slow-roll file instead of the main file's (the rest are shared:
#: it is recorded with the same probes and acquisition set-up)
SLOW_ROLL_QUERY_KEYS = {"slow_roll_sample_rate_hz": "sample_rate_hz", "slow_roll_keyphasor_times_s": "keyphasor_times_s"}


def _slow_roll_recording(slow_roll: tuple[bytes, str], query: dict[str, Any]) -> Any:
    """The slow-roll upload read like the main one: same reader, limits and sandbox; its own sample rate and
    keyphasor times when given (``slow_roll_sample_rate_hz``, ``slow_roll_keyphasor_times_s``), no speed."""
    from rotordiag.features.reader import read_recording

    data, name = slow_roll
    if not data:
        raise InputError(f"slow_roll_file {name!r} is empty: send the slow-roll recording (CSV/NPY/HDF5/UFF/JSON) "
                         "or leave the part out")
    # the main file's keyphasor times and speed are not the slow roll's; its sample rate is unless given
    q = {k: v for k, v in query.items() if k not in ("speed_rpm", "speed_range_rpm", "sample_index", "keyphasor_times_s",
                                                     "acquisitions", *SLOW_ROLL_QUERY_KEYS)}
    for own, shared in SLOW_ROLL_QUERY_KEYS.items():
        if query.get(own) is not None:
            q[shared] = query[own]
    try:
        opts = options_from_query(q)
    except InputError as exc:
        raise InputError(f"slow_roll_file: {exc}") from None
    try:
        return read_recording(data, filename=name, options=opts, limits=service_limits()).recording
    except ValueError as exc:
        if "unknown file type" in str(exc):
            raise InputError(f"slow_roll_file {name!r}: unknown file type; send .csv, .npy, .h5, .hdf5, .uff, .unv "
                             "or .json", "unsupported_type") from None
        raise InputError(f"slow_roll_file {name!r}: {exc}") from None


def parse_body(kind: str, body: bytes, filename: str, query: dict[str, Any],
               slow_roll: tuple[bytes, str] | None = None) -> tuple[Any, str | None, str | None]:
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
    slow_roll : (bytes, str), optional
        A slow-roll recording uploaded beside the main file (multipart part ``slow_roll_file``) and its
        file name: read the same way, its 1X/2X runout vectors are subtracted from the recording's
        (``features.apply_slow_roll``; the evidence says so).

    Raises
    ------
    InputError, RequestInvalid
        Domain exceptions with a message that says what to fix (4xx in the API layer).
    """
    from rotordiag.features.reader import read_recording

    if slow_roll is not None and kind != "upload":
        raise InputError("a slow-roll recording comes as a second file (part 'slow_roll_file') of a multipart "
                         "upload; with a JSON body give the slow-roll vectors per channel (channels[].slow_roll)")
    if kind == "json":
        req = _validated_json(DiagnoseRequest, body)
        return checked(recording_from_model, req), req.asset_id, req.plant
    if not body:
        raise InputError("empty body: send an NPY file (numpy.save) with an (n_channels, n_points) array, "
                         "or a CSV/HDF5/JSON file as a multipart upload")
    if kind == "npy" and not body.startswith(b"\x93NUMPY"):
        raise InputError("body is not an NPY file (it must start with the \\x93NUMPY magic); "
                         "write it with numpy.save, or send JSON with Content-Type application/json")
    opts = options_from_query(query)
    try:
        res = read_recording(body, filename=filename if kind == "upload" else "body.npy", options=opts,
                             limits=service_limits())
    except ValueError as exc:
        msg = str(exc)
        if "unknown file type" in msg:
            raise InputError(f"multipart upload {filename!r}: unknown file type; send .csv, .npy, .h5, .hdf5, .uff, .unv "
                             "or .json", "unsupported_type") from None
        raise _read_error(exc) from None
    asset_id = query.get("asset_id") or res.asset_id
    plant = query.get("plant") or res.plant
    recording = res.recording
    if slow_roll is not None:
        from rotordiag.features import apply_slow_roll

        slow = _slow_roll_recording(slow_roll, query)
        try:
            recording = apply_slow_roll(recording, slow)[0]
        except ValueError as exc:
            raise InputError(f"slow_roll_file: {exc}") from None
    return recording, asset_id, plant
