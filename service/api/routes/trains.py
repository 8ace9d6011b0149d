"""Shaft trains: GET /trains/presets, POST /trains/summary (the web page's plant card), POST /trains/simulate."""
from __future__ import annotations

import json
from dataclasses import asdict
from typing import Any

import anyio
from fastapi import APIRouter
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import Response

from ...errors import InputError
from ...schemas import TrainPreset, TrainSimulateOut, TrainSimulateRequest, TrainSummaryOut, TrainSummaryRequest
from ...trains import line_of_request, simulate_train_request
from ..deps import DiagnoseKeyDep, JsonBodyDep, StateDep
from ..errors import error_responses
from ..recordings import diagnosis_limiter, in_worker
from ..routing import FiniteJSONRoute

router = APIRouter(tags=["trains"], route_class=FiniteJSONRoute)

_ERRORS = error_responses({422: "Not exactly one of preset/shaftline/shaftline_toml, an unknown preset, invalid TOML "
                                 "or a shaft line the model cannot build or rest on its bearings; `detail` says what "
                                 "to fix."}, key="diagnose", body="json")


@router.get("/trains/presets", response_model=list[TrainPreset], summary="Preset shaft trains")
def list_presets() -> list[TrainPreset]:
    from rotordiag.simulator.shaftline import PRESETS

    return [TrainPreset(name=k, rated_speed_rpm=[float(s) for s in v["rated_speed_rpm"]]) for k, v in PRESETS.items()]


def _summary(body: TrainSummaryRequest) -> TrainSummaryOut:
    from rotordiag.simulator.train.shaftline import train_from_shaftline
    from rotordiag.simulator.train.summary import train_summary

    line, rated = line_of_request(body)
    speed = body.speed_rpm if body.speed_rpm is not None else rated
    try:
        s = train_summary(train_from_shaftline(line), float(speed))  # type: ignore[arg-type]
    except (ValueError, TypeError, ArithmeticError, LookupError, AttributeError) as exc:
        raise InputError(f"shaft line: {exc}") from None
    out = asdict(s)
    return TrainSummaryOut(source=body.preset or "shaftline", rated_speed_rpm=rated, **out)


@router.post("/trains/summary", response_model=TrainSummaryOut, dependencies=[DiagnoseKeyDep, JsonBodyDep],
             responses=_ERRORS, summary="A shaft train's bearings at their static state and its stability margin")
async def train_summary_route(body: TrainSummaryRequest) -> TrainSummaryOut:
    """Build the finite-element train of a preset or a shaft line, solve its static state on the oil films
    at `speed_rpm` and report each bearing's load, eccentricity and attitude angle, and the log decrement of
    the least-damped mode (docs/train.md)."""
    return await run_in_threadpool(_summary, body)


_SIM_ERRORS: dict[int | str, dict[str, Any]] = {
    **error_responses({422: "Not exactly one of preset/shaftline/shaftline_toml, an unknown preset, a shaft line the "
                            "model cannot build, a record over the size limit (record_revs × samples_per_rev), an "
                            "offset that presses a journal on its bearing metal (the bearing and the largest offset "
                            "the train takes are named), or a simulation over the time limit; `detail` says what to "
                            "fix."}, key="diagnose", body="json"),
    200: {"description": "The recording: JSON (`format` json), or a CSV / HDF5 file (`format` csv / h5) in the "
                         "layout of `rotordiag simulate --train --probes-out`, its warnings in the "
                         "`X-Rotordiag-Warnings` header (a JSON list).",
          "content": {"application/json": {}, "text/csv": {}, "application/x-hdf5": {}}},
}

_MEDIA = {"csv": "text/csv; charset=utf-8", "h5": "application/x-hdf5"}


@router.post("/trains/simulate", response_model=TrainSimulateOut, dependencies=[DiagnoseKeyDep, JsonBodyDep],
             responses=_SIM_ERRORS, summary="A shaft train's steady recording: its probes and keyphasor")
async def train_simulate_route(body: TrainSimulateRequest, state: StateDep) -> Any:
    """Build the finite-element train of a preset or a shaft line, misalign it by moving the exciter's bearings
    (`offset_um` along `offset_angle_deg`, default −90°: the exciter low; `angular_mrad`), unbalance it and
    simulate it at `speed_rpm`: what a 45°/135° probe pair at every bearing and a keyphasor record (µm, DC
    included), with the stability warnings (a speed beyond the threshold gives oil whirl/whip). The record is
    bounded (record_revs × samples_per_rev ≤ 32768 samples per channel) and the simulation runs in a diagnosis
    worker within ROTORDIAG_DIAGNOSIS_TIMEOUT_S (docs/train.md)."""
    from ...pool import TrainSimulate

    if state.pool is not None:
        answer = (await in_worker(state, TrainSimulate(body)))[1]
    else:
        limit_s = float(state.settings.diagnosis_timeout_s)
        try:
            with anyio.fail_after(limit_s):
                answer = await anyio.to_thread.run_sync(simulate_train_request, body,
                                                        limiter=diagnosis_limiter(state), abandon_on_cancel=True)
        except TimeoutError:
            raise InputError(f"the train simulation took longer than the limit of {limit_s:g} s and was abandoned; "
                             "ask for fewer revolutions (transient_revs, record_revs) or samples per revolution "
                             "(or raise ROTORDIAG_DIAGNOSIS_TIMEOUT_S)") from None
    if "json" in answer:
        return TrainSimulateOut(**answer["json"])
    name = f"rotordiag-train-{body.preset or 'shaftline'}.{body.format}"
    return Response(answer["file"], media_type=_MEDIA[body.format],
                    headers={"Content-Disposition": f'attachment; filename="{name}"',
                             "X-Rotordiag-Warnings": json.dumps(answer["warnings"], ensure_ascii=True),
                             "X-Content-Type-Options": "nosniff", "Cache-Control": "no-store"})
