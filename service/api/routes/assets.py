"""GET /assets/{asset_id}/history and /report (PDF or HTML to hand on); the asset baseline (GET/POST/DELETE /assets/{asset_id}/baseline),
alarm thresholds (GET/PUT /assets/{asset_id}/thresholds) and probe configuration (GET/PUT/DELETE
/assets/{asset_id}/probes)."""
from __future__ import annotations

import datetime as dt
from typing import Annotated, Any, Literal

import anyio
from fastapi import APIRouter, Path, Query, Request, Response
from fastapi.concurrency import run_in_threadpool
from pydantic import BeforeValidator

from ...baseline import (
    AUTO_N,
    add_recording,
    alarm_events,
    baseline_dict,
    from_diagnosis,
    propose,
    record_verdict,
    remove_recording,
    rule_for,
    set_auto,
    thresholds_origin,
)
from ...schemas import (
    MAX_LABEL_LEN,
    AssetBaselineOut,
    AssetHistory,
    AssetId,
    AssetPoint,
    AssetSummary,
    BaselineOut,
    ErrorOut,
    HierarchyIn,
    ProbeConfigIn,
    ProbeConfigOut,
    ThresholdsIn,
)
from ...store import (
    asset_history,
    baseline_recordings,
    delete_baseline,
    get_baseline,
    get_hierarchy,
    get_probe_config,
    get_thresholds,
    list_assets,
    put_hierarchy,
    put_probe_config,
    put_thresholds,
)
from ..deps import (
    ApiKeyDep,
    JsonBodyDep,
    ModelsDep,
    SessionDep,
    StateDep,
)
from ..errors import InputError, error_responses
from ..recordings import ReaderQueryDep, diagnosis_limiter, in_worker

router = APIRouter(tags=["assets"])

AssetPath = Annotated[AssetId, Path(min_length=1, max_length=MAX_LABEL_LEN, pattern=r"^[A-Za-z0-9._:-]+$",
                                    description="The `asset_id` sent with /diagnose.")]


def _iso_time(value: object) -> object:
    """Refuse a bare number for ``since`` (pydantic would read ``0.5`` as seconds since 1970)."""
    if isinstance(value, str):
        try:
            float(value)
        except ValueError:
            return value
        raise ValueError("since: give a date and time in ISO 8601, e.g. 2024-05-01T12:00:00Z (not a number)")
    return value


@router.get("/assets/{asset_id}/history", response_model=AssetHistory,
            responses={404: {"model": ErrorOut, "description": "No diagnosis stored for this asset."}},
            summary="Trend of an asset's diagnoses")
def history(
    asset_id: AssetPath,
    session: SessionDep,
    limit: Annotated[int, Query(ge=1, le=10_000, description="Most recent points to return.")] = 500,
    since: Annotated[dt.datetime | None, BeforeValidator(_iso_time), Query(description="Only points at or after this time (ISO 8601; "
                                               "UTC when no offset is given).")] = None,
) -> AssetHistory:
    rows = asset_history(session, asset_id, limit, since)
    if not rows and since is None:
        raise InputError(f"no diagnosis stored for asset {asset_id!r}; POST /diagnose with \"asset_id\": "
                         f"\"{asset_id}\" to start its history", "not_found")
    points = [AssetPoint(id=r.id, alarm=r.alarm, change=r.change, time=r.created_at, severity=r.severity, misalignment=r.misalignment,
                         misalignment_low=r.misalignment_low, misalignment_high=r.misalignment_high,
                         speed_rpm=r.speed_rpm, ood=r.ood, model_version=r.model_version, plant=r.plant,
                         key_features=r.key_features, amplitudes_um_pp=_amplitudes(r.verdict),
                         recorded_at=r.recorded_at, trend_time=r.recorded_at or r.created_at, tags=r.tags,
                         note=r.note) for r in rows]
    return AssetHistory(asset_id=asset_id, count=len(points), points=points, alarms=alarm_events(rows),
                        **get_hierarchy(session, asset_id))



#: the HTML report is one self-contained page: inline style, figures as data: URIs, no script
_REPORT_HTML_HEADERS = {
    "Content-Security-Policy": "default-src 'none'; img-src data:; style-src 'unsafe-inline'; base-uri 'none'; "
                               "form-action 'none'; frame-ancestors 'none'",
    "X-Content-Type-Options": "nosniff", "Cache-Control": "no-store",
}


@router.get("/assets/{asset_id}/report", response_class=Response,
            responses={200: {"content": {"application/pdf": {}, "text/html": {}},
                             "description": "The report: PDF, or with `?format=html` one self-contained HTML page."},
                       404: {"model": ErrorOut, "description": "No diagnosis stored for this asset."},
                       422: {"model": ErrorOut, "description": "The report took longer than the time limit."}},
            summary="A report of an asset to hand on (PDF or HTML)",
            description="The asset, its stored recordings (the trend and its plot), the latest verdict with its "
            "status, severity, Δ and interval, probabilities, reasons, warnings and model-independent evidence — "
            "the content of `rotordiag report --asset`, with the asset's latest start-up compared with its baseline "
            "start-up (POST /assets/{id}/startup), lengths in `output_units`. The service stores verdicts, not "
            "waveforms, so the start-up plots are not in it (the report says so). Rendered in a diagnosis worker (or a thread) within "
            "ROTORDIAG_DIAGNOSIS_TIMEOUT_S.")
async def asset_report(
    asset_id: AssetPath, state: StateDep,
    format: Annotated[Literal["pdf", "html"], Query(description="pdf (default) or html.")] = "pdf",
    output_units: Annotated[Literal["um", "mil"], Query(description="Lengths of the report: `um` (default) or "
                                                        "`mil`, as the diagnosis answers (`?output_units=`).")] = "um",
) -> Response:
    from ...pool import AssetReport
    from ...report import asset_report_inputs, render_asset_report

    def read() -> dict | None:
        with state.sessions() as s:
            return asset_report_inputs(s, asset_id, units=output_units)

    inputs = await run_in_threadpool(read)
    if inputs is None:
        raise InputError(f"no diagnosis stored for asset {asset_id!r}; POST /diagnose with \"asset_id\": "
                         f"\"{asset_id}\" to start its history", "not_found")
    if state.pool is not None:
        data = (await in_worker(state, AssetReport(inputs, format)))[1]
    else:
        limit_s = float(state.settings.diagnosis_timeout_s)
        try:
            with anyio.fail_after(limit_s):
                data = await anyio.to_thread.run_sync(render_asset_report, inputs, format,
                                                      limiter=diagnosis_limiter(state), abandon_on_cancel=True)
        except TimeoutError:
            raise InputError(f"the report took longer than the limit of {limit_s:g} s to render and was abandoned; "
                             "try again when the server is less busy (or raise ROTORDIAG_DIAGNOSIS_TIMEOUT_S)") from None
    if format == "html":
        return Response(data, media_type="text/html; charset=utf-8", headers=_REPORT_HTML_HEADERS)
    return Response(data, media_type="application/pdf",
                    headers={"Content-Disposition": f'inline; filename="rotordiag-report-{asset_id}.pdf"',
                             "X-Content-Type-Options": "nosniff", "Cache-Control": "no-store"})


def _amplitudes(verdict: dict | None) -> dict[str, float | None]:
    """1X/2X orbit major axes (µm pk-pk) of each bearing, from a stored verdict's per-bearing features."""
    out: dict[str, float | None] = {}
    for b in (verdict or {}).get("bearings") or []:
        feats = b.get("features") or {}
        for name in (f"b{b.get('bearing')}_1x_major_um_pp", f"b{b.get('bearing')}_2x_major_um_pp"):
            if name in feats:
                out[name] = feats[name]
    return out


_BASELINE_ERRORS = error_responses({
    404: "No such diagnosis of this asset / no baseline to delete.",
    409: "No automatic baseline possible (too few recordings, or not at one operating condition), or the diagnosis "
         "keeps no signature.",
    413: "Body over the size limit.",
    422: "The recording cannot be diagnosed; `detail` says what to fix."}, key="always", body="recording")


@router.get("/assets/{asset_id}/baseline", response_model=AssetBaselineOut, summary="An asset's baseline")
def get_asset_baseline(asset_id: AssetPath, session: SessionDep) -> AssetBaselineOut:
    """The baseline (with its signature), or, when none is set, the automatic proposal (the first
    recordings at one operating condition) or why there is none; and the alarm thresholds in force."""
    row = get_baseline(session, asset_id)
    proposal = None
    if row is None:
        try:
            p = propose(session, asset_id)
            proposal = {"diagnosis_ids": p["diagnosis_ids"], "speed_rpm": p["speed_rpm"], "n": AUTO_N,
                        "how": f"POST /assets/{asset_id}/baseline?auto=true"}
        except InputError as exc:
            proposal = {"reason": str(exc)}
    base = baseline_dict(row, recordings=baseline_recordings(session, asset_id)) if row is not None else None
    return AssetBaselineOut(asset_id=asset_id,
                            baseline=BaselineOut(**base) if base is not None else None,
                            proposal=proposal, thresholds=rule_for(session, asset_id, row).thresholds,
                            edited_thresholds=get_thresholds(session, asset_id),
                            thresholds_origin=thresholds_origin(session, asset_id, row))


@router.post(
    "/assets/{asset_id}/baseline", response_model=BaselineOut, responses=_BASELINE_ERRORS, dependencies=[ApiKeyDep],
    summary="Set (or replace) an asset's baseline",
    description="Three ways, e.g. right after an alignment job: `?diagnosis_id=N` (a stored diagnosis of the asset, "
    "see GET /assets/{id}/history), `?auto=true` (the average of its first `n` stored recordings, refused unless "
    "they lie within ±5 % of their median speed), or a recording in the body — the same forms and query "
    "parameters as POST /diagnose; it is diagnosed, stored in the asset's history and made the baseline. The "
    "API key is checked before the body is read.",
    openapi_extra={"requestBody": {"required": False, "content": {
        "application/json": {"schema": {"$ref": "#/components/schemas/DiagnoseRequest"}},
        "application/octet-stream": {"schema": {"type": "string", "format": "binary"}},
        "multipart/form-data": {"schema": {"type": "object", "properties": {
            "file": {"type": "string", "format": "binary"}}}}}}},
)
async def set_asset_baseline(
    request: Request, asset_id: AssetPath, state: StateDep, reader: ReaderQueryDep,
    diagnosis_id: Annotated[int | None, Query(ge=1, le=2**63 - 1, description="Make this stored diagnosis the baseline.")] = None,
    auto: Annotated[bool, Query(description="Make the automatic proposal the baseline.")] = False,
    n: Annotated[int, Query(ge=1, le=50, description="With `auto`: recordings to average.")] = AUTO_N,
) -> dict:
    if diagnosis_id is not None and auto:
        raise InputError("give either diagnosis_id or auto=true, not both")
    if diagnosis_id is not None:
        return await run_in_threadpool(from_diagnosis, state, asset_id, diagnosis_id)
    if auto:
        return await run_in_threadpool(set_auto, state, asset_id, n)
    did = await _recorded_from_body(request, state, asset_id, reader, "?diagnosis_id= or ?auto=true")
    return await run_in_threadpool(from_diagnosis, state, asset_id, did, "recording")


async def _recorded_from_body(request: Request, state: Any, asset_id: str, reader: dict, otherwise: str) -> int:
    """Diagnose the recording in the body (as POST /diagnose does) and store it as the asset's diagnosis: its id."""
    if not request.headers.get("content-type"):
        raise InputError(f"send a recording in the body (as for POST /diagnose), or use {otherwise}")
    from .diagnose import diagnose_from_request

    query = dict(asset_id=asset_id, plant=None, sample_index=0, **reader)
    verdict, body_asset = await diagnose_from_request(request, state, query, None, store=False)
    if body_asset is not None and body_asset != asset_id:
        raise InputError(f"the body's asset_id {body_asset!r} is not the asset of the path ({asset_id!r})")
    verdict.pop("baseline", None)
    did = await run_in_threadpool(record_verdict, state, asset_id, None, verdict)
    assert did is not None
    return did


_RECORDING_BODY = {"requestBody": {"required": False, "content": {
    "application/json": {"schema": {"$ref": "#/components/schemas/DiagnoseRequest"}},
    "application/octet-stream": {"schema": {"type": "string", "format": "binary"}},
    "multipart/form-data": {"schema": {"type": "object", "properties": {"file": {"type": "string", "format": "binary"}}}}}}}


@router.post(
    "/assets/{asset_id}/baseline/recordings", response_model=BaselineOut, responses=_BASELINE_ERRORS,
    dependencies=[ApiKeyDep], summary="Add a recording to an asset's baseline",
    description="Another recording of the unchanged machine at the baseline's operating condition (within ±5 % of "
    "its speed): `?diagnosis_id=N` (a stored diagnosis of the asset) or a recording in the body, as for POST "
    "/diagnose (diagnosed and stored first). The baseline becomes the vector average of its recordings; from 3 "
    "recordings its 1X, 2X and centreline thresholds are the asset's own, from how much they differ from each "
    "other (`thresholds_basis`). Without a baseline, this one recording starts it. 409: a recording already in "
    "it, at another speed, or keeping no signature.",
    openapi_extra=_RECORDING_BODY,
)
async def add_baseline_recording(
    request: Request, asset_id: AssetPath, state: StateDep, reader: ReaderQueryDep,
    diagnosis_id: Annotated[int | None, Query(ge=1, le=2**63 - 1, description="Add this stored diagnosis.")] = None,
) -> dict:
    if diagnosis_id is None:
        diagnosis_id = await _recorded_from_body(request, state, asset_id, reader, "?diagnosis_id=")
    return await run_in_threadpool(add_recording, state, asset_id, diagnosis_id)


@router.delete(
    "/assets/{asset_id}/baseline/recordings/{diagnosis_id}", response_model=BaselineOut, responses=_BASELINE_ERRORS,
    dependencies=[ApiKeyDep], summary="Remove a recording from an asset's baseline",
    description="The baseline is recomputed from the others, its own thresholds too (below 3 recordings it goes "
    "back to the fleet-wide ones: `thresholds_basis`). The diagnosis stays in the history. 404: not one of the "
    "baseline's recordings; 409: its last one (DELETE /assets/{id}/baseline).")
def delete_baseline_recording(
    asset_id: AssetPath, state: StateDep,
    diagnosis_id: Annotated[int, Path(ge=1, le=2**63 - 1, description="The stored diagnosis to take out.")],
) -> dict:
    return remove_recording(state, asset_id, diagnosis_id)


@router.delete("/assets/{asset_id}/baseline", status_code=204, dependencies=[ApiKeyDep],
               responses=_BASELINE_ERRORS, summary="Remove an asset's baseline")
def delete_asset_baseline(asset_id: AssetPath, state: StateDep) -> None:
    if not delete_baseline(state, asset_id):
        raise InputError(f"asset {asset_id!r} has no baseline", "not_found")


@router.put("/assets/{asset_id}/thresholds", response_model=AssetBaselineOut,
            dependencies=[ApiKeyDep, JsonBodyDep], responses=_BASELINE_ERRORS,
            summary="Edit an asset's alarm thresholds on the change")
def put_asset_thresholds(asset_id: AssetPath, body: ThresholdsIn, state: StateDep, session: SessionDep):
    """Override some of the thresholds in force for this asset (the shipped ones,
    `models/default/change_thresholds.json`, or those of an automatic baseline's repeatability); `{}` removes
    the edits. Names: those of GET /assets/{id}/baseline's `thresholds`."""
    from rotordiag.models.change import shipped_rule

    try:
        shipped_rule().with_overrides(body.thresholds)
    except ValueError as exc:
        raise InputError(f"thresholds: {exc}") from None
    bad = [k for k, v in body.thresholds.items() if v is not None and not (v >= 0 and v < 1e9)]
    if bad:
        raise InputError(f"thresholds: {', '.join(bad)} must be a non-negative number (or null to not alarm on it)")
    put_thresholds(state, asset_id, body.thresholds)
    return get_asset_baseline(asset_id, session)


@router.get("/assets/{asset_id}/probes", response_model=ProbeConfigOut, responses=_BASELINE_ERRORS,
            summary="An asset's probe configuration")
def get_asset_probes(asset_id: AssetPath, session: SessionDep) -> ProbeConfigOut:
    found = get_probe_config(session, asset_id)
    if found is None:
        raise InputError(f"asset {asset_id!r} has no probe configuration; set one with PUT /assets/{asset_id}/probes",
                         "not_found")
    return ProbeConfigOut(asset_id=asset_id, probes=found[0], updated_at=found[1])


@router.put("/assets/{asset_id}/probes", response_model=ProbeConfigOut,
            dependencies=[ApiKeyDep, JsonBodyDep], responses=_BASELINE_ERRORS,
            summary="Set an asset's probe configuration",
            description="The column mapping (or layout in file order), units, probe sensitivity, gap voltage and "
            "keyphasor column of the asset's probes, stored once: every binary or multipart upload with this "
            "`asset_id` (POST /diagnose, POST /assets/{id}/baseline) is read with them and its answer says so "
            "(`asset_probes`, `input_notes`); likewise the rotation and viewing end, the clearance, the speed band "
            "around the rated speed and the model version its uploads are diagnosed with. An upload's own query "
            "parameters win, group by group (`layout`: channel_map/bearings/angles_deg; `units`; `sensitivity`; "
            "`gap_voltage`; `keyphasor`; `rotation`: rotation/viewed_from; `clearance`; `speed_band`; `model`). "
            "`{}` removes it.")
def put_asset_probes(asset_id: AssetPath, body: ProbeConfigIn, state: StateDep, session: SessionDep,
                     models: ModelsDep) -> ProbeConfigOut:
    from ...parsing import check_probe_config

    probes = body.model_dump(exclude_none=True)
    check_probe_config(probes)
    if probes.get("model_version") is not None and probes["model_version"] not in models.registry.versions():
        raise InputError(f"model_version {probes['model_version']!r} is not registered; GET /models lists the "
                         "versions", "not_found")
    put_probe_config(state, asset_id, probes)
    if not probes:
        return ProbeConfigOut(asset_id=asset_id, probes={}, updated_at=None)
    return get_asset_probes(asset_id, session)


@router.delete("/assets/{asset_id}/probes", status_code=204, dependencies=[ApiKeyDep],
               responses=_BASELINE_ERRORS, summary="Remove an asset's probe configuration")
def delete_asset_probes(asset_id: AssetPath, state: StateDep, session: SessionDep) -> None:
    if get_probe_config(session, asset_id) is None:
        raise InputError(f"asset {asset_id!r} has no probe configuration", "not_found")
    put_probe_config(state, asset_id, {})


@router.get("/assets", response_model=list[AssetSummary], summary="The assets, by site → unit → train")
def assets_list(session: SessionDep,
                site: Annotated[str | None, Query(min_length=1, max_length=MAX_LABEL_LEN,
                                                  description="Only this site's assets.")] = None) -> list[AssetSummary]:
    return [AssetSummary(**r) for r in list_assets(session, site)]


@router.put("/assets/{asset_id}/hierarchy", response_model=AssetSummary, dependencies=[ApiKeyDep, JsonBodyDep],
            responses=_BASELINE_ERRORS, summary="Set where an asset sits (site → unit → train)")
def put_asset_hierarchy(asset_id: AssetPath, body: HierarchyIn, state: StateDep, session: SessionDep) -> AssetSummary:
    put_hierarchy(state, asset_id, body.model_dump())
    found = [r for r in list_assets(session) if r["asset_id"] == asset_id]
    return AssetSummary(**found[0])


_STARTUP_BODY = {"requestBody": {
    "required": True,
    "description": "A start-up or coast-down recording with a keyphasor (or a speed the signal shows), in the forms "
    "of POST /diagnose: JSON (`DiagnoseRequest`), NPY (`application/octet-stream`) or a multipart part `file` "
    "(CSV / NPY / HDF5 / UFF / JSON); the asset's probe configuration fills what the query does not give.",
    "content": {"application/json": {"schema": {"$ref": "#/components/schemas/DiagnoseRequest"}},
                "application/octet-stream": {"schema": {"type": "string", "format": "binary"}},
                "multipart/form-data": {"schema": {"type": "object", "required": ["file"],
                                                   "properties": {"file": {"type": "string", "format": "binary"}}}}}}}


def _startup_sync(recording) -> dict:
    from ...startups import startup_data

    try:
        return startup_data(recording)
    except ValueError as exc:  # the features package's messages (speed reverses, keyphasor drops out, ...)
        raise InputError(str(exc)) from None


def _startup_answer(state, asset_id: str, startup_id: int, units: str) -> dict:
    """A stored start-up with what it does to the asset's verdict: the comparison with the baseline start-up
    (evidence rows, reasons) and the asset's latest stored verdict with it (status, headline)."""
    from rotordiag.models.output_units import revive_typed_texts, verdict_in_units

    from ...core.db import AssetStartup
    from ...startups import attach_startup, startup_comparison, startup_dict, startups_in_force

    with state.sessions() as s:
        row = s.get(AssetStartup, startup_id)
        assert row is not None
        out = startup_dict(row)
        base, later = startups_in_force(s, asset_id)
        out["baseline_startup_id"] = None if base is None else base.id
        rows = [r for r in asset_history(s, asset_id, 50, None) if r.verdict]
        latest = revive_typed_texts(rows[-1].verdict) if rows else None
        if row.is_baseline:
            out["evidence_rows"], out["reasons"] = [], []
            out["comparison"] = ("this is the asset's baseline start-up: later start-ups (POST without "
                                 "?baseline=true) are compared with it")
        else:
            entries, reasons = startup_comparison(base, row, latest)
            out["evidence_rows"] = entries
            out["reasons"] = [r.to_dict() for r in reasons]
            out["comparison"] = (f"compared with baseline start-up #{base.id}" if base is not None else
                                 f"no baseline start-up of this asset: nothing to compare with (POST "
                                 f"/assets/{asset_id}/startup?baseline=true sets one)")
        if latest is not None and later is not None and later.id == row.id:
            v = verdict_in_units(attach_startup(s, asset_id, latest), units)
            out["asset_verdict"] = {"diagnosis_id": rows[-1].id, "severity": v.get("severity"),
                                    "status": v.get("status"), "headline": v.get("headline"),
                                    "reasons": v.get("reasons") or []}
        else:
            out["asset_verdict"] = None
    out["output_units"] = units
    if units == "mil":
        from rotordiag.core.units import UM_PER_MIL, lengths_in

        out["peaks"] = [lengths_in(dict(p), "mil") for p in out["peaks"]]
        ev = out["evidence"]
        ev["top_mil"] = {b: [v / UM_PER_MIL for v in xy] for b, xy in ev.pop("top_um").items()}
        ev["slow_roll_mil"] = {b: [v / UM_PER_MIL for v in xy] for b, xy in ev.pop("slow_roll_um", {}).items()}
        ev["clearance_mil"] = {b: v / UM_PER_MIL for b, v in ev.pop("clearance_um").items()}
    return out


@router.post("/assets/{asset_id}/startup", responses=_BASELINE_ERRORS, dependencies=[ApiKeyDep],
             openapi_extra=_STARTUP_BODY, summary="Store a start-up or coast-down of an asset as evidence",
             description="The run is order-tracked and reduced to its 1X criticals and its coupling-end bearings' "
             "shaft-centreline rise (half-rise speed, position at the top speed); only that is stored, no waveform. "
             "`?baseline=true` makes it the asset's baseline start-up. A later start-up is compared with the "
             "baseline's: from then on every diagnosis of the asset (POST /diagnose with `asset_id`) and its report "
             "carry the comparison as `start-up` evidence rows and, on an \"aligned\" call whose coupling-end "
             "centreline rise changed, the reason `startup_changed` (confident → uncertain; headline: investigate "
             "the change). It never changes a band, Δ or probability. The answer says what it does to the asset's "
             "latest stored verdict. Refused (422, with what to do): a speed that reverses, a keyphasor that drops "
             "out, a recording too long for the reader's limits.")
async def post_asset_startup(
    request: Request, asset_id: AssetPath, state: StateDep, reader: ReaderQueryDep,
    baseline: Annotated[bool, Query(description="Make this run the asset's baseline start-up.")] = False,
    recorded_at: Annotated[dt.datetime | None, BeforeValidator(_iso_time), Query(
        description="When the run was recorded (ISO 8601).")] = None,
    note: Annotated[str | None, Query(min_length=1, max_length=2000, description="A note stored with it.")] = None,
    output_units: Annotated[Literal["um", "mil"], Query(description="Lengths of the answer: um or mil.")] = "um",
) -> dict:
    from ...pool import StartupBody
    from ...startups import store_startup
    from ..recordings import asset_probes_query, recording_answer

    query = dict(asset_id=asset_id, plant=None, sample_index=0, **reader)
    if "application/json" not in request.headers.get("content-type", ""):
        query = {**(await run_in_threadpool(asset_probes_query, state, query))[0], "asset_id": None}
    data = await recording_answer(request, state, query,
                                  lambda kind, body, filename, q: StartupBody(kind, body, filename, q),
                                  _startup_sync)
    sid = await run_in_threadpool(lambda: store_startup(state, asset_id, data, is_baseline=baseline,
                                                        recorded_at=recorded_at, note=note))
    return await run_in_threadpool(_startup_answer, state, asset_id, sid, output_units)


@router.get("/assets/{asset_id}/startups", summary="An asset's stored start-ups",
            responses={404: {"model": ErrorOut, "description": "No start-up stored for this asset."}})
def get_asset_startups(asset_id: AssetPath, session: SessionDep) -> dict:
    """The asset's stored start-ups (newest first, at most 100), which one is the baseline start-up and which
    later one is compared with it in the asset's verdicts."""
    from sqlalchemy import select

    from ...core.db import AssetStartup
    from ...startups import startup_dict, startups_in_force

    rows = list(session.scalars(select(AssetStartup).where(AssetStartup.asset_id == asset_id)
                                .order_by(AssetStartup.id.desc()).limit(100)))
    if not rows:
        raise InputError(f"no start-up stored for asset {asset_id!r}; POST /assets/{asset_id}/startup?baseline=true "
                         "with a run-up or coast-down recording sets its baseline start-up", "not_found")
    base, later = startups_in_force(session, asset_id)
    return {"asset_id": asset_id, "baseline_startup_id": None if base is None else base.id,
            "compared_startup_id": None if later is None else later.id,
            "startups": [startup_dict(r) for r in rows]}
