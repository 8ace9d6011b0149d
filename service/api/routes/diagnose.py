"""POST /diagnose and POST /diagnose/batch."""
from __future__ import annotations

import asyncio
import datetime as dt
import json
import logging
from typing import Annotated, Any, Literal

import anyio
import anyio.to_thread
from fastapi import APIRouter, HTTPException, Query, Request
from fastapi.concurrency import run_in_threadpool
from sqlalchemy.exc import DatabaseError as SQLAlchemyDatabaseError

from rotordiag.core.input_bounds import SAMPLE_RATE_RANGE_HZ
from rotordiag.core.timefmt import readable_time
from rotordiag.models.output_units import verdict_in_units

from ...baseline import parse_tags, record_verdict
from ...inference import ModelUnavailable
from ...parsing import (
    MAX_TAKE_FILES,
    batch_record,
    checked,
    parse_batch,
    parse_request,
    plant_declared_by,
    recording_from_model,
)
from ...pool import DiagnoseBody, DiagnoseRecord, ParseBatch
from ...schemas import (
    MAX_BATCH_VALUES,
    MAX_LABEL_LEN,
    PLANT_MODEL_DESCRIPTION,
    PLANT_MODEL_MAX_LEN,
    AssetId,
    BatchItem,
    BatchResponse,
    DiagnoseResponse,
)
from ..deps import (
    DiagnoseKeyDep,
    JsonBodyDep,
    MayStoreDep,
    ModelsDep,
    StateDep,
)
from ..errors import STATUS_OF_KIND, InputError, RequestInvalid, error_responses
from ..recordings import ReaderQueryDep, asset_probes_query, diagnosis_limiter, in_worker, read_body, read_json_bounded
from ..routing import FiniteJSONRoute

router = APIRouter(tags=["diagnose"], route_class=FiniteJSONRoute)
log = logging.getLogger("rotordiag.service")


_ERRORS = error_responses({404: "`model_version` is not registered.",
                           413: "Body over the size limit (ROTORDIAG_MAX_BODY_BYTES).",
                           422: "The recording cannot be diagnosed; `detail` says what to fix.",
                           503: "No model is available on the server."}, key="diagnose", body="recording")

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

def _diagnose_sync(state, recording, version: str | None, plant_model: str | None = None,
                   plant_shaftline: dict | None = None, declared_by: str | None = None) -> dict:
    try:
        verdict = state.models.diagnose(recording, version, plant_model, plant_shaftline, declared_by)
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
    plant_model: Annotated[str | None, Query(min_length=1, max_length=PLANT_MODEL_MAX_LEN, description=(
        PLANT_MODEL_DESCRIPTION + " Default: a binary or multipart upload's asset's plant model. A JSON body may "
        "give it as its own field `plant_model` instead; given in both, they must agree (422 otherwise)."))] = None,
    recorded_at: Annotated[dt.datetime | None, Query(description="When the recording was made (ISO 8601; UTC when no "
                                                     "offset): orders the asset's trend, so a backfilled recording "
                                                     "lands in its place (and raises no alarm).")] = None,
    tags: Annotated[str | None, Query(max_length=4000, description="Operating state at the recording, stored with "
                                      "it: `load_mw=350;field_current_a=1210;stator_temp_c=71`.")] = None,
    note: Annotated[str | None, Query(min_length=1, max_length=2000, description="An event note stored with the "
                                      "recording, shown on the trend, e.g. `aligned on 2026-03-02`.")] = None,
    slow_roll_sample_rate_hz: Annotated[float | None, Query(
        ge=SAMPLE_RATE_RANGE_HZ[0], le=SAMPLE_RATE_RANGE_HZ[1], allow_inf_nan=False, description="Multipart with `slow_roll_file` only: the slow-roll file's "
        "sample rate, Hz (default: `sample_rate_hz`).")] = None,
    slow_roll_keyphasor_times_s: Annotated[str | None, Query(
        max_length=200_000, description="Multipart with `slow_roll_file` only: the slow-roll file's keyphasor pulse "
        "times, s, comma-separated (or a keyphasor column/channel in that file).")] = None,
) -> dict:
    query = dict(asset_id=asset_id, plant=plant, sample_index=sample_index, **reader)
    if plant_model is not None:                 # else the asset's, when it has one (service.parsing.with_probe_config)
        query["plant_model"] = plant_model
    query.update(slow_roll_sample_rate_hz=slow_roll_sample_rate_hz, slow_roll_keyphasor_times_s=slow_roll_keyphasor_times_s)
    meta = recording_meta(recorded_at, tags, note)
    verdict, _ = await diagnose_from_request(request, state, query, model_version, slow_roll_allowed=True,
                                             may_store=writer, meta=meta)
    return verdict_in_units(verdict, output_units)   # stored in µm; answered in the units asked for


async def diagnose_from_request(request: Request, state, query: dict[str, Any], version: str | None,
                                store: bool = True, slow_roll_allowed: bool = False,
                                may_store: bool = False, meta: dict[str, Any] | None = None) -> tuple[dict, str | None]:
    """Read the body, parse and diagnose it in a worker process (``service.pool``, which bounds the requests
    in flight per worker) or a thread; with ``store``, compare with the asset's baseline and, when
    ``may_store`` (the request carried the API key), store the result here
    (``service.baseline.record_verdict``). Returns the verdict and the request's asset id."""
    kind, body, filename, slow_roll = await read_body(request, slow_roll=slow_roll_allowed)
    probes = None
    if kind != "json" and query.get("asset_id"):    # a JSON body states its channels itself
        query, probes = await run_in_threadpool(asset_probes_query, state, {**query, "model_version": version})
        version = query.pop("model_version", None)  # the upload's, else the asset's, else the active model
    if state.pool is not None:
        _, verdict, asset_id, plant = await in_worker(state, DiagnoseBody(kind, body, filename, query, slow_roll, version))
    else:
        verdict, asset_id, plant = await anyio.to_thread.run_sync(_parse_and_diagnose, state, kind, body, filename,
                                                                  query, slow_roll, version,
                                                                  limiter=diagnosis_limiter(state))
    if probes is not None:
        verdict["asset_probes"] = probes
        used = ", ".join(f"{k}={v}" for k, v in probes["used"].items())
        verdict.setdefault("input_notes", []).insert(0, f"read with asset {probes['asset_id']!r}'s probe "
                                                     f"configuration: {used or 'nothing of it'}"
                                                     + (f" (given with this upload instead: "
                                                        f"{', '.join(probes['overridden_by_upload'])})"
                                                        if probes["overridden_by_upload"] else ""))
    in_file = verdict.pop("recorded_at_in_file", None)
    if in_file and meta is not None and meta.get("recorded_at") is None:
        try:
            meta = {**meta, "recorded_at": recording_meta(dt.datetime.fromisoformat(in_file), None, None)["recorded_at"]}
            verdict.setdefault("input_notes", []).append(f"recording time {readable_time(in_file)} from the file "
                                                         "(give recorded_at to override it)")
        except (InputError, ValueError) as exc:
            verdict.setdefault("input_notes", []).append(f"the file's recording time {in_file!r} is not used: {exc}")
    if store:
        if asset_id is None:            # no database to touch: no hand-over to a thread
            record_verdict(state, None, plant, verdict, may_store, meta)
        else:
            await run_in_threadpool(record_verdict, state, asset_id, plant, verdict, may_store, meta)
    return verdict, asset_id


def recording_meta(recorded_at: dt.datetime | None, tags: str | None, note: str | None) -> dict[str, Any]:
    """The recording's time, operating-state tags and note as ``store_diagnosis`` takes them; a time in the
    future (beyond a day of clock skew) or before 1970 is refused."""
    if recorded_at is not None:
        if recorded_at.tzinfo is None:
            recorded_at = recorded_at.replace(tzinfo=dt.UTC)
        now = dt.datetime.now(dt.UTC)
        if not (dt.datetime(1970, 1, 1, tzinfo=dt.UTC) <= recorded_at <= now + dt.timedelta(days=1)):
            raise InputError(f"recorded_at: {recorded_at.isoformat()} is in the future or before 1970; give when "
                             "the recording was made")
    return {"recorded_at": recorded_at, "tags": parse_tags(tags), "note": note}


def _parse_and_diagnose(state, kind, body, filename, query, slow_roll,
                        model_version) -> tuple[dict, str | None, str | None]:
    recording, asset_id, plant, notes, plant_model = parse_request(kind, body, filename, query, slow_roll)
    return ({**_diagnose_sync(state, recording, model_version, plant_model, query.get("plant_shaftline"),
                              plant_declared_by(query, plant_model)),
             "input_notes": notes,
             "recorded_at_in_file": recording.recorded_at}, asset_id, plant)


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
    body = await read_json_bounded(request, MAX_BATCH_VALUES)
    cap = state.settings.max_batch_records
    if state.pool is not None:
        records = (await in_worker(state, ParseBatch(body)))[1]
        _check_batch_size(len(records), cap)
        results = await asyncio.gather(*(_batch_item(state, i, rec, model_version, writer)
                                         for i, rec in enumerate(records)))
        items = list(results)
    else:
        records = await anyio.to_thread.run_sync(parse_batch, body, limiter=diagnosis_limiter(state))
        _check_batch_size(len(records), cap)
        items = await anyio.to_thread.run_sync(_batch_sync, state, records, model_version, writer,
                                               limiter=diagnosis_limiter(state))
    answered = [it if isinstance(it, BatchItem) else BatchItem(index=it[0], status_code=200,
                                                               result=verdict_in_units(it[1], output_units))
                for it in items]
    return {"count": len(answered), "n_ok": sum(it.status_code == 200 for it in answered), "items": answered}


def _check_batch_size(n: int, cap: int) -> None:
    if n > cap:
        raise InputError(f"records: {n} records sent; this server accepts at most {cap} per batch "
                         "(ROTORDIAG_MAX_BATCH_RECORDS); split the batch")


async def _batch_item(state, i: int, record: dict[str, Any], version: str | None,
                      may_store: bool) -> BatchItem | tuple[int, dict]:
    """One record's answer: a ``BatchItem`` with its error, or ``(index, verdict)`` in µm (converted to the
    request's units from its typed values before validation)."""
    try:
        _, verdict, asset_id, plant = await in_worker(state, DiagnoseRecord(record, version))
    except InputError as exc:
        return BatchItem(index=i, status_code=STATUS_OF_KIND[exc.kind], error=str(exc))
    except RequestInvalid as exc:
        return BatchItem(index=i, status_code=422, error=json.dumps(exc.errors))
    except HTTPException as exc:             # no model, or the worker stopped on this record: this record's answer
        return BatchItem(index=i, status_code=exc.status_code, error=str(exc.detail))
    except RuntimeError:                     # a bug on this record (logged by the pool): the others still answered
        return BatchItem(index=i, status_code=500, error=_RECORD_FAILED)
    try:
        meta = record_meta(record)
    except InputError as exc:
        return BatchItem(index=i, status_code=STATUS_OF_KIND[exc.kind], error=str(exc))
    await run_in_threadpool(record_verdict, state, asset_id, plant, verdict, may_store, meta)
    return i, verdict


def record_meta(record: dict[str, Any]) -> dict[str, Any]:
    """A batch record's time, tags and note (validated by the worker as a ``BatchRecord``) as ``recording_meta``
    gives them; ``InputError`` for a time that is not ISO 8601."""
    when = record.get("recorded_at")
    try:
        at = dt.datetime.fromisoformat(when.replace("Z", "+00:00")) if isinstance(when, str) else None
    except ValueError:
        raise InputError(f"recorded_at: {when!r} is not an ISO 8601 time (e.g. 2025-01-14T10:00:00Z)") from None
    return recording_meta(at, record.get("tags"), record.get("note"))


#: a batch record's error when the server failed on it (the cause is in the server log)
_RECORD_FAILED = "the server failed on this record (an internal error, logged); the other records were answered"


def _batch_sync(state, records: list[dict[str, Any]], model_version: str | None,
                may_store: bool) -> list[BatchItem | tuple[int, dict]]:
    items: list[BatchItem | tuple[int, dict]] = []
    for i, raw in enumerate(records):
        try:
            rec = batch_record(raw)
            recording = checked(recording_from_model, rec)
            meta = record_meta(raw)
            verdict = _diagnose_sync(state, recording, model_version, rec.plant_model,
                                     declared_by="request" if rec.plant_model else None)
            record_verdict(state, rec.asset_id, rec.plant, verdict, may_store, meta)
            items.append((i, verdict))
        except InputError as exc:
            items.append(BatchItem(index=i, status_code=STATUS_OF_KIND[exc.kind], error=str(exc)))
        except RequestInvalid as exc:
            items.append(BatchItem(index=i, status_code=422, error=json.dumps(exc.errors)))
        except HTTPException as exc:
            items.append(BatchItem(index=i, status_code=exc.status_code, error=str(exc.detail)))
        except SQLAlchemyDatabaseError:      # the store failed: the whole request is a 503 that says so
            raise
        except Exception:  # noqa: BLE001 - a bug on one record must not lose the others' answers
            log.exception("batch record %d failed", i)
            items.append(BatchItem(index=i, status_code=500, error=_RECORD_FAILED))
    return items
