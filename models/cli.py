"""CLI commands of the models package: ``train``, ``models list|activate|rollback``, ``diagnose``."""
from __future__ import annotations

import os
from pathlib import Path
from typing import Optional

import typer

#: Registry used when --registry is not given: $ROTORDIAG_REGISTRY, else the shipped default.
DEFAULT_REGISTRY = Path(__file__).resolve().parent / "default_registry"


def default_registry() -> Path:
    env = os.environ.get("ROTORDIAG_REGISTRY")
    return Path(env) if env else DEFAULT_REGISTRY


def _fail(message: str, code: int = 2) -> None:
    typer.secho(f"error: {message}", fg=typer.colors.RED, err=True)
    raise typer.Exit(code)


_REGISTRY_HELP = "Model registry directory (default: $ROTORDIAG_REGISTRY, else the shipped default registry)."


def register(app: typer.Typer) -> None:
    """Add this package's commands to the ``rotordiag`` app."""
    models_app = typer.Typer(help="List, activate and roll back registered models.", no_args_is_help=True)
    app.add_typer(models_app, name="models")

    @app.command()
    def train(
        data: list[Path] = typer.Argument(..., help="Dataset HDF5 file(s) (rotordiag dataset generate / merge); several are joined."),
        registry: Path = typer.Option(..., "--registry", help="Registry directory to add the model to (created if missing)."),
        config: Optional[Path] = typer.Option(None, "--config", help="train.toml (bands, estimators, evaluation; see docs/models.md)."),
        activate: bool = typer.Option(True, "--activate/--no-activate", help="Make the new model the active one."),
        cache: bool = typer.Option(True, "--cache/--no-cache", help="Cache extracted features next to the dataset."),
        threads: int = typer.Option(1, min=1, max=256, help="OpenMP threads of the boosted trees (1 is safest on shared machines)."),
    ) -> None:
        """Extract features, evaluate on held-out plants, fit, and register a model."""
        from threadpoolctl import threadpool_limits

        from .config import TrainConfig
        from .dataset import load_feature_tables
        from .registry import Registry, RegistryError
        from .train import train_and_register

        try:
            cfg = TrainConfig.from_file(config) if config is not None else TrainConfig()
            typer.echo(f"reading {', '.join(map(str, data))} and extracting features …", err=True)
            table = load_feature_tables(data, cache=cache)
            typer.echo(
                f"{len(table)} samples from {len(set(table.plant_id.tolist()))} plants "
                f"(skipped: {table.meta.get('skipped')}; features {table.meta['feature_time_s']} s, "
                f"cache {'hit' if table.meta['feature_cache']['hit'] else 'written'})", err=True)
            with threadpool_limits(threads):
                version, report = train_and_register(table, cfg, Registry(registry), activate=activate)
        except (ValueError, RegistryError) as exc:
            _fail(str(exc))
        except KeyboardInterrupt:
            _fail("interrupted; nothing was registered (the feature cache, if written, is kept)", 130)
        typer.echo(f"registered {version} in {registry}" + (" (active)" if activate else ""))
        typer.echo(_summary(report))

    @models_app.command("list")
    def list_models(registry: Optional[Path] = typer.Option(None, "--registry", help=_REGISTRY_HELP)) -> None:
        """List the versions of a registry (* = active)."""
        from .registry import Registry, RegistryError

        reg = Registry(registry or default_registry())
        try:
            versions = reg.list()
        except RegistryError as exc:
            _fail(str(exc))
        if not versions:
            typer.echo(f"no models in {reg.root}")
            return
        for v in versions:
            mech = v.card.get("metrics", {}).get("per_mechanism", {})
            f1 = ", ".join(f"{m} F1 {r['model']['macro_f1']:.2f}" for m, r in mech.items() if "model" in r)
            typer.echo(f"{'*' if v.active else ' '} {v.name}  {v.card.get('created', '?')}  "
                       f"{v.card.get('training_data', {}).get('n_rows_used', '?')} rows  {f1}  "
                       f"code {v.card.get('code_version', '?')}")

    @models_app.command("activate")
    def activate_model(
        version: str = typer.Argument(..., help="Version name, e.g. v0002."),
        registry: Optional[Path] = typer.Option(None, "--registry", help=_REGISTRY_HELP),
    ) -> None:
        """Make VERSION the active model."""
        from .registry import Registry, RegistryError

        try:
            Registry(registry or default_registry()).activate(version)
        except RegistryError as exc:
            _fail(str(exc))
        typer.echo(f"active: {version}")

    @models_app.command("rollback")
    def rollback_model(registry: Optional[Path] = typer.Option(None, "--registry", help=_REGISTRY_HELP)) -> None:
        """Re-activate the model that was active before the current one."""
        from .registry import Registry, RegistryError

        try:
            v = Registry(registry or default_registry()).rollback()
        except RegistryError as exc:
            _fail(str(exc))
        typer.echo(f"active: {v}")

    @app.command()
    def diagnose(
        file: Path = typer.Argument(..., help="Waveforms: .csv (one column per probe), .npy (channels × points) or .h5."),
        registry: Optional[Path] = typer.Option(None, "--registry", help=_REGISTRY_HELP),
        version: Optional[str] = typer.Option(None, "--version", help="Model version (default: the active one)."),
        sidecar: Optional[Path] = typer.Option(None, "--sidecar", help="JSON with sample_rate_hz, units, channels, speed_rpm, clearance_um (default: FILE with .json)."),
        sample_rate_hz: Optional[float] = typer.Option(None, "--sample-rate-hz", help="Sample rate, Hz."),
        units: Optional[str] = typer.Option(None, "--units", help="um | mm | m | mil."),
        channels: Optional[str] = typer.Option(None, "--channels", help="Probe layout in file order, BEARING@ANGLE: '1@45,1@135,2@45,2@135'."),
        speed_rpm: Optional[float] = typer.Option(None, "--speed-rpm", help="Running speed, r/min (estimated from the signal if omitted)."),
        clearance_um: Optional[float] = typer.Option(None, "--clearance-um", help="Radial bearing clearance, µm (gives the offset in µm)."),
        sample: Optional[int] = typer.Option(None, "--sample", help="Row of a rotordiag dataset HDF5 file."),
        as_json: bool = typer.Option(False, "--json", help="Print the verdict as JSON."),
    ) -> None:
        """Diagnose coupling misalignment from one recording."""
        import json

        from features import extract_features

        from .predict import diagnose as run_diagnose
        from .predict import format_verdict, load_bundle
        from .registry import RegistryError
        from .waveform_io import parse_channels, read_recording

        try:
            overrides = {
                "sample_rate_hz": sample_rate_hz, "units": units, "speed_rpm": speed_rpm,
                "clearance_um": clearance_um,
                "channels": parse_channels(channels) if channels else None,
            }
            rec, info = read_recording(file, sidecar=sidecar, overrides=overrides, sample=sample)
            bundle = load_bundle(registry or default_registry(), version)
            fr = extract_features(rec)
            clearance = rec.clearance_um if isinstance(rec.clearance_um, (int, float)) else None
            if isinstance(rec.clearance_um, dict) and rec.clearance_um:
                # Δ is δ over the coupling bearings' clearance: use bearing 2/3 when given.
                cands = [rec.clearance_um.get(b) for b in (2, 3) if rec.clearance_um.get(b)]
                clearance = float(sum(cands) / len(cands)) if cands else None
            verdict = run_diagnose(bundle, fr, clearance_um=clearance)
        except (ValueError, RegistryError) as exc:
            _fail(str(exc))
        if as_json:
            d = verdict.to_dict()
            if "truth" in info:
                d["truth"] = info["truth"]
            typer.echo(json.dumps(d, indent=2))
        else:
            typer.echo(format_verdict(verdict))
            if "truth" in info:
                typer.echo(f"(dataset truth: Δ = {info['truth']['misalignment']:.3f})")


def _summary(report: dict) -> str:
    lines = ["held-out plants (GroupKFold), macro-F1  model | rule of thumb | 2X/1X threshold:"]
    for kind in ("mechanism", "speed_band_rpm"):
        for name, r in report["results"][kind].items():
            if "model" not in r:
                continue
            lines.append(
                f"  {kind:>14s} {name:<10s} n={r['n_rows']:<5d} {r['model']['macro_f1']:.3f} | "
                f"{r['rule_of_thumb']['macro_f1']:.3f} | {r['ratio_threshold']['macro_f1']:.3f}   "
                f"Δ MAE {r['model']['delta_mae']:.3f}, ECE {r['model']['ece']:.3f}"
            )
    for mech, t in report.get("targets", {}).items():
        ok = t["macro_f1_at_least_0.90"] and t["margin_at_least_0.15"]
        lines.append(f"  target {mech}: F1 {t['model_macro_f1']:.3f} vs best baseline "
                     f"{t['best_baseline_macro_f1']:.3f} → {'met' if ok else 'NOT met'}")
    return "\n".join(lines)
