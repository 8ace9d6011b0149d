"""POST /diagnose and POST /diagnose/batch."""
from __future__ import annotations

from typing import Annotated, Any, Literal

import anyio
import anyio.to_thread
from fastapi import APIRouter, Depends, HTTPException, Query, Request
from fastapi.concurrency import run_in_threadpool

from ...inference import ModelUnavailable
from ...parsing import checked, parse_body, recording_from_model
from ...pool import WorkerCrashed
from ...schemas import MAX_LABEL_LEN, BatchItem, BatchRequest, BatchResponse, DiagnoseResponse, ErrorOut
from ...store import store_diagnosis
from ..deps import DiagnoseKeyDep, JsonBodyDep, ModelsDep, StateDep
from ..errors import InputError

router = APIRouter(tags=["diagnose"])


def reader_query(
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
        "Raw keyphasor pulse channel: CSV column name or row index (default: a CSV column named kp/keyphasor)."))] = None,
    keyphasor_edge: Annotated[Literal["falling", "rising"], Query(description=(
        "Edge of the keyphasor pulse: falling (a notch) or rising (a projection, TTL)."))] = "falling",
    keyphasor_threshold_v: Annotated[float | None, Query(allow_inf_nan=False, description=(
        "Keyphasor threshold in the channel's units (default: halfway between its 1st and 99th percentile)."))] = None,
) -> dict[str, Any]:
    """Query parameters of the recording reader beyond the basic metadata (``features.reader.ReadOptions``)."""
    return dict(sensitivity_v_per_mm=sensitivity_v_per_mm, gap_voltage_v=gap_voltage_v, rotation=rotation,
                viewed_from=viewed_from, keyphasor_channel=keyphasor_channel, keyphasor_edge=keyphasor_edge,
                keyphasor_threshold_v=keyphasor_threshold_v)


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
        "CSV / NPY / HDF5 file in the part `file` (metadata in the query parameters; HDF5 may carry "
        "`sample_rate_hz`, `units` attributes and a `channels/bearing`, `channels/angle_deg` table).",
        "content": {
            "application/json": {"schema": {"$ref": "#/components/schemas/DiagnoseRequest"}},
            "application/octet-stream": {"schema": {"type": "string", "format": "binary",
                                                    "description": "numpy.save output, (n_channels, n_points)"}},
            "multipart/form-data": {"schema": {
                "type": "object", "required": ["file"],
                "properties": {"file": {"type": "string", "format": "binary",
                                        "description": "CSV (one probe per column), .npy or .h5/.hdf5 file"}}}},
        },
    }
}

JSON_TYPES = ("application/json",)
NPY_TYPES = ("application/octet-stream", "application/x-npy", "application/npy")


def _media_type(request: Request) -> str:
    return request.headers.get("content-type", "").split(";")[0].strip().lower()


async def _read_body(request: Request) -> tuple[str, bytes, str]:
    """``(kind, bytes, file name)`` of the body: kind is ``json``, ``npy`` or ``upload``; 415 for anything else.

    Only the I/O happens here, on the event loop; parsing runs off the loop (``service.parsing.parse_body``).
    """
    media = _media_type(request)
    if media in JSON_TYPES:
        return "json", await request.body(), ""
    if media in NPY_TYPES:
        return "npy", await request.body(), ""
    if media == "multipart/form-data":
        form = await request.form(max_files=1, max_fields=8)
        try:
            upload = form.get("file")
            if upload is None or isinstance(upload, str):
                raise InputError("multipart upload: put the waveform file in a part named 'file' (with a filename)")
            return "upload", await upload.read(), upload.filename or ""
        finally:
            await form.close()
    raise InputError(
        f"unsupported Content-Type {media or '(none)'!r}: send application/json (DiagnoseRequest), "
        "application/octet-stream (an NPY array) or multipart/form-data (a CSV/NPY/HDF5 file in part 'file')", 415)


async def _recording_from_request(request: Request, query: dict[str, Any]) -> tuple[Any, str | None, str | None]:
    """Recording, asset_id, plant from any accepted body form (read on the loop, parsed in the thread pool).

    Also used by the web page's ``/ui/plot-data`` (service/web/routes.py).
    """
    kind, body, filename = await _read_body(request)
    return await run_in_threadpool(parse_body, kind, body, filename, query)


def _diagnose_sync(state, recording, asset_id: str | None, plant: str | None, version: str | None) -> dict:
    try:
        verdict = state.models.diagnose(recording, version)
    except ModelUnavailable as exc:
        if version is not None:
            raise InputError(str(exc), 404) from None
        raise HTTPException(503, str(exc)) from None
    except ValueError as exc:  # the features/models packages' messages for bad recordings
        raise InputError(str(exc)) from None
    if asset_id is not None:
        store_diagnosis(state, asset_id, plant, verdict)
    return verdict


@router.post(
    "/diagnose", response_model=DiagnoseResponse, responses=_ERRORS, openapi_extra=_BINARY_BODY,
    dependencies=[DiagnoseKeyDep],
    summary="Diagnose one recording",
    description="Returns the severity class, probabilities, Δ estimate with interval, offset in µm (when "
    "`clearance_um` is given), motion type, per-bearing key features, top contributing features, OOD flag, "
    "warnings and the model version. With an `asset_id`, the diagnosis is stored for the asset's history.",
)
async def diagnose(
    request: Request,
    state: StateDep,
    models: ModelsDep,
    reader: ReaderQueryDep,
    sample_rate_hz: Annotated[float | None, Query(gt=0, le=1e6, allow_inf_nan=False,
                                                  description="Binary/multipart only: sample rate, Hz.")] = None,
    speed_rpm: Annotated[float | None, Query(gt=0, le=100_000, allow_inf_nan=False,
                                             description="Binary/multipart only: running speed, r/min.")] = None,
    clearance_um: Annotated[float | None, Query(gt=0, le=100_000, allow_inf_nan=False,
                                                description="Binary/multipart only: radial clearance, µm.")] = None,
    units: Annotated[str | None, Query(min_length=1, max_length=16,
                                       description="Binary/multipart only: units of the array (`um`, `mm`, `m`, `mil`, "
                                       "or `V` with `sensitivity_v_per_mm`); "
                                       "default `um` (or the HDF5 file's `units` attribute).")] = None,
    bearings: Annotated[str | None, Query(max_length=64, pattern=r"^[0-9, ]*$",
                                          description="Binary/multipart only: bearing (1-4) of each row, "
                                          "comma-separated; default 1,1,2,2,3,3,4,4 for 8 rows.")] = None,
    angles_deg: Annotated[str | None, Query(max_length=256,
                                            description="Binary/multipart only: probe angle of each row in degrees "
                                            "from horizontal x towards vertical-up y, comma-separated; "
                                            "default 45,135 repeated.")] = None,
    keyphasor_times_s: Annotated[str | None, Query(max_length=200_000,
                                                   description="Binary/multipart only: keyphasor pulse times, s, "
                                                   "comma-separated.")] = None,
    asset_id: Annotated[str | None, Query(min_length=1, max_length=MAX_LABEL_LEN, pattern=r"^[A-Za-z0-9._:/-]+$",
                                          description="Binary/multipart only: asset identifier (stores the "
                                          "diagnosis in the asset's history).")] = None,
    plant: Annotated[str | None, Query(min_length=1, max_length=MAX_LABEL_LEN,
                                       description="Binary/multipart only: plant label.")] = None,
    sample_index: Annotated[int, Query(ge=0, le=10_000_000, description="HDF5 upload of a dataset file only: "
                                       "which sample to diagnose.")] = 0,
    model_version: Annotated[str | None, Query(min_length=1, max_length=128,
                                               description="Diagnose with this registered version instead of the "
                                               "active one.")] = None,
) -> dict:
    query = dict(sample_rate_hz=sample_rate_hz, speed_rpm=speed_rpm, clearance_um=clearance_um, asset_id=asset_id,
                 plant=plant, units=units, bearings=bearings, angles_deg=angles_deg,
                 keyphasor_times_s=keyphasor_times_s, sample_index=sample_index, **reader)
    kind, body, filename = await _read_body(request)
    if state.pool is not None:
        return await _diagnose_in_pool(state, kind, body, filename, query, model_version)
    return await anyio.to_thread.run_sync(_parse_and_diagnose, state, kind, body, filename, query, model_version,
                                          limiter=_diagnosis_limiter(state))


async def _diagnose_in_pool(state, kind: str, body: bytes, filename: str, query: dict[str, Any],
                            version: str | None) -> dict:
    """Parse and diagnose in a worker process (``service.pool``, which bounds the requests in flight
    per worker); store the result here."""
    try:
        result = await state.pool.run(kind, body, filename, query, version)
    except WorkerCrashed as exc:
        raise HTTPException(503, str(exc)) from None
    tag = result[0]
    if tag == "input":
        raise InputError(result[2], result[1])
    if tag == "http":
        raise HTTPException(result[1], result[2])
    if tag == "unavailable":
        if version is not None:
            raise InputError(result[1], 404)
        raise HTTPException(503, result[1])
    _, verdict, asset_id, plant = result
    if asset_id is not None:
        await run_in_threadpool(store_diagnosis, state, asset_id, plant, verdict)
    return verdict


def _diagnosis_limiter(state) -> anyio.CapacityLimiter:
    """At most one diagnosis per CPU at a time: the work is CPU-bound, so more threads only thrash
    (requests beyond it wait on the event loop, not in a crowd of threads)."""
    limiter = getattr(state, "diagnosis_limiter", None)
    if limiter is None:
        limiter = state.diagnosis_limiter = anyio.CapacityLimiter(state.settings.effective_diagnosis_threads)
    return limiter


def _parse_and_diagnose(state, kind, body, filename, query, model_version) -> dict:
    recording, asset_id, plant = parse_body(kind, body, filename, query)
    return _diagnose_sync(state, recording, asset_id, plant, model_version)


@router.post(
    "/diagnose/batch", response_model=BatchResponse, responses=_ERRORS, dependencies=[DiagnoseKeyDep, JsonBodyDep],
    summary="Diagnose many recordings (JSON)",
    description="Each record is diagnosed independently; a record the service cannot diagnose gets its own "
    "`status_code` and `error` while the others still get results. The number of records is capped by "
    "ROTORDIAG_MAX_BATCH_RECORDS.",
)
def diagnose_batch(body: BatchRequest, state: StateDep,
                   model_version: Annotated[str | None, Query(min_length=1, max_length=128)] = None) -> dict:
    cap = state.settings.max_batch_records
    if len(body.records) > cap:
        raise InputError(f"records: {len(body.records)} records sent; this server accepts at most {cap} per batch "
                         "(ROTORDIAG_MAX_BATCH_RECORDS); split the batch")
    items: list[BatchItem] = []
    for i, rec in enumerate(body.records):
        try:
            recording = checked(recording_from_model, rec)
            verdict = _diagnose_sync(state, recording, rec.asset_id, rec.plant, model_version)
            items.append(BatchItem(index=i, status_code=200, result=verdict))
        except InputError as exc:
            items.append(BatchItem(index=i, status_code=exc.status_code, error=str(exc)))
        except HTTPException as exc:
            if exc.status_code >= 500:
                raise
            items.append(BatchItem(index=i, status_code=exc.status_code, error=str(exc.detail)))
    return {"count": len(items), "n_ok": sum(it.status_code == 200 for it in items), "items": items}
