"""POST /diagnose and POST /diagnose/batch."""
from __future__ import annotations

import asyncio
import json
from typing import Annotated, Any, Literal

import anyio
import anyio.to_thread
from fastapi import APIRouter, Depends, HTTPException, Query, Request
from fastapi.concurrency import run_in_threadpool

from rotordiag.models.output_units import verdict_in_units

from ...baseline import record_verdict
from ...inference import ModelUnavailable
from ...parsing import MAX_TAKE_FILES, Body, checked, parse_batch, parse_body, recording_from_model
from ...schemas import MAX_LABEL_LEN, AssetId, BatchItem, BatchResponse, DiagnoseResponse, ErrorOut
from ..deps import (
    AcquisitionsQuery,
    AnglesQuery,
    BearingsQuery,
    ClearanceQuery,
    DiagnoseKeyDep,
    JsonBodyDep,
    KeyphasorQuery,
    MayStoreDep,
    ModelsDep,
    SampleRateQuery,
    SpeedQuery,
    SpeedRangeQuery,
    StateDep,
    UnitsQuery,
)
from ..errors import STATUS_OF_KIND, InputError, RequestInvalid, raise_worker_error
from ..routing import FiniteJSONRoute

router = APIRouter(tags=["diagnose"], route_class=FiniteJSONRoute)


def reader_query(
    sample_rate_hz: SampleRateQuery = None,
    speed_rpm: SpeedQuery = None,
    speed_range_rpm: SpeedRangeQuery = None,
    clearance_um: ClearanceQuery = None,
    units: UnitsQuery = None,
    bearings: BearingsQuery = None,
    angles_deg: AnglesQuery = None,
    keyphasor_times_s: KeyphasorQuery = None,
    sensitivity_v_per_mm: Annotated[float | None, Query(gt=0, le=1e3, allow_inf_nan=False, description=(
        "Binary/multipart with `units=V` only: probe scale factor, V/mm (7.87 = 200 mV/mil)."))] = None,
    gap_voltage_v: Annotated[float | None, Query(ge=-100, le=100, allow_inf_nan=False, description=(
        "Binary/multipart with `units=V` only: DC gap voltage, V (default: each channel's mean)."))] = None,
    rotation: Annotated[Literal["ccw", "cw"], Query(description=(
        "Shaft rotation seen from the driver end; with `viewed_from` it decides whether the probe angles "
        "are mirrored so that a mirrored installation is not read as reverse whirl."))] = "ccw",
    viewed_from: Annotated[Literal["driver", "non-driver"], Query(description=(
        "End of the machine the probe angles are measured from."))] = "driver",
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
                sensitivity_v_per_mm=sensitivity_v_per_mm, gap_voltage_v=gap_voltage_v, rotation=rotation,
                viewed_from=viewed_from, keyphasor_channel=keyphasor_channel, keyphasor_edge=keyphasor_edge,
                keyphasor_threshold_v=keyphasor_threshold_v, dc_removed=dc_removed, acquisitions=acquisitions)


ReaderQueryDep = Annotated[dict, Depends(reader_query)]

_ERRORS: dict[int | str, dict[str, Any]] = {
    400: {"model": ErrorOut, "description": "The body cannot be decoded (e.g. JSON that is not UTF-8)."},
    401: {"model": ErrorOut, "description": "No X-API-Key header (only when ROTORDIAG_DIAGNOSE_REQUIRES_KEY)."},
    403: {"model": ErrorOut, "description": "Wrong API key (only when ROTORDIAG_DIAGNOSE_REQUIRES_KEY)."},
    404: {"model": ErrorOut, "description": "`model_version` is not registered."},
    413: {"model": ErrorOut, "description": "Body over the size limit (ROTORDIAG_MAX_BODY_BYTES)."},
    415: {"model": ErrorOut, "description": "Content-Type is not JSON, NPY (application/octet-stream) or multipart."},
    422: {"model": ErrorOut, "description": "The recording cannot be diagnosed; `detail` says what to fix."},
    503: {"model": ErrorOut, "description": "No model is available on the server."},
}

_BINARY_BODY = {
    "requestBody": {
        "required": True,
        "description": "A recording as JSON (`DiagnoseRequest`), as an NPY array of shape (n_channels, n_points) "
        "(`application/octet-stream`; metadata in the query parameters), or as a multipart upload of one "
        "CSV / NPY / HDF5 / UFF file in the part `file` (metadata in the query parameters; HDF5 may carry "
        "`sample_rate_hz`, `units` attributes and a `channels/bearing`, `channels/angle_deg` table). Takes saved "
        "as separate files (a portable analyser's, bearing pair by bearing pair, each with its keyphasor): up to "
        f"{MAX_TAKE_FILES} parts `file`, merged into one recording, each file one acquisition and its keyphasor "
        "that take's; `bearings`, `angles_deg`, `keyphasor_channel` and `keyphasor_times_s` then take one value per "
        "file separated by `;` (docs/service.md).",
        "content": {
            "application/json": {"schema": {"$ref": "#/components/schemas/DiagnoseRequest"}},
            "application/octet-stream": {"schema": {"type": "string", "format": "binary",
                                                    "description": "numpy.save output, (n_channels, n_points)"}},
            "multipart/form-data": {"schema": {
                "type": "object", "required": ["file"],
                "properties": {"file": {"type": "array", "items": {"type": "string", "format": "binary"},
                                        "minItems": 1, "maxItems": MAX_TAKE_FILES,
                                        "description": "CSV (one probe per column), .npy, .h5/.hdf5, .uff or .json "
                                        "file; several: the takes of one recording, each its own acquisition"},
                               "slow_roll_file": {
                                   "type": "string", "format": "binary",
                                   "description": "Optional (POST /diagnose only): a recording of the same probes "
                                   "at slow roll (<= 20 % of the running speed), with a keyphasor in both files; "
                                   "its 1X/2X runout vectors are subtracted from the recording's (docs/recordings.md)"}}}},
        },
    }
}

JSON_TYPES = ("application/json",)
NPY_TYPES = ("application/octet-stream", "application/x-npy", "application/npy")


def _media_type(request: Request) -> str:
    return request.headers.get("content-type", "").split(";")[0].strip().lower()


async def _read_body(request: Request, slow_roll: bool = False) -> tuple[str, Body, str, tuple[bytes, str] | None]:
    """``(kind, body, file name, slow roll)`` of the body: kind is ``json``, ``npy`` or ``upload`` (body: the bytes),
    or ``takes`` (several parts ``file``, the takes of one recording; body: each file's ``(bytes, file name)``); 415
    for anything else. ``slow roll`` is the multipart part ``slow_roll_file`` as ``(bytes, file name)`` (only
    where ``slow_roll`` is allowed; else a second file is refused), or None.

    Only the I/O happens here, on the event loop; parsing runs off the loop (``service.parsing.parse_body``).
    """
    media = _media_type(request)
    if media in JSON_TYPES:
        return "json", await request.body(), "", None
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


async def in_worker(state, name: str, *args: Any) -> tuple:
    """``service.pool``'s worker function ``name`` in a diagnosis worker; errors as 4xx/503.

    Returns the ``("ok", ...)`` tuple; every other answer (a client mistake, no model, a worker over
    its time limit or crashed twice) is raised for the error handlers (``service.api.errors``).
    """
    from ...pool import DiagnosisTimeout, WorkerCrashed

    try:
        result = await state.pool.call(name, *args)
    except (WorkerCrashed, DiagnosisTimeout) as exc:
        raise_worker_error(exc)
    if result[0] != "ok":
        raise_worker_error(result, version_given=name in ("work", "record") and args[-1] is not None)
    return result


async def recording_answer(request: Request, state, query: dict[str, Any], name: str, fallback) -> Any:
    """Read the body and compute ``name`` (a worker function taking ``(kind, body, filename, query)``) in a
    diagnosis worker, or ``fallback(recording)`` in a thread of this process when there are none.

    Used by the web page's ``/ui/plot-data`` (service/web/routes.py): the same body forms and messages as
    /diagnose, and the same isolation.
    """
    kind, body, filename, _ = await _read_body(request)
    if state.pool is not None:
        return (await in_worker(state, name, kind, body, filename, query))[1]

    def run() -> Any:
        return fallback(parse_body(kind, body, filename, query)[0])

    return await anyio.to_thread.run_sync(run, limiter=_diagnosis_limiter(state))


def _diagnose_sync(state, recording, version: str | None) -> dict:
    try:
        verdict = state.models.diagnose(recording, version)
    except ModelUnavailable as exc:
        if version is not None:
            raise InputError(str(exc), "not_found") from None
        raise HTTPException(503, str(exc)) from None
    except ValueError as exc:  # the features/models packages' messages for bad recordings
        raise InputError(str(exc)) from None
    return verdict


#: ``?output_units=`` of the diagnosis routes
OutputUnitsQuery = Annotated[Literal["um", "mil"], Query(
    description="Units of every length in the answer: `um` (micrometres, default) or `mil` (0.001 in = 25.4 µm). "
    "With `mil` the µm-named fields come renamed (`offset_mil`, `b2_1x_major_mil_pp`, …) and the evidence texts "
    "are in mils; pk-pk vs 0-pk stays in the names.")]


@router.post(
    "/diagnose", response_model=DiagnoseResponse, responses=_ERRORS, openapi_extra=_BINARY_BODY,
    dependencies=[DiagnoseKeyDep],
    summary="Diagnose one recording",
    description="Returns the severity class, probabilities, Δ estimate with interval, offset in µm (when "
    "`clearance_um` is given), motion type, per-bearing key features, top contributing features, OOD flag, "
    "warnings and the model version. With an `asset_id`, the recording is compared with the asset's baseline; the "
    "diagnosis is stored in the asset's history only when the request carries the API key (`stored` says whether).",
)
async def diagnose(
    request: Request,
    state: StateDep,
    models: ModelsDep,
    reader: ReaderQueryDep,
    writer: MayStoreDep,
    asset_id: Annotated[AssetId | None, Query(description="Binary/multipart only: asset identifier (compares with "
                                              "the asset's baseline; with the API key also stores the diagnosis "
                                              "in the asset's history).")] = None,
    plant: Annotated[str | None, Query(min_length=1, max_length=MAX_LABEL_LEN,
                                       description="Binary/multipart only: plant label.")] = None,
    sample_index: Annotated[int, Query(ge=0, le=10_000_000, description="HDF5 upload of a dataset file only: "
                                       "which sample to diagnose.")] = 0,
    model_version: Annotated[str | None, Query(min_length=1, max_length=128,
                                               description="Diagnose with this registered version instead of the "
                                               "active one.")] = None,
    output_units: OutputUnitsQuery = "um",
    slow_roll_sample_rate_hz: Annotated[float | None, Query(
        gt=0, le=1e6, allow_inf_nan=False, description="Multipart with `slow_roll_file` only: the slow-roll file's "
        "sample rate, Hz (default: `sample_rate_hz`).")] = None,
    slow_roll_keyphasor_times_s: Annotated[str | None, Query(
        max_length=200_000, description="Multipart with `slow_roll_file` only: the slow-roll file's keyphasor pulse "
        "times, s, comma-separated (or a keyphasor column/channel in that file).")] = None,
) -> dict:
    query = dict(asset_id=asset_id, plant=plant, sample_index=sample_index, **reader)
    query.update(slow_roll_sample_rate_hz=slow_roll_sample_rate_hz, slow_roll_keyphasor_times_s=slow_roll_keyphasor_times_s)
    verdict, _ = await diagnose_from_request(request, state, query, model_version, slow_roll_allowed=True,
                                             may_store=writer)
    return verdict_in_units(verdict, output_units)   # stored in µm; answered in the units asked for


async def diagnose_from_request(request: Request, state, query: dict[str, Any], version: str | None,
                                store: bool = True, slow_roll_allowed: bool = False,
                                may_store: bool = False) -> tuple[dict, str | None]:
    """Read the body, parse and diagnose it in a worker process (``service.pool``, which bounds the requests
    in flight per worker) or a thread; with ``store``, compare with the asset's baseline and, when
    ``may_store`` (the request carried the API key), store the result here
    (``service.baseline.record_verdict``). Returns the verdict and the request's asset id."""
    kind, body, filename, slow_roll = await _read_body(request, slow_roll=slow_roll_allowed)
    if state.pool is not None:
        _, verdict, asset_id, plant = await in_worker(state, "work", kind, body, filename, query, slow_roll, version)
    else:
        verdict, asset_id, plant = await anyio.to_thread.run_sync(_parse_and_diagnose, state, kind, body, filename,
                                                                  query, slow_roll, version,
                                                                  limiter=_diagnosis_limiter(state))
    if store:
        await run_in_threadpool(record_verdict, state, asset_id, plant, verdict, may_store)
    return verdict, asset_id


def _diagnosis_limiter(state) -> anyio.CapacityLimiter:
    """At most one diagnosis per CPU at a time: the work is CPU-bound, so more threads only thrash
    (requests beyond it wait on the event loop, not in a crowd of threads)."""
    limiter = getattr(state, "diagnosis_limiter", None)
    if limiter is None:
        limiter = state.diagnosis_limiter = anyio.CapacityLimiter(state.settings.effective_diagnosis_threads)
    return limiter


def _parse_and_diagnose(state, kind, body, filename, query, slow_roll,
                        model_version) -> tuple[dict, str | None, str | None]:
    recording, asset_id, plant = parse_body(kind, body, filename, query, slow_roll)
    return _diagnose_sync(state, recording, model_version), asset_id, plant


_BATCH_BODY = {"requestBody": {"required": True, "content": {
    "application/json": {"schema": {"$ref": "#/components/schemas/BatchRequest"}}}}}


@router.post(
    "/diagnose/batch", response_model=BatchResponse, responses=_ERRORS, dependencies=[DiagnoseKeyDep, JsonBodyDep],
    openapi_extra=_BATCH_BODY,
    summary="Diagnose many recordings (JSON)",
    description="Each record is diagnosed independently; a record the service cannot diagnose gets its own "
    "`status_code` and `error` while the others still get results. The number of records is capped by "
    "ROTORDIAG_MAX_BATCH_RECORDS.",
)
async def diagnose_batch(request: Request, state: StateDep, writer: MayStoreDep,
                         model_version: Annotated[str | None, Query(min_length=1, max_length=128)] = None,
                         output_units: OutputUnitsQuery = "um") -> dict:
    """The body (a ``BatchRequest``) is parsed in a diagnosis worker, not here; the records are then
    diagnosed one per worker call, in parallel across the workers."""
    body = await request.body()
    cap = state.settings.max_batch_records
    if state.pool is not None:
        records = (await in_worker(state, "batch_parse", body))[1]
        _check_batch_size(len(records), cap)
        results = await asyncio.gather(*(_batch_item(state, i, rec, model_version, writer)
                                         for i, rec in enumerate(records)))
        items = list(results)
    else:
        batch = await anyio.to_thread.run_sync(parse_batch, body, limiter=_diagnosis_limiter(state))
        _check_batch_size(len(batch.records), cap)
        items = await anyio.to_thread.run_sync(_batch_sync, state, batch.records, model_version, writer,
                                               limiter=_diagnosis_limiter(state))
    if output_units != "um":
        for it in items:
            if it.result is not None:
                it.result = DiagnoseResponse.model_validate(verdict_in_units(it.result.model_dump(), output_units))
    return {"count": len(items), "n_ok": sum(it.status_code == 200 for it in items), "items": items}


def _check_batch_size(n: int, cap: int) -> None:
    if n > cap:
        raise InputError(f"records: {n} records sent; this server accepts at most {cap} per batch "
                         "(ROTORDIAG_MAX_BATCH_RECORDS); split the batch")


async def _batch_item(state, i: int, record: dict[str, Any], version: str | None, may_store: bool) -> BatchItem:
    try:
        _, verdict, asset_id, plant = await in_worker(state, "record", record, version)
    except InputError as exc:
        return BatchItem(index=i, status_code=STATUS_OF_KIND[exc.kind], error=str(exc))
    except RequestInvalid as exc:
        return BatchItem(index=i, status_code=422, error=json.dumps(exc.errors))
    except HTTPException as exc:
        if exc.status_code >= 500:
            raise
        return BatchItem(index=i, status_code=exc.status_code, error=str(exc.detail))
    await run_in_threadpool(record_verdict, state, asset_id, plant, verdict, may_store)
    return BatchItem(index=i, status_code=200, result=verdict)


def _batch_sync(state, records, model_version: str | None, may_store: bool) -> list[BatchItem]:
    items: list[BatchItem] = []
    for i, rec in enumerate(records):
        try:
            recording = checked(recording_from_model, rec)
            verdict = _diagnose_sync(state, recording, model_version)
            record_verdict(state, rec.asset_id, rec.plant, verdict, may_store)
            items.append(BatchItem(index=i, status_code=200, result=verdict))
        except InputError as exc:
            items.append(BatchItem(index=i, status_code=STATUS_OF_KIND[exc.kind], error=str(exc)))
        except HTTPException as exc:
            if exc.status_code >= 500:
                raise
            items.append(BatchItem(index=i, status_code=exc.status_code, error=str(exc.detail)))
    return items
