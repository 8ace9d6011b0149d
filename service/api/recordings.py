"""Reading a recording's request — its body (JSON, NPY, files) and the query parameters that describe it — and
running a call on it in a diagnosis worker: shared by ``POST /diagnose`` (``api/routes/diagnose.py``), the asset
routes and the web page's plot data (``service/web/routes.py``), so that every door reads a body alike."""
from __future__ import annotations

from collections.abc import Callable
from typing import Annotated, Any, Literal

import anyio
import anyio.to_thread
from fastapi import Depends, Query, Request

from rotordiag.core.input_bounds import SENSITIVITY_RANGE_V_PER_MM

from ..parsing import MAX_TAKE_FILES, Body, parse_body
from ..pool import DiagnoseBody, DiagnoseRecord, WorkerCall
from ..schemas import MAX_RECORD_VALUES
from .deps import (
    AcquisitionsQuery,
    AnglesQuery,
    BearingsQuery,
    ClearanceQuery,
    KeyphasorQuery,
    SampleRateQuery,
    SpeedQuery,
    SpeedRangeQuery,
    UnitsQuery,
)
from .errors import InputError, raise_worker_error

__all__ = ["reader_query", "ReaderQueryDep", "JSON_TYPES", "NPY_TYPES", "media_type", "read_body", "in_worker",
           "recording_answer", "diagnosis_limiter", "read_json_bounded"]


async def reader_query(
    sample_rate_hz: SampleRateQuery = None,
    speed_rpm: SpeedQuery = None,
    speed_range_rpm: SpeedRangeQuery = None,
    clearance_um: ClearanceQuery = None,
    units: UnitsQuery = None,
    bearings: BearingsQuery = None,
    angles_deg: AnglesQuery = None,
    keyphasor_times_s: KeyphasorQuery = None,
    sensitivity_v_per_mm: Annotated[float | None, Query(ge=SENSITIVITY_RANGE_V_PER_MM[0],
                                                        le=SENSITIVITY_RANGE_V_PER_MM[1], allow_inf_nan=False, description=(
        "Binary/multipart with `units=V` only: probe scale factor, V/mm (7.87 = 200 mV/mil)."))] = None,
    sensitivity: Annotated[str | None, Query(min_length=1, max_length=32, description=(
        "Binary/multipart with `units=V` or `mV` only: the probe sensitivity as the datasheet states it, "
        "`7.87 V/mm`, `200 mV/mil` or `7.87 mV/um` (a bare number is V/mm); instead of `sensitivity_v_per_mm`."))] = None,
    gap_voltage_v: Annotated[float | None, Query(ge=-100, le=100, allow_inf_nan=False, description=(
        "Binary/multipart with `units=V` or `mV` only: DC gap voltage, V (default: each channel's mean)."))] = None,
    channel_map: Annotated[str | None, Query(min_length=1, max_length=2000, description=(
        "CSV/UFF upload only: each probe column's bearing and angle by column name, `COLUMN=b<bearing>@<angle>` "
        "separated by `;` (`GEN DE X=b2@45;GEN DE Y=b2@135`); the file's other columns (besides the time and "
        "keyphasor) are left out and the answer's notes name them. Instead of `bearings`/`angles_deg`."))] = None,
    rotation: Annotated[Literal["ccw", "cw"] | None, Query(description=(
        "Shaft rotation seen from the driver end; with `viewed_from` it decides whether the probe angles "
        "are mirrored so that a mirrored installation is not read as reverse whirl. Default: the asset's "
        "configuration, else `ccw`."))] = None,
    viewed_from: Annotated[Literal["driver", "non-driver"] | None, Query(description=(
        "End of the machine the probe angles are measured from. Default: the asset's configuration, else "
        "`driver`."))] = None,
    keyphasor_channel: Annotated[str | None, Query(max_length=64, description=(
        "Raw keyphasor pulse channel: CSV column name or row index (default: a CSV column named kp/keyphasor); with "
        "`acquisitions`, one per acquisition separated by semicolons (`kp_a;kp_b`)."))] = None,
    keyphasor_edge: Annotated[Literal["falling", "rising"], Query(description=(
        "Edge of the keyphasor pulse: falling (a notch) or rising (a projection, TTL)."))] = "falling",
    keyphasor_threshold_v: Annotated[float | None, Query(allow_inf_nan=False, description=(
        "Keyphasor threshold in the channel's units (default: halfway between its 1st and 99th percentile)."))] = None,
    dc_removed: Annotated[bool | None, Query(description=(
        "The channels' DC part is no shaft position (AC-coupled acquisition): the shaft centreline is not read. "
        "Channels that all average to zero, and `units=V` without `gap_voltage_v`, are read so anyway."))] = None,
    acquisitions: AcquisitionsQuery = None,
) -> dict[str, Any]:
    """Query parameters that describe an uploaded recording (its layout and the reader's options,
    ``features.reader.ReadOptions``), shared by every route that takes one."""
    return dict(sample_rate_hz=sample_rate_hz, speed_rpm=speed_rpm, speed_range_rpm=speed_range_rpm,
                clearance_um=clearance_um, units=units,
                bearings=bearings, angles_deg=angles_deg, keyphasor_times_s=keyphasor_times_s,
                sensitivity_v_per_mm=sensitivity_v_per_mm, sensitivity=sensitivity, gap_voltage_v=gap_voltage_v,
                channel_map=channel_map, rotation=rotation,
                viewed_from=viewed_from, keyphasor_channel=keyphasor_channel, keyphasor_edge=keyphasor_edge,
                keyphasor_threshold_v=keyphasor_threshold_v, dc_removed=dc_removed, acquisitions=acquisitions)


ReaderQueryDep = Annotated[dict, Depends(reader_query)]


def asset_probes_query(state, query: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any] | None]:
    """The upload's query completed by its asset's stored probe configuration (``service.parsing.with_probe_config``)."""
    from ..parsing import with_probe_config
    from ..store import get_probe_config

    with state.sessions() as s:
        found = get_probe_config(s, query["asset_id"])
    return with_probe_config(query, found[0] if found else None, query["asset_id"])


JSON_TYPES = ("application/json",)
NPY_TYPES = ("application/octet-stream", "application/x-npy", "application/npy")


def media_type(request: Request) -> str:
    return request.headers.get("content-type", "").split(";")[0].strip().lower()


async def read_body(request: Request, slow_roll: bool = False) -> tuple[str, Body, str, tuple[bytes, str] | None]:
    """``(kind, body, file name, slow roll)`` of the body: kind is ``json``, ``npy`` or ``upload`` (body: the bytes),
    or ``takes`` (several parts ``file``, the takes of one recording; body: each file's ``(bytes, file name)``); 415
    for anything else. ``slow roll`` is the multipart part ``slow_roll_file`` as ``(bytes, file name)`` (only
    where ``slow_roll`` is allowed; else a second file is refused), or None.

    Only the I/O happens here, on the event loop; parsing runs off the loop (``service.parsing.parse_body``).
    """
    media = media_type(request)
    if media in JSON_TYPES:
        return "json", await read_json_bounded(request, MAX_RECORD_VALUES), "", None
    if media in NPY_TYPES:
        return "npy", await request.body(), "", None
    if media == "multipart/form-data":
        form = await _read_form(request, max_files=MAX_TAKE_FILES + (1 if slow_roll else 0))
        try:
            uploads = form.getlist("file")
            if not uploads or any(isinstance(u, str) for u in uploads):
                raise InputError("multipart upload: put the waveform file in a part named 'file' (with a filename); "
                                 "takes recorded as separate files: one part 'file' each")
            upload = uploads[0]
            second = None
            if slow_roll and "slow_roll_file" in form:
                part = form.get("slow_roll_file")
                if isinstance(part, str):
                    raise InputError("multipart upload: 'slow_roll_file' must be a file part (with a filename) "
                                     "holding the slow-roll recording", "malformed")
                second = (await part.read(), part.filename or "")
            if len(uploads) > 1:
                takes = tuple([(await u.read(), u.filename or "") for u in uploads])   # type: ignore[union-attr]
                return "takes", takes, ", ".join(name for _, name in takes), second
            return "upload", await upload.read(), upload.filename or "", second
        finally:
            await form.close()
    raise InputError(
        f"unsupported Content-Type {media or '(none)'!r}: send application/json (DiagnoseRequest), "
        "application/octet-stream (an NPY array) or multipart/form-data (a CSV/NPY/HDF5 file in part 'file')", "unsupported_type")


async def read_json_bounded(request: Request, max_values: int) -> bytes:
    """A JSON body, its values counted while it streams in: past ``max_values`` (commas bound them from above,
    ``features.safe_io.count_json_values``) it is refused with 413 at once, before the rest is read or anything
    decoded, so a body of millions of numbers never reaches a diagnosis worker."""
    chunks: list[bytes] = []
    commas = 0
    async for chunk in request.stream():
        commas += chunk.count(b",")
        if commas > max_values:
            raise InputError(f"JSON holds more than {max_values} values; send a shorter recording (fewer samples per "
                             "channel), split a batch, or send an NPY array", "too_large")
        chunks.append(chunk)
    return b"".join(chunks)


async def _read_form(request: Request, max_files: int = 1) -> Any:
    """The multipart form, with the parser's complaints in the client's terms (400)."""
    from python_multipart.exceptions import FormParserError
    from starlette.exceptions import HTTPException as StarletteHTTPException
    from starlette.formparsers import MultiPartException

    try:
        return await request.form(max_files=max_files, max_fields=8)
    except (MultiPartException, StarletteHTTPException, FormParserError) as exc:
        # FormParserError: python-multipart's own, which starlette < 1.7 lets through on garbage bodies
        if isinstance(exc, StarletteHTTPException) and exc.status_code != 400:
            raise                      # 408/413 from the body limits
        msg = str(getattr(exc, "detail", None) or getattr(exc, "message", None) or exc)
        if "maximum size" in msg:      # a part without a file name is a form field, limited to 1 MiB
            raise InputError("multipart upload: the part is not a file (its filename is missing or empty); send "
                             "the waveform file in a part named 'file' with a file name ending .csv, .npy, .h5, "
                             ".hdf5 or .json", "malformed") from None
        if "too many files" in msg.lower():
            raise InputError(f"multipart upload: {msg.rstrip('.')}: send the recording in one part 'file', or its "
                             f"takes as separate files (at most {MAX_TAKE_FILES}, one part 'file' each)"
                             + (" and a part 'slow_roll_file'" if max_files > MAX_TAKE_FILES else ""),
                             "malformed") from None
        raise InputError(f"multipart upload cannot be read: {msg}", "malformed") from None


async def in_worker(state, call: WorkerCall) -> tuple:
    """``call`` (a ``service.pool.WorkerCall``) in a diagnosis worker; errors as 4xx/503.

    Returns the ``("ok", ...)`` tuple; every other answer (a client mistake, no model, a worker over
    its time limit or crashed twice) is raised for the error handlers (``service.api.errors``).
    """
    from ..pool import DiagnosisTimeout, WorkerCrashed

    try:
        result = await state.pool.call(call)
    except (WorkerCrashed, DiagnosisTimeout) as exc:
        raise_worker_error(exc)
    if result[0] != "ok":
        raise_worker_error(result, version_given=isinstance(call, (DiagnoseBody, DiagnoseRecord))
                           and call.version is not None)
    return result


async def recording_answer(request: Request, state, query: dict[str, Any],
                           make_call: Callable[[str, Any, str, dict[str, Any]], WorkerCall], fallback) -> Any:
    """Read the body and run ``make_call(kind, body, filename, query)`` (a ``service.pool.WorkerCall``) in a
    diagnosis worker, or ``fallback(recording)`` in a thread of this process when there are none.

    Used by the web page's ``/ui/plot-data`` (service/web/routes.py): the same body forms and messages as
    /diagnose, and the same isolation.
    """
    kind, body, filename, _ = await read_body(request)
    if state.pool is not None:
        return (await in_worker(state, make_call(kind, body, filename, query)))[1]

    def run() -> Any:
        return fallback(parse_body(kind, body, filename, query)[0])

    return await anyio.to_thread.run_sync(run, limiter=diagnosis_limiter(state))



def diagnosis_limiter(state) -> anyio.CapacityLimiter:
    """At most one diagnosis per CPU at a time: the work is CPU-bound, so more threads only thrash
    (requests beyond it wait on the event loop, not in a crowd of threads)."""
    limiter = getattr(state, "diagnosis_limiter", None)
    if limiter is None:
        limiter = state.diagnosis_limiter = anyio.CapacityLimiter(state.settings.effective_diagnosis_threads)
    return limiter
