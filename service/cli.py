"""CLI command that starts the HTTP service (``rotordiag serve``)."""
from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Optional

import typer

# The options of `rotordiag baseline set|add`, defined once: a stored diagnosis, or how to read a recording (as
# `rotordiag diagnose` reads it; a sidecar JSON's values are overridden by these)
DiagnosisIdOption = Annotated[Optional[int], typer.Option("--diagnosis-id", help="A stored diagnosis of the asset.")]
SampleRateOption = Annotated[Optional[float], typer.Option("--sample-rate-hz", help="The recording's sample rate, Hz.")]
UnitsOption = Annotated[Optional[str], typer.Option("--units", help="The recording's units: um | mm | m | mil | V | mV "
                                                   "(V and mV need sensitivity_v_per_mm in its sidecar JSON).")]
SpeedOption = Annotated[Optional[float], typer.Option("--speed-rpm", help="The running speed, r/min.")]
ClearanceOption = Annotated[Optional[float], typer.Option("--clearance-um", help="The radial bearing clearance, µm.")]
ChannelsOption = Annotated[Optional[str], typer.Option("--channels", help="BEARING@ANGLE list, as `rotordiag "
                                                       "diagnose`.")]


def _reading(sample_rate_hz: float | None, units: str | None, speed_rpm: float | None, clearance_um: float | None,
             channels: str | None) -> dict[str, Any]:
    """The reading options of a recording given to `rotordiag baseline set|add` (``load_options``' ``given``)."""
    return {"sample_rate_hz": sample_rate_hz, "units": units, "speed_rpm": speed_rpm, "clearance_um": clearance_um,
            "channels": channels}


def register(app: typer.Typer) -> None:
    """Add ``rotordiag serve`` to the ``rotordiag`` app."""

    @app.command()
    def serve(
        host: str = typer.Option("127.0.0.1", help="Interface to listen on (0.0.0.0 for every interface)."),
        port: int = typer.Option(8000, min=1, max=65535, help="TCP port."),
    ) -> None:
        """Serve the HTTP API (settings from ROTORDIAG_* environment variables or .env; see docs/service.md)."""
        import os

        # Requests already run in parallel (one diagnosis per CPU); OpenMP/BLAS threads inside each
        # would oversubscribe the cores. Set before the app (scikit-learn, NumPy) is imported.
        for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ.setdefault(var, "1")
        import uvicorn
        from pydantic import ValidationError

        from rotordiag.service.core.config import Settings

        try:
            settings = Settings()
        except ValidationError as exc:
            msgs = "; ".join(str(e.get("msg", "")).removeprefix("Value error, ") for e in exc.errors())
            typer.secho(f"error: invalid settings: {msgs}", fg="red", err=True)
            raise typer.Exit(2) from None
        try:
            # One uvicorn process per replica: diagnoses use every core through the diagnosis worker
            # processes (ROTORDIAG_DIAGNOSIS_WORKERS, service/pool.py), jobs scale out on Dask, and more
            # replicas (another `rotordiag serve` on this or another host, sharing a PostgreSQL
            # ROTORDIAG_DATABASE_URL and the data directory) claim jobs from the database.
            # SIGINT/SIGTERM: open requests get shutdown_timeout_s, then the jobs get it again (service/jobs.py)
            uvicorn.run("rotordiag.service.main:app", host=host, port=port,
                        log_level=settings.log_level.lower(), access_log=False,
                        timeout_graceful_shutdown=max(1, round(settings.shutdown_timeout_s)))
        except OSError as exc:  # e.g. address in use
            typer.secho(f"error: cannot listen on {host}:{port}: {exc}", fg="red", err=True)
            raise typer.Exit(2) from None

    _register_baseline(app)
    _register_report(app)
    _register_db(app)


def _register_db(app: typer.Typer) -> None:
    """``rotordiag db current|upgrade|copy``: the schema version of the service's database, and copying a
    SQLite store into PostgreSQL."""
    db_app = typer.Typer(help="The service's database (ROTORDIAG_DATABASE_URL, as `rotordiag serve`): schema "
                         "version, upgrade, copy into another database.", no_args_is_help=True)
    app.add_typer(db_app, name="db")

    def _url(url: Optional[str]) -> str:
        if url:
            return url
        from pydantic import ValidationError

        from rotordiag.service.core.config import Settings

        try:
            return Settings().effective_database_url
        except ValidationError as exc:
            typer.secho(f"error: invalid settings: {exc}", fg="red", err=True)
            raise typer.Exit(2) from None

    def _engine(url: str):
        from sqlalchemy.exc import ArgumentError

        from rotordiag.service.core.db import make_engine

        try:
            return make_engine(url)
        except (ArgumentError, ImportError) as exc:
            typer.secho(f"error: database URL {url!r}: {exc}", fg="red", err=True)
            raise typer.Exit(2) from None

    @db_app.command("current")
    def current(url: Optional[str] = typer.Option(None, "--url", help="Database URL (default: the settings').")) -> None:
        """Print the database's schema version and the newest one this code knows."""
        from rotordiag.service.core.db import current_revision, head_revision

        engine = _engine(_url(url))
        typer.echo(f"database: {current_revision(engine) or 'none (not migrated yet)'}; newest: {head_revision()}")

    @db_app.command("upgrade")
    def upgrade(url: Optional[str] = typer.Option(None, "--url", help="Database URL (default: the settings').")) -> None:
        """Migrate the database to the newest schema version (the server does this at its start too)."""
        from rotordiag.service.core.db import current_revision, migrate

        engine = _engine(_url(url))
        migrate(engine)
        typer.echo(f"database at schema version {current_revision(engine)}")

    @db_app.command("copy")
    def copy(target: str = typer.Argument(..., help="URL of the EMPTY database to copy into, e.g. "
                                          "postgresql://rotordiag:PASSWORD@db:5432/rotordiag."),
             source: Optional[str] = typer.Option(None, "--from", help="URL of the database to copy "
                                                  "(default: the settings', e.g. the SQLite file under data_dir).")) -> None:
        """Copy every job, diagnosis, baseline and alarm setting into another database (SQLite → PostgreSQL).

        Stop the server first: rows written during the copy would be missed."""
        from sqlalchemy.exc import OperationalError

        from rotordiag.service.core.db import CopyError, copy_store

        src, dst = _engine(_url(source)), _engine(target)
        try:
            copied = copy_store(src, dst)
        except (CopyError, OperationalError) as exc:
            typer.secho(f"error: {str(exc).splitlines()[0]}", fg="red", err=True)
            raise typer.Exit(2) from None
        for table, n in copied.items():
            typer.echo(f"{table}: {n} row(s)")


def _register_baseline(app: typer.Typer) -> None:
    """``rotordiag baseline show|set|add|remove|clear ASSET``: the asset baselines of the service's database."""
    baseline_app = typer.Typer(help="Asset baselines in the service's database (ROTORDIAG_* settings, as "
                               "`rotordiag serve`): show, set (from a recording, a stored diagnosis or the first "
                               "recordings), add or remove a recording, clear.", no_args_is_help=True)
    app.add_typer(baseline_app, name="baseline")

    def _open():
        from pydantic import ValidationError

        from rotordiag.service.core.config import Settings
        from rotordiag.service.core.db import init_db, make_engine

        try:
            settings = Settings()
        except ValidationError as exc:
            typer.secho(f"error: invalid settings: {exc}", fg="red", err=True)
            raise typer.Exit(2) from None
        settings.data_dir.mkdir(parents=True, exist_ok=True)
        return _DbState(init_db(make_engine(settings.effective_database_url)), settings), settings

    def _fail(message: str) -> None:
        typer.secho(f"error: {message}", fg="red", err=True)
        raise typer.Exit(2)

    @baseline_app.command("show")
    def show(asset_id: str = typer.Argument(..., help="The asset."),
             as_json: bool = typer.Option(False, "--json", help="Print it as JSON (what `rotordiag diagnose "
                                          "--baseline` reads; the same as GET /assets/{id}/baseline).")) -> None:
        """Show an asset's baseline (or the automatic proposal) and its alarm thresholds."""
        import json

        from rotordiag.service.baseline import baseline_dict, propose, rule_for, thresholds_origin
        from rotordiag.service.errors import InputError
        from rotordiag.service.store import baseline_recordings, get_baseline, get_thresholds

        state, _ = _open()
        with state.sessions() as s:
            row = get_baseline(s, asset_id)
            out: dict = {"asset_id": asset_id, "baseline": baseline_dict(row, recordings=baseline_recordings(s, asset_id))
                         if row is not None else None,
                         "thresholds": rule_for(s, asset_id, row).thresholds,
                         "edited_thresholds": get_thresholds(s, asset_id),
                         "thresholds_origin": thresholds_origin(s, asset_id, row)}
            if row is None:
                try:
                    p = propose(s, asset_id)
                    out["proposal"] = {"diagnosis_ids": p["diagnosis_ids"], "speed_rpm": p["speed_rpm"]}
                except InputError as exc:
                    out["proposal"] = {"reason": str(exc)}
        if as_json:
            typer.echo(json.dumps(out, indent=2, default=str))
            return
        b = out["baseline"]
        if b is None:
            typer.echo(f"asset {asset_id}: no baseline")
            p = out["proposal"]
            typer.echo(f"  automatic proposal: diagnoses {p['diagnosis_ids']} at {p['speed_rpm']:.0f} r/min "
                       f"(`rotordiag baseline set {asset_id} --auto`)" if "diagnosis_ids" in p else f"  {p['reason']}")
        else:
            speed = "unknown" if b["speed_rpm"] is None else f"{b['speed_rpm']:.0f} r/min"
            typer.echo(f"asset {asset_id}: baseline set {b['set_at']} from {b['source']} (diagnoses "
                       f"{b['diagnosis_ids']}), speed {speed} (compared within ±5 %), model {b['model_version']}")
            typer.echo(_basis_line(b))
        origin = out["thresholds_origin"]
        typer.echo("  alarm thresholds: " + ", ".join(
            f"{k} {v:.3g}" + ("" if origin.get(k) == "shipped" else f" ({origin.get(k)})")
            for k, v in out["thresholds"].items() if v is not None))

    @baseline_app.command("set")
    def set_(
        asset_id: str = typer.Argument(..., help="The asset."),
        recording: Optional[Path] = typer.Argument(None, help="A recording (as `rotordiag diagnose` reads: CSV, NPY, "
                                                   "HDF5, JSON; options from its sidecar JSON or below)."),
        diagnosis_id: DiagnosisIdOption = None,
        auto: bool = typer.Option(False, "--auto", help="The average of the asset's first --n stored recordings."),
        n: int = typer.Option(3, "--n", min=1, max=50, help="With --auto: recordings to average."),
        sample_rate_hz: SampleRateOption = None, units: UnitsOption = None, speed_rpm: SpeedOption = None,
        clearance_um: ClearanceOption = None, channels: ChannelsOption = None,
    ) -> None:
        """Set (or replace) an asset's baseline: from a recording, --diagnosis-id or --auto."""
        from rotordiag.service.baseline import from_diagnosis, set_auto
        from rotordiag.service.errors import InputError

        if sum([recording is not None, diagnosis_id is not None, auto]) != 1:
            _fail("give exactly one of a RECORDING, --diagnosis-id or --auto")
        state, settings = _open()
        try:
            if diagnosis_id is not None:
                b = from_diagnosis(state, asset_id, diagnosis_id)  # type: ignore[arg-type]
            elif auto:
                b = set_auto(state, asset_id, n)  # type: ignore[arg-type]
            else:
                assert recording is not None
                did = _store_recording(state, settings, asset_id, recording,
                                       _reading(sample_rate_hz, units, speed_rpm, clearance_um, channels))
                b = from_diagnosis(state, asset_id, did, "recording")  # type: ignore[arg-type]
        except InputError as exc:
            _fail(str(exc))
        except ValueError as exc:
            _fail(f"{recording}: {exc}")
        typer.echo(f"asset {asset_id}: baseline set from {b['source']} (diagnoses {b['diagnosis_ids']}), speed "
                   f"{b['speed_rpm']:.0f} r/min, model {b['model_version']}" if b["speed_rpm"] is not None else
                   f"asset {asset_id}: baseline set from {b['source']} (diagnoses {b['diagnosis_ids']})")
        typer.echo(_basis_line(b))

    def _store_recording(state, settings, asset_id: str, recording: Path, given: dict) -> int:
        """Diagnose ``recording`` with the active model and store it in the asset's history; its diagnosis id."""
        from rotordiag.features.reader import read_recording
        from rotordiag.models.diagnose_files import CLI_LIMITS, load_options
        from rotordiag.service.baseline import record_verdict
        from rotordiag.service.inference import ModelStore

        opts = load_options(recording, None, given)
        rec = read_recording(recording, options=opts, limits=CLI_LIMITS).recording
        verdict = ModelStore.open(settings).diagnose(rec)
        did = record_verdict(state, asset_id, None, verdict)
        assert did is not None
        return did

    def _basis_line(b: dict) -> str:
        """Where the baseline's change thresholds come from, in words."""
        from rotordiag.models.change import basis_note

        return f"  change thresholds: {basis_note(b['thresholds_basis'])}"

    @baseline_app.command("add")
    def add(
        asset_id: str = typer.Argument(..., help="The asset."),
        recording: Optional[Path] = typer.Argument(None, help="A recording of the unchanged machine at the "
                                                   "baseline's operating condition (as `rotordiag diagnose` reads)."),
        diagnosis_id: DiagnosisIdOption = None,
        sample_rate_hz: SampleRateOption = None, units: UnitsOption = None, speed_rpm: SpeedOption = None,
        clearance_um: ClearanceOption = None, channels: ChannelsOption = None,
    ) -> None:
        """Add a recording to an asset's baseline (POST /assets/{id}/baseline/recordings): from 3 recordings its
        change thresholds are the asset's own."""
        from rotordiag.service.baseline import add_recording
        from rotordiag.service.errors import InputError

        if (recording is None) == (diagnosis_id is None):
            _fail("give exactly one of a RECORDING or --diagnosis-id")
        state, settings = _open()
        try:
            if diagnosis_id is None:
                assert recording is not None
                diagnosis_id = _store_recording(state, settings, asset_id, recording,
                                                _reading(sample_rate_hz, units, speed_rpm, clearance_um, channels))
            b = add_recording(state, asset_id, diagnosis_id)  # type: ignore[arg-type]
        except InputError as exc:
            _fail(str(exc))
        except ValueError as exc:
            _fail(f"{recording}: {exc}")
        typer.echo(f"asset {asset_id}: diagnosis {diagnosis_id} added; the baseline is made of "
                   f"{b['n_recordings']} recording(s) (diagnoses {b['diagnosis_ids']})")
        typer.echo(_basis_line(b))

    @baseline_app.command("remove")
    def remove(asset_id: str = typer.Argument(..., help="The asset."),
               diagnosis_id: int = typer.Option(..., "--diagnosis-id", help="The baseline recording to take out.")
               ) -> None:
        """Take a recording out of an asset's baseline (DELETE /assets/{id}/baseline/recordings/{diagnosis_id})."""
        from rotordiag.service.baseline import remove_recording
        from rotordiag.service.errors import InputError

        state, _ = _open()
        try:
            b = remove_recording(state, asset_id, diagnosis_id)  # type: ignore[arg-type]
        except InputError as exc:
            _fail(str(exc))
        typer.echo(f"asset {asset_id}: diagnosis {diagnosis_id} removed; the baseline is made of "
                   f"{b['n_recordings']} recording(s) (diagnoses {b['diagnosis_ids']})")
        typer.echo(_basis_line(b))

    @baseline_app.command("clear")
    def clear(asset_id: str = typer.Argument(..., help="The asset.")) -> None:
        """Remove an asset's baseline (its diagnoses stay)."""
        from rotordiag.service.store import delete_baseline

        state, _ = _open()
        if not delete_baseline(state, asset_id):  # type: ignore[arg-type]
            _fail(f"asset {asset_id!r} has no baseline")
        typer.echo(f"asset {asset_id}: baseline removed")


class _DbState:
    """The part of ``AppState`` that the baseline functions use (the database and the settings: the history's
    retention), for the CLI."""

    def __init__(self, sessions, settings) -> None:
        self.sessions = sessions
        self.settings = settings


def asset_report_data(asset_id: str, units: str = "um") -> dict:
    """What ``GET /assets/{id}/report`` shows of an asset (:func:`rotordiag.service.report.asset_report_inputs`:
    its trend, latest stored verdict, recordings and notes), from the service's database (ROTORDIAG_* settings,
    as ``rotordiag serve``). Raises ValueError for an unknown asset or unreadable settings."""
    from pydantic import ValidationError

    from rotordiag.service.core.config import Settings
    from rotordiag.service.core.db import init_db, make_engine
    from rotordiag.service.report import asset_report_inputs

    try:
        settings = Settings()
    except ValidationError as exc:
        raise ValueError(f"invalid service settings: {exc}") from None
    sessions = init_db(make_engine(settings.effective_database_url))
    with sessions() as s:
        out = asset_report_inputs(s, asset_id, units=units)
    if out is None:
        raise ValueError(f"asset {asset_id!r} has no stored diagnoses in {settings.effective_database_url}")
    return out


def _startup_evidence(verdict: dict | None, recording, track, baseline) -> tuple[dict | None, list[str]]:
    """The start-up beside the steady verdict (``models.checks.startup``): its evidence entries as report notes and,
    for an "aligned" call on a start-up that changed since the baseline, the ``startup_changed`` reason added to the
    verdict (a confident verdict becomes uncertain; the band is never changed)."""
    from rotordiag.features.transient import centreline, track_orders
    from rotordiag.models.checks.startup import StartupContext, startup_findings
    from rotordiag.models.startup import misaligned_call, startup_evidence, with_startup

    def evidence(rec, tr):
        return startup_evidence(tr, None if rec.dc_removed else centreline(rec, tr))

    base = evidence(baseline, track_orders(baseline)) if baseline is not None else None
    entries, reasons = startup_findings(StartupContext(evidence(recording, track), base, misaligned_call(verdict)))
    notes = [f"start-up evidence ({e['effect']}): {e['text']}" for e in entries]
    if verdict is not None and reasons:
        verdict = with_startup(verdict, [], reasons)
    return verdict, notes


def report_target(target: str | None, asset_option: str | None) -> tuple[Path | None, str | None]:
    """``rotordiag report``'s argument read as (recording, asset): an existing file is a recording (``--asset``
    may then name the asset beside it); anything else is an asset id, which ``--asset`` may not name again.
    A name that looks like a recording file (a reader's suffix, or a folder in it) but does not exist is
    refused as a missing file rather than taken for an asset.

    Raises
    ------
    ValueError
        The message says what to fix.
    """
    from rotordiag.features.reader import FORMATS
    from rotordiag.service.schemas import _check_asset_id

    if target is None:
        return None, asset_option
    path = Path(target)
    if path.is_file():
        return path, asset_option
    suffixes = {s for group in FORMATS.values() for s in group}
    if path.suffix.lower() in suffixes or "/" in target:
        raise ValueError(f"{target}: no such recording file (an asset's id has no folder and no recording "
                         f"suffix such as {', '.join(sorted(suffixes))})")
    if path.exists():
        raise ValueError(f"{target} is a folder, not a recording file or an asset's id")
    if asset_option is not None:
        raise ValueError(f"the asset is given twice ({target!r} and --asset {asset_option!r}): name it once, "
                         "as the argument (`rotordiag report G3`) or with --asset beside a recording")
    try:
        return None, _check_asset_id(target)
    except ValueError as exc:
        raise ValueError(f"{target!r} is neither a recording file nor an asset's id: {exc}") from None


def _register_report(app: typer.Typer) -> None:
    """``rotordiag report``: a PDF and an HTML page to hand on."""

    @app.command()
    def report(
        target: Optional[str] = typer.Argument(
            None, metavar="ASSET|RECORDING",
            help="An asset's id (its latest stored verdict, recordings and trend from the service's database, as "
                 "GET /assets/{id}/report), or a steady recording file (its verdict, reasons and evidence). An "
                 "existing file is read as a recording; anything else is an asset id."),
        out: Path = typer.Option(..., "--out", help="The PDF to write (the HTML page goes next to it, .html)."),
        startup: Optional[Path] = typer.Option(None, "--startup", help="A start-up or coast-down recording: its Bode, "
                                                                       "polar, cascade, centreline, orbit plots."),
        asset: Optional[str] = typer.Option(None, "--asset", help="The asset's id: its trend from the service's "
                                                                  "database (ROTORDIAG_* settings, as `rotordiag serve`); "
                                                                  "beside a RECORDING (else give the asset as the "
                                                                  "argument: `rotordiag report G3`)."),
        registry: Optional[Path] = typer.Option(None, "--registry", help="Model registry (default: the shipped one)."),
        version: Optional[str] = typer.Option(None, "--version", help="Model version (default: the active one)."),
        sample_rate_hz: Optional[float] = typer.Option(None, "--sample-rate-hz", help="Sample rate, Hz (both files)."),
        channels: Optional[str] = typer.Option(None, "--channels", help="Probe layout in file order, BEARING@ANGLE."),
        keyphasor_channel: Optional[str] = typer.Option(None, "--keyphasor-channel", help="Raw keyphasor channel (column or index)."),
        clearance_um: Optional[float] = typer.Option(None, "--clearance-um", help="Radial bearing clearance, µm."),
        plant: Optional[Path] = typer.Option(None, "--plant", help="Plant file: adds its Campbell diagram."),
        baseline_startup: Optional[Path] = typer.Option(None, "--baseline-startup", help="The asset's baseline "
                                                        "start-up (same layout): --startup is compared with it, its "
                                                        "coupling-end centreline rise as evidence beside the verdict."),
        title: Optional[str] = typer.Option(None, "--title", help="Report title."),
        output_units: str = typer.Option("um", "--output-units", help="Lengths in the report and its plots: um | mil."),
    ) -> None:
        """Write a report (PDF + HTML) of an asset (`rotordiag report G3 --out g3.pdf`) or of recordings: the verdict
        with its status, reasons and evidence, the start-up plots, the trend."""
        try:
            recording, asset = report_target(target, asset)
        except ValueError as exc:
            typer.secho(f"error: {exc}", fg="red", err=True)
            raise typer.Exit(2) from None
        if recording is None and startup is None and asset is None:
            typer.secho("error: give an ASSET or a RECORDING (or --startup)", fg="red", err=True)
            raise typer.Exit(2)
        if out.suffix.lower() != ".pdf":
            typer.secho(f"error: --out {out}: the report is a .pdf (the .html is written next to it)", fg="red",
                        err=True)
            raise typer.Exit(2)
        from rotordiag.core.units import um_to
        from rotordiag.models.cli import default_registry
        from rotordiag.models.output_units import verdict_in_units
        from rotordiag.models.registry import RegistryError
        from rotordiag.models.report import build_report, write_report

        try:
            um_to(None, output_units)
        except ValueError as exc:
            typer.secho(f"error: --output-units: {exc}", fg="red", err=True)
            raise typer.Exit(2) from None
        units = "mil" if output_units.strip().lower().startswith("mil") else "um"

        given = {"sample_rate_hz": sample_rate_hz, "channels": channels, "keyphasor_channel": keyphasor_channel,
                 "clearance_um": clearance_um}
        recs: list[dict] = []
        verdict = None
        note = None
        track = None
        figs: dict = {}
        history: list[dict] = []
        try:
            if recording is not None:
                from rotordiag.features.reader import read_recording
                from rotordiag.models.diagnose_files import diagnose_read, load_options
                from rotordiag.models.predict import load_bundle

                res = read_recording(recording, options=load_options(recording, None, given))
                try:
                    bundle = load_bundle(registry or default_registry(), version)
                except RegistryError as exc:
                    raise ValueError(str(exc)) from None
                v, res, _ = diagnose_read(bundle, res)
                verdict = v.to_dict()
                recs.append({"file": str(recording), "role": "steady", "format": res.format, "notes": res.notes})
            else:
                note = "no steady recording given: no verdict (the start-up plots and the trend are evidence only)"
            if startup is not None:
                from rotordiag.features.plots import transient_figures
                from rotordiag.features.transient import track_orders
                from rotordiag.models.transient_cli import read_transient

                sres = read_transient(startup, given)
                track = track_orders(sres.recording)
                pl = None
                if plant is not None:
                    from rotordiag.simulator import Plant

                    pl = Plant.from_file(plant)
                figs = transient_figures(sres.recording, track, plant=pl, units=units)
                recs.append({"file": str(startup), "role": "start-up", "format": sres.format, "notes": sres.notes})
            notes: list[str] = []
            if baseline_startup is not None:
                if startup is None:
                    raise ValueError("--baseline-startup needs --startup (the start-up to compare with it)")
                bres = read_transient(baseline_startup, given)
                recs.append({"file": str(baseline_startup), "role": "baseline start-up", "format": bres.format,
                             "notes": bres.notes})
            if startup is not None:
                verdict, more = _startup_evidence(verdict, sres.recording, track,
                                                  bres.recording if baseline_startup is not None else None)
                notes += more
            if verdict is not None:
                verdict = verdict_in_units(verdict, units)
            if asset is not None:
                stored = asset_report_data(asset, units)
                history = stored["history"]
                if recording is None:   # the asset's latest stored verdict, as GET /assets/{id}/report shows it
                    verdict, note = stored["verdict"], stored["verdict_note"]
                    from rotordiag.service.report import NO_WAVEFORMS_NOTE

                    recs = stored["recordings"] + recs
                    notes = [n for n in stored["notes"] if startup is None or n != NO_WAVEFORMS_NOTE]
            content = build_report(title=title or f"rotordiag report{' — ' + asset if asset else ''}", asset_id=asset,
                                   recordings=recs, verdict=verdict, verdict_note=note, history=history,
                                   track=track, figures=figs, notes=notes, units=units)
            paths = write_report(content, out, out.with_suffix(".html"))
        except (ValueError, OSError) as exc:
            typer.secho(f"error: {exc}", fg="red", err=True)
            raise typer.Exit(2) from None
        finally:
            import matplotlib.pyplot as plt

            for f in figs.values():
                plt.close(f)
        typer.echo("wrote " + ", ".join(str(p) for p in paths))
