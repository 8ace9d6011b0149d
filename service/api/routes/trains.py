"""Shaft trains: GET /trains/presets, POST /trains/summary (the web page's plant card)."""
from __future__ import annotations

import tomllib
from dataclasses import asdict

from fastapi import APIRouter
from fastapi.concurrency import run_in_threadpool

from ...errors import InputError
from ...schemas import TrainPreset, TrainSummaryOut, TrainSummaryRequest
from ..deps import DiagnoseKeyDep, JsonBodyDep
from ..errors import error_responses
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
    from rotordiag.simulator.shaftline import ShaftLine
    from rotordiag.simulator.train.shaftline import shaftline_of, train_from_shaftline
    from rotordiag.simulator.train.summary import train_summary

    given = [k for k in ("preset", "shaftline", "shaftline_toml") if getattr(body, k) is not None]
    if len(given) != 1:
        raise InputError("give exactly one of `preset`, `shaftline` (tables) or `shaftline_toml` (file text); "
                         f"got {given or 'none'}")
    if body.preset is None and body.speed_rpm is None:
        raise InputError("give `speed_rpm`: a shaft line carries no rated speed")
    rated = None
    try:
        if body.preset is not None:
            line, rated = shaftline_of(body.preset)
        elif body.shaftline is not None:
            line = ShaftLine.from_dict(body.shaftline)
        else:
            try:
                tables = tomllib.loads(body.shaftline_toml or "")
            except tomllib.TOMLDecodeError as exc:
                raise InputError(f"shaftline_toml is not valid TOML: {exc}") from None
            line = ShaftLine.from_dict(tables)
        speed = body.speed_rpm if body.speed_rpm is not None else rated
        s = train_summary(train_from_shaftline(line), float(speed))  # type: ignore[arg-type]
    except InputError:
        raise
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
