"""CLI commands of the dataset package: ``rotordiag dataset generate | info | merge``."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer

dataset_app = typer.Typer(
    name="dataset",
    help="Labelled datasets: run a TOML sweep spec through the simulator (on Dask) into HDF5.",
    no_args_is_help=True,
)


def _fail(message: str, code: int = 2) -> None:
    typer.secho(message, fg=typer.colors.RED, err=True)
    raise typer.Exit(code)


@dataset_app.command()
def generate(
    spec: Path = typer.Argument(..., help="Dataset spec (TOML); see examples/dataset_small.toml."),
    out: Path = typer.Option(..., "--out", "-o", help="Output HDF5 file; an existing one from the same spec is resumed."),
    workers: Optional[int] = typer.Option(
        None, "--workers", "-w", min=0,
        help="Worker processes of the local Dask cluster (default: CPUs available; 0 = serial, no Dask)."),
    scheduler: Optional[str] = typer.Option(
        None, "--scheduler", help="Address of an existing Dask scheduler, e.g. tcp://scheduler:8786."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show the progress bar."),
    connect_timeout: float = typer.Option(30.0, "--connect-timeout", min=0.1,
                                          help="Seconds to wait for --scheduler to answer."),
) -> None:
    """Generate (or resume) a dataset. Safe to kill at any moment; rerun the same command to resume."""
    from rotordiag.simulator.dataset.generate import generate as run
    from rotordiag.simulator.dataset.spec import SpecError
    from rotordiag.simulator.dataset.store import StoreError
    from rotordiag.simulator.runner import TaskError

    if workers is not None and scheduler is not None:
        raise typer.BadParameter("give either --workers or --scheduler, not both", param_hint="--workers")
    try:
        summary = run(spec, out, n_workers=workers, scheduler_address=scheduler, progress=progress,
                      connect_timeout_s=connect_timeout)
    except (SpecError, StoreError) as exc:
        _fail(str(exc))
    except TaskError as exc:
        _fail(f"{exc}\nthe samples finished so far are saved in {out}; fix the cause and rerun to resume", 1)
    except OSError as exc:
        if scheduler is not None:
            _fail(f"cannot reach the Dask scheduler at {scheduler}: {exc}")
        raise
    except KeyboardInterrupt:
        _fail(f"interrupted; the finished samples are saved in {out}; rerun the same command to resume", 130)
    what = "resumed" + (" (repaired after a crash)" if summary.repaired else "") if summary.resumed else "created"
    typer.echo(f"{out}: {what}; {summary.n_computed} samples computed, "
               f"{summary.n_done_before + summary.n_computed}/{summary.n_samples} done; status {summary.status_counts}; "
               f"{summary.elapsed_s:.1f} s")
    bad = {k: v for k, v in summary.status_counts.items() if k != "ok"}
    if bad:
        typer.secho(f"note: {sum(bad.values())} samples did not finish cleanly ({bad}); they are kept with their "
                    "status in labels/status", fg=typer.colors.YELLOW, err=True)


@dataset_app.command()
def info(
    path: Path = typer.Argument(..., help="Dataset HDF5 file."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Summarise a dataset: counts per class, status, mechanism and motion; parameter ranges."""
    from rotordiag.simulator.dataset.info import summarize
    from rotordiag.simulator.dataset.store import StoreError

    try:
        s = summarize(path)
    except StoreError as exc:
        _fail(str(exc))
    if as_json:
        typer.echo(json.dumps(s, indent=2))
        return
    typer.echo(f"{s['path']}  ({'merged, ' if s['merged'] else ''}format v{s['format_version']}, "
               f"code {s['code_version']}, created {s['created_utc']})")
    typer.echo(f"samples     {s['n_done']}/{s['n_samples']} done"
               + ("" if s["n_done"] == s["n_samples"] else "  (incomplete: rerun generate to resume)"))
    typer.echo(f"channels    {s['n_channels']} × {s['n_points']} points at {s['sample_rate_hz']:g} Hz: "
               + ", ".join(f"b{c['bearing']}@{c['angle_deg']:g}°" for c in s["channels"]))
    typer.echo(f"plants      {s['n_plants']} distinct")
    if s["sample_kind"] == "transient":
        t = s["transient"]
        for prof in t["profiles"]:
            typer.echo("samples are run-ups / coast-downs with a keyphasor: profile "
                       + ", ".join(f"{ts:g} s {n:g} r/min" for ts, n in zip(prof["times_s"], prof["speeds_rpm"])))
        typer.echo(f"            {t['record_s']:.3f} s per record, {t['keyphasor_marks']} keyphasor marks, "
                   f"{t['stopped_early']} stopped early; read them with DatasetReader.transient_sample")
    else:
        typer.echo("samples are steady runs, one speed each")
    for key in ("severity_counts", "status_counts", "mechanism_counts", "motion_counts"):
        typer.echo(f"{key.split('_')[0]:<11} " + ", ".join(f"{k} {v}" for k, v in s[key].items()))
    typer.echo("ranges")
    for k, (lo, hi) in s["parameter_ranges"].items():
        typer.echo(f"  {k:<32} {lo:.6g} .. {hi:.6g}")
    if s["bytes_per_done_sample"]:
        typer.echo(f"size        {s['file_bytes'] / 1e6:.2f} MB, {s['bytes_per_done_sample']} bytes/sample")


@dataset_app.command()
def merge(
    inputs: list[Path] = typer.Argument(..., help="Dataset files of one family (same measurement layout)."),
    out: Path = typer.Option(..., "--out", "-o", help="New merged HDF5 file."),
) -> None:
    """Join the finished samples of several dataset files into one new file."""
    from rotordiag.simulator.dataset.merge import merge as run
    from rotordiag.simulator.dataset.store import StoreError

    try:
        result = run(inputs, out)
    except StoreError as exc:
        _fail(str(exc))
    typer.echo(f"{out}: {result['n_samples']} samples from {len(result['sources'])} source specs")


@dataset_app.command()
def repair(path: Path = typer.Argument(..., help="Dataset HDF5 file of a killed run.")) -> None:
    """Make the file of a killed run readable by plain h5py again (keeps every finished sample)."""
    from rotordiag.simulator.dataset.store import StoreError, repair_file

    try:
        crashed, n_done = repair_file(path)
    except StoreError as exc:
        _fail(str(exc))
    typer.echo(f"{path}: {'repaired' if crashed else 'nothing to repair'}; {n_done} finished samples")


def register(app: typer.Typer) -> None:
    """Add the ``dataset`` command group to the ``rotordiag`` app."""
    app.add_typer(dataset_app, name="dataset")
