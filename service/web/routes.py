"""The web page's routes: ``GET /`` (the page), ``GET /ui/static/{name}`` (its JS and CSS) and
``POST /ui/plot-data`` (orbit and spectrum arrays of a recording), ``POST /ui/transient-plots`` (a start-up's
or coast-down's plots as PNG).

The page is a client of the API: the verdict comes from ``POST /diagnose``, the trend from
``GET /assets/{id}/history``, the models from ``GET /models``. ``/ui/plot-data`` accepts the same
bodies and query parameters as ``/diagnose`` (it reuses the diagnose route's body parsing) and
returns pictures' data only; it stores nothing and needs no model. These routes are left out of the
OpenAPI schema: they belong to the page, not to the API clients program against.
"""
from __future__ import annotations

from importlib.resources import files
from pathlib import Path
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query, Request
from fastapi.responses import FileResponse

from ..api.deps import (
    DiagnoseKeyDep,
    StateDep,
)
from ..api.recordings import ReaderQueryDep, recording_answer  # same body forms and messages as /diagnose
from ..errors import InputError
from ..plotdata import plot_data, transient_plots
from ..pool import PlotBody, TransientPlots
from ..schemas import AssetId

#: the page's upload queries: the recording's index in an HDF5 dataset file, and the asset whose probe
#: configuration reads it (the same identifier and checks as /diagnose's)
_SampleIndex = Annotated[int, Query(ge=0, le=10_000_000)]
_AssetQuery = Annotated[AssetId | None, Query()]

#: the page's files, installed with the package (found through importlib.resources)
STATIC_DIR = Path(str(files("rotordiag.service.web.static")))

#: the only files served from STATIC_DIR (no path is built from the request)
_STATIC = {"app.js": "text/javascript; charset=utf-8", "style.css": "text/css; charset=utf-8"}

#: the page loads nothing from anywhere but this server
_SECURITY_HEADERS = {
    "Content-Security-Policy": "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data:; "
                               "connect-src 'self'; object-src 'none'; base-uri 'none'; frame-ancestors 'none'",
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
}

router = APIRouter(include_in_schema=False)


@router.get("/")
def index() -> FileResponse:
    """The single page."""
    return FileResponse(STATIC_DIR / "index.html", media_type="text/html; charset=utf-8",
                        headers={**_SECURITY_HEADERS, "Cache-Control": "no-cache"})


@router.get("/ui/static/{name}")
def static(name: str) -> FileResponse:
    """``app.js`` or ``style.css``."""
    media = _STATIC.get(name)
    if media is None:
        raise InputError(f"no static file {name!r}; the page uses {sorted(_STATIC)}", "not_found")
    return FileResponse(STATIC_DIR / name, media_type=media,
                        headers={"X-Content-Type-Options": "nosniff", "Cache-Control": "no-cache"})


@router.get("/ui/examples")
def examples() -> list[dict[str, Any]]:
    """The example recordings shipped with the package: name, title and the query they need."""
    from rotordiag.features.examples import describe_example, example_options, list_examples

    return [{"name": name, "title": describe_example(name), "query": example_options(name)} for name in list_examples()]


@router.get("/ui/examples/{name}")
def example_file(name: str) -> FileResponse:
    """One example recording's bytes (only names from :func:`examples`; no path is built from the request)."""
    from rotordiag.features.examples import example_path, list_examples

    if name not in list_examples():
        raise InputError(f"no example recording {name!r}; the examples are {list_examples()}", "not_found")
    return FileResponse(example_path(name), media_type="application/octet-stream", filename=name,
                        headers={"X-Content-Type-Options": "nosniff", "Cache-Control": "no-cache"})


def _plot_sync(state: Any, recording: Any) -> dict[str, Any]:
    try:
        return plot_data(recording, state.models.plot_features(recording))
    except ValueError as exc:  # the features package's messages for recordings it cannot analyse
        raise InputError(str(exc)) from None


@router.post("/ui/plot-data", dependencies=[DiagnoseKeyDep])
async def plot(
    request: Request,
    state: StateDep,
    reader: ReaderQueryDep,
    sample_index: _SampleIndex = 0,
    asset_id: _AssetQuery = None,
) -> dict[str, Any]:
    """Orbit and spectrum arrays of a recording sent as to ``POST /diagnose`` (see ``service.plotdata``);
    with ``asset_id``, read with the asset's probe configuration as /diagnose reads it (nothing is stored).

    Parsed and computed in a diagnosis worker (memory and time limits), as /diagnose; with
    ``ROTORDIAG_DIAGNOSIS_WORKERS=0`` in a thread of the server (HDF5 still decoded in the sandbox).
    Needs the API key when /diagnose does (``ROTORDIAG_DIAGNOSE_REQUIRES_KEY``).
    """
    query = await _reader_query(request, state, reader, sample_index, asset_id)
    return await recording_answer(request, state, query, PlotBody, lambda recording: _plot_sync(state, recording))


async def _reader_query(request: Request, state: Any, reader: dict[str, Any], sample_index: int,
                        asset_id: str | None) -> dict[str, Any]:
    """The reader's query of a page upload; with ``asset_id`` (binary or multipart), the asset's stored probe
    configuration fills what the query does not give, as /diagnose reads it (nothing is stored)."""
    query = dict(asset_id=None, plant=None, sample_index=sample_index, **reader)
    if asset_id is not None and "application/json" not in request.headers.get("content-type", ""):
        from fastapi.concurrency import run_in_threadpool

        from ..api.recordings import asset_probes_query

        query = {**(await run_in_threadpool(asset_probes_query, state, {**query, "asset_id": asset_id}))[0],
                 "asset_id": None}
    return query


def _transient_sync(recording: Any, units: str, cascade_scale: str = "db", plant_model: str | None = None,
                    plant_shaftline: dict | None = None, centreline_reference: str = "recorded") -> dict[str, Any]:
    from ..parsing import plant_of_model

    try:
        return transient_plots(recording, units, cascade_scale,
                               plant=plant_of_model(plant_model, plant_shaftline)
                               if plant_model or plant_shaftline else None,
                               centreline_reference=centreline_reference)
    except ValueError as exc:  # the features package's messages (speed reverses, keyphasor drops out, ...)
        raise InputError(str(exc)) from None


@router.post("/ui/transient-plots", dependencies=[DiagnoseKeyDep])
async def transient(
    request: Request,
    state: StateDep,
    reader: ReaderQueryDep,
    sample_index: _SampleIndex = 0,
    asset_id: _AssetQuery = None,
    output_units: Annotated[Literal["um", "mil"], Query()] = "um",
    cascade_scale: Annotated[Literal["db", "row", "linear"], Query(
        description="Trace height of the cascades: dB below the largest line (60 dB shown), each trace to its own "
                    "largest line, or one linear scale (a whip line dwarfs the low speeds)")] = "db",
    centreline_reference: Annotated[Literal["recorded", "slow_roll"], Query(
        description="Where the centreline plot's positions are measured from: the probes' own zero as recorded "
                    "(the gap voltage stated with a voltage record), or the slow roll — the slowest step put at the "
                    "bottom of the clearance (needs the clearance)")] = "recorded",
) -> dict[str, Any]:
    """A start-up or coast-down recording sent as to ``POST /diagnose``, order-tracked (``features.transient``)
    and plotted (``features.plots``): Bode, polar, cascade and full spectrum of each bearing, centreline, orbits,
    as PNG (base64) with the run's summary (``service.plotdata.transient_plots``); ``cascade_scale`` as
    ``rotordiag plots --cascade-scale``, ``centreline_reference`` as ``--centreline-reference``. Nothing is stored. In a
    diagnosis worker (memory and time limits), or with no workers in a thread of the server, as /ui/plot-data."""
    query = await _reader_query(request, state, reader, sample_index, asset_id)
    return await recording_answer(
        request, state, query,
        lambda kind, body, filename, q: TransientPlots(kind, body, filename, q, output_units, cascade_scale,
                                                       centreline_reference),
        lambda recording: _transient_sync(recording, output_units, cascade_scale, query.get("plant_model"),
                                          query.get("plant_shaftline"), centreline_reference))
