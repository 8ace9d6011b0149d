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
from .schemas import (
    MAX_BATCH_VALUES,
    MAX_CHANNELS,
    MAX_KEYPHASOR_PULSES,
    MAX_POINTS,
    MAX_RECORD_VALUES,
    BatchEnvelope,
    BatchRecord,
    DiagnoseRequest,
    RecordingIn,
)

#: chunks an uploaded HDF5 file may be stored in: h5py's automatic chunking of a full recording (8 × 262,144
#: float64) makes 512, and each chunk costs a call when its compression ratio is checked
MAX_HDF5_CHUNKS = 8192

#: Default probe layout for an 8-channel array: bearings 1-4, an XY pair each (the reader's default).
DEFAULT_BEARINGS = (1, 1, 2, 2, 3, 3, 4, 4)
DEFAULT_PAIR_ANGLES_DEG = (45.0, 135.0)
#: the query parameters that become reader options (``service.api.routes.diagnose``)
OPTION_QUERY_KEYS = ("sample_rate_hz", "speed_rpm", "speed_range_rpm", "clearance_um", "units", "sensitivity_v_per_mm",
                     "gap_voltage_v", "rotation", "viewed_from", "keyphasor_channel", "keyphasor_edge",
                     "keyphasor_threshold_v", "dc_removed", "acquisitions")


#: a request body as the routes read it: the bytes, or for a multipart upload of several take files each file's
#: bytes and name (``kind`` = "takes")
Body = bytes | tuple[tuple[bytes, str], ...]


def service_limits() -> Any:
    """What one upload may make the reader allocate (one recording: the request schema's bounds)."""
    from rotordiag.features.reader import ReadLimits

    return ReadLimits(max_channels=MAX_CHANNELS, max_points=MAX_POINTS, max_file_bytes=512 * 2**20,
                      max_hdf5_bytes=64 * 2**20, max_keyphasor_pulses=MAX_KEYPHASOR_PULSES,
                      max_hdf5_chunks=MAX_HDF5_CHUNKS)


def _read_error(exc: ValueError) -> InputError:
    """The reader's (or ``safe_io``'s) message as a 422."""
    return exc if isinstance(exc, InputError) else InputError(str(exc))


def recording_from_model(req: RecordingIn) -> Any:
    """``features.Recording`` from the JSON form (validated by pydantic), through the reader. The channels' samples
    are handed over as pydantic validated them, not copied into new lists by ``model_dump`` (131,072 numbers in
    bench_service's recording: 0.8 ms)."""
    from rotordiag.features.reader import recording_from_dict

    d = req.model_dump(exclude={"channels", "plant_model"})
    d["channels"] = [{**ch.model_dump(exclude={"data"}), "data": ch.data} for ch in req.channels]
    return recording_from_dict(d, limits=service_limits()).recording


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
    if q.get("sensitivity") is not None:
        if "sensitivity_v_per_mm" in opts:
            raise InputError("sensitivity and sensitivity_v_per_mm: give the probe sensitivity once")
        opts["sensitivity_v_per_mm"] = str(q["sensitivity"])
    if q.get("channel_map") is not None:
        from rotordiag.features.reader import parse_channel_map

        if q.get("bearings") is not None or q.get("angles_deg") is not None:
            raise InputError("channel_map and bearings/angles_deg: give the layout one way, by column name "
                             "(channel_map) or in file order (bearings, angles_deg)")
        try:
            mapping = parse_channel_map(str(q["channel_map"]))
        except ValueError as exc:
            raise InputError(f"channel_map: {exc}") from None
        if not isinstance(mapping, dict):
            raise InputError("channel_map: give COLUMN=b<bearing>@<angle> for each probe column, separated by ';' "
                             "(e.g. 'GEN DE X=b2@45;GEN DE Y=b2@135'); a layout in file order goes in bearings= "
                             "and angles_deg=")
        opts["channels"] = mapping
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


#: what an asset's probe configuration holds (``PUT /assets/{id}/probes``), as groups of query parameters:
#: an upload that gives any parameter of a group replaces the configuration's whole group
PROBE_CONFIG_GROUPS: dict[str, tuple[str, ...]] = {
    "layout": ("channel_map", "bearings", "angles_deg"), "units": ("units",),
    "sensitivity": ("sensitivity", "sensitivity_v_per_mm"), "gap_voltage": ("gap_voltage_v",),
    "keyphasor": ("keyphasor_channel",), "rotation": ("rotation", "viewed_from"), "clearance": ("clearance_um",),
    "speed_band": ("speed_range_rpm",), "model": ("model_version",), "plant_model": ("plant_model", "plant_shaftline")}
PROBE_CONFIG_KEYS = tuple(k for keys in PROBE_CONFIG_GROUPS.values() for k in keys)


def plant_of_model(name: str | None, shaftline: dict[str, Any] | None = None) -> Any:
    """The lumped plant of an asset's plant model: ``default`` (MODEL.md's), a preset's shaft line, or the asset's
    own shaft-line tables, reduced (``simulator.shaftline.to_plant``); InputError saying what to fix."""
    from rotordiag.simulator import Plant
    from rotordiag.simulator.shaftline import PRESETS, ShaftLine, preset, to_plant

    if name is not None and shaftline is not None:
        raise InputError("plant_model and plant_shaftline: give the asset's plant one way")
    if shaftline is not None:
        try:
            return to_plant(ShaftLine.from_dict(shaftline))
        except (TypeError, ValueError, OverflowError, ZeroDivisionError, FloatingPointError) as exc:
            raise InputError(f"plant_shaftline: {exc}") from None
    if name is None or name == "default":
        return Plant.default()
    if name not in PRESETS:
        raise InputError(f"plant_model {name!r}: use default or a preset: {', '.join(sorted(PRESETS))}")
    return to_plant(preset(name))


def request_plant_model(query_value: str | None, body_value: str | None) -> str | None:
    """The plant model a JSON request declares: its body's ``plant_model`` or the query parameter's (None: neither);
    InputError when both are given and differ."""
    if query_value is not None and body_value is not None and query_value.strip() != body_value.strip():
        raise InputError(f"plant_model: the query parameter says {query_value!r} and the JSON body {body_value!r}; "
                         "give the machine's plant model once (or the same in both)")
    return body_value if body_value is not None else query_value


#: the query key :func:`with_probe_config` sets when the plant model came from the asset's stored configuration
PLANT_FROM_ASSET = "plant_model_from_asset"


def plant_declared_by(query: dict[str, Any], plant_model: str | None) -> str | None:
    """Who declared the plant model a request is diagnosed with: ``asset`` (its stored configuration,
    :func:`with_probe_config`), ``request`` (the query parameter, a JSON body's or a batch record's field), or None
    (none declared)."""
    if query.get(PLANT_FROM_ASSET):
        return "asset"
    return "request" if plant_model is not None or query.get("plant_shaftline") is not None else None


def check_probe_config(config: dict[str, Any]) -> None:
    """Refuse (InputError, saying what to fix) a probe configuration the reader would refuse for every upload."""
    from rotordiag.core.units import INPUT_UNITS, input_unit, sensitivity_v_per_mm

    unknown = sorted(set(config) - set(PROBE_CONFIG_KEYS))
    if unknown:
        raise InputError(f"probe configuration: unknown field(s) {unknown}; allowed: {list(PROBE_CONFIG_KEYS)}")
    options_from_query({k: v for k, v in config.items() if k not in ("model_version", "plant_model", "plant_shaftline")})
    if config.get("plant_model") is not None or config.get("plant_shaftline") is not None:
        plant_of_model(config.get("plant_model"), config.get("plant_shaftline"))
    if config.get("units") is not None and input_unit(str(config["units"])) is None:
        raise InputError(f"probe configuration: units {config['units']!r}: use one of {list(INPUT_UNITS)}")
    for key in ("sensitivity", "sensitivity_v_per_mm"):
        if config.get(key) is not None:
            try:
                sensitivity_v_per_mm(config[key])
            except ValueError as exc:
                raise InputError(f"probe configuration: {exc}") from None


def with_probe_config(query: dict[str, Any], config: dict[str, Any] | None,
                      asset_id: str) -> tuple[dict[str, Any], dict[str, Any] | None]:
    """The upload's query completed by its asset's stored probe configuration (the upload's own parameters win,
    group by group: :data:`PROBE_CONFIG_GROUPS`), and the answer's section saying what was used."""
    if not config:
        return query, None
    out = dict(query)
    used: dict[str, Any] = {}
    overridden: list[str] = []
    for group, keys in PROBE_CONFIG_GROUPS.items():
        stored = {k: config[k] for k in keys if config.get(k) is not None}
        if not stored:
            continue
        if any(query.get(k) is not None for k in keys):
            overridden.append(group)
            continue
        out.update(stored)
        used.update(stored)
        if group == "plant_model":
            out[PLANT_FROM_ASSET] = True
    return out, {"asset_id": asset_id, "used": used, "overridden_by_upload": overridden}


def checked(build, *args):
    """Call a recording constructor, turning its ValueError (bad recording) into a 422."""
    try:
        return build(*args)
    except ValueError as exc:
        raise _read_error(exc) from None


#: the most values one array of a JSON body may hold (a channel's samples; a keyphasor train is shorter)
MAX_ARRAY_VALUES = max(MAX_POINTS, MAX_KEYPHASOR_PULSES)


def _validated_json(model: Any, body: bytes, max_values: int) -> Any:
    """``model`` validated from a JSON body; a body that may hold more than ``max_values`` values (413, counted
    before anything is decoded) and non-finite numbers (422) refused first, saying so."""
    from rotordiag.features.safe_io import UnsafeFileError, check_json_finite, count_json_values

    try:
        count_json_values(body, max_values, MAX_ARRAY_VALUES)
    except UnsafeFileError as exc:
        raise InputError(str(exc), "too_large") from None
    try:
        check_json_finite(body)                # malformed JSON passes: pydantic reports it with its location
    except UnsafeFileError as exc:
        raise InputError(str(exc)) from None
    try:
        return model.model_validate_json(body)
    except ValidationError as exc:
        raise RequestInvalid(validation_detail(exc, ("body",))) from None


def parse_batch(body: bytes) -> list[dict[str, Any]]:
    """The records of a POST /diagnose/batch body, each still to be validated by :func:`batch_record` (4xx as for
    :func:`parse_body` when the body itself is wrong: not JSON, no ``records`` list, too many values)."""
    return _validated_json(BatchEnvelope, body, MAX_BATCH_VALUES).records


def batch_record(record: dict[str, Any]) -> BatchRecord:
    """One record of a batch validated as a ``BatchRecord`` (:class:`RequestInvalid` naming its fields)."""
    try:
        return BatchRecord.model_validate(record)
    except ValidationError as exc:
        raise RequestInvalid(validation_detail(exc, ("record",))) from None


#: query parameters that apply to the slow-roll file instead of the main file's (the rest are shared:
#: it is recorded with the same probes and acquisition set-up)
SLOW_ROLL_QUERY_KEYS = {"slow_roll_sample_rate_hz": "sample_rate_hz", "slow_roll_keyphasor_times_s": "keyphasor_times_s"}


def _slow_roll_recording(slow_roll: tuple[bytes, str], query: dict[str, Any]) -> Any:
    """The slow-roll upload read like the main one: same reader, limits and sandbox; its own sample rate and
    keyphasor times when given (``slow_roll_sample_rate_hz``, ``slow_roll_keyphasor_times_s``), no speed."""
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
    return _read_file(data, name, opts, "slow_roll_file").recording


def _read_file(data: bytes, name: str, opts: Any, what: str | None = None) -> Any:
    """One uploaded file through the reader (``ReadResult``); its refusal as a 422, prefixed with ``what`` and the
    file's name (``None``: the request's one recording, the reader's message as it is)."""
    from rotordiag.features.reader import read_recording

    try:
        return read_recording(data, filename=name, options=opts, limits=service_limits())
    except ValueError as exc:
        if "unknown file type" in str(exc):
            raise InputError(f"{what or 'multipart upload'} {name!r}: unknown file type; send .csv, .npy, .h5, .hdf5, "
                             ".uff, .unv or .json", "unsupported_type") from None
        if what is None:
            raise _read_error(exc) from None
        raise InputError(f"{what} {name!r}: {exc}") from None


#: the most take files one multipart upload may carry (each holds bearings of its own, of bearings 1-4)
MAX_TAKE_FILES = 4
#: query parameters that describe each take file of a multipart upload on its own: one value per file, separated
#: by ';' in the order the files are sent. ``angles_deg`` and ``keyphasor_channel`` may be one value for every file;
#: ``bearings`` and ``keyphasor_times_s`` never (a bearing is in one take only; each take has its own clock).
PER_TAKE_QUERY_KEYS = ("bearings", "angles_deg", "keyphasor_channel", "keyphasor_times_s")
_ONE_FOR_ALL = ("angles_deg", "keyphasor_channel")


def take_queries(query: dict[str, Any], labels: list[str]) -> list[dict[str, Any]]:
    """Each take file's query parameters: the shared ones, and its own part of every ``PER_TAKE_QUERY_KEYS`` value.

    Raises
    ------
    InputError
        ``acquisitions`` given (each file is one), or a per-take value with a count of parts other than the files'.
    """
    n = len(labels)
    if (query.get("channel_map") or "").strip():
        raise InputError(f"channel_map with {n} take files: give each take's layout in file order with bearings= "
                         "and angles_deg= (one value per file, separated by ';'), or name the columns b2@45")
    if (query.get("acquisitions") or "").strip():
        raise InputError(f"acquisitions: the {n} files in part 'file' are the takes, each its own acquisition; leave "
                         "acquisitions out (or send one file holding every take, with acquisitions)")
    out = [dict(query) for _ in labels]
    for key in PER_TAKE_QUERY_KEYS:
        text = query.get(key)
        if text is None or not str(text).strip():
            continue
        parts = [part.strip() for part in str(text).split(";")]
        if len(parts) == 1 and key in _ONE_FOR_ALL:
            continue
        if len(parts) != n:
            raise InputError(f"{key}: {len(parts)} value(s) for {n} take files ({', '.join(labels)}); give one per "
                             "file, separated by ';' in the order the files are sent"
                             + (" (a bearing is in one take only)" if key == "bearings" else "")
                             + (" (each take's pulses on its own clock)" if key == "keyphasor_times_s" else ""))
        for q, part in zip(out, parts):
            q[key] = part or None
    return out


def _parse_takes(files: tuple[tuple[bytes, str], ...], query: dict[str, Any]) -> Any:
    """The takes of one recording, uploaded as separate files, read one by one and merged
    (``features.take_files.merge_takes``: each file one acquisition, its keyphasor that take's)."""
    from rotordiag.features.take_files import merge_takes

    names = [name or f"take {i + 1}" for i, (_, name) in enumerate(files)]
    labels = names if len(set(names)) == len(names) else [f"take {i + 1} ({n})" for i, n in enumerate(names)]
    if len(files) > MAX_TAKE_FILES:
        raise InputError(f"{len(files)} files in part 'file': at most {MAX_TAKE_FILES} takes (bearings 1-4)")
    results = []
    for (data, name), label, q in zip(files, labels, take_queries(query, labels)):
        if not data:
            raise InputError(f"take file {label!r} is empty: send the take's recording (CSV/NPY/HDF5/UFF/JSON)")
        try:
            opts = options_from_query(q)
        except InputError as exc:
            raise InputError(f"take file {label!r}: {exc}") from None
        results.append(_read_file(data, name, opts, "take file"))
    try:
        merged = merge_takes(results, labels)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    if len(merged.recording.channels) > MAX_CHANNELS:
        raise InputError(f"the takes hold {len(merged.recording.channels)} probe channels together; at most "
                         f"{MAX_CHANNELS} (two per bearing)")
    return merged


def parse_body(kind: str, body: Body, filename: str, query: dict[str, Any],
               slow_roll: tuple[bytes, str] | None = None) -> tuple[Any, str | None, str | None]:
    """Recording, asset_id, plant from a request body (:func:`parse_request` without the reader's notes)."""
    return parse_request(kind, body, filename, query, slow_roll)[:3]


def parse_request(kind: str, body: Body, filename: str, query: dict[str, Any],
                  slow_roll: tuple[bytes, str] | None = None) -> tuple[Any, str | None, str | None, list[str], str | None]:
    """Recording, asset_id, plant, the reader's notes (what it assumed or left out: the time column's
    sample rate, the unit conversion, columns not read) and the declared plant model from a request body
    (a JSON body's ``plant_model``, else the query's: :func:`request_plant_model`).

    Parameters
    ----------
    kind : {"json", "npy", "upload", "takes"}
        How the body came (``service.api.recordings.read_body``).
    body : bytes, or for ``takes`` a tuple of (bytes, file name)
        ``takes``: the files of a multipart upload with several parts ``file``, the takes of one recording
        (a portable analyser's, bearing pair by bearing pair), merged by :func:`_parse_takes`.
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
    if isinstance(body, tuple):                 # kind "takes"
        if slow_roll is not None:
            raise InputError("a slow-roll file with several take files is not taken: send the takes as one file with "
                             "acquisitions and a keyphasor per take, or use `rotordiag diagnose --takes --slow-roll`")
        res = _parse_takes(body, query)
    else:
        if slow_roll is not None and kind != "upload":
            raise InputError("a slow-roll recording comes as a second file (part 'slow_roll_file') of a multipart "
                             "upload; with a JSON body give the slow-roll vectors per channel (channels[].slow_roll)")
        if kind == "json":
            req = _validated_json(DiagnoseRequest, body, MAX_RECORD_VALUES)
            plant_model = request_plant_model(query.get("plant_model"), req.plant_model)
            return checked(recording_from_model, req), req.asset_id, req.plant, [], plant_model
        if not body:
            raise InputError("empty body: send an NPY file (numpy.save) with an (n_channels, n_points) array, "
                             "or a CSV/HDF5/JSON file as a multipart upload")
        if kind == "npy" and not body.startswith(b"\x93NUMPY"):
            raise InputError("body is not an NPY file (it must start with the \\x93NUMPY magic); "
                             "write it with numpy.save, or send JSON with Content-Type application/json")
        if ";" in (query.get("bearings") or ""):
            raise InputError("bearings: ';' separates the take files of a multipart upload with several files in "
                             "part 'file'; this request has one recording: give one bearing per row, comma-separated")
        res = _read_file(body, filename if kind == "upload" else "body.npy", options_from_query(query))
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
    return recording, asset_id, plant, list(res.notes), query.get("plant_model")
