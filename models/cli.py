"""CLI commands of the models package: ``train``, ``models list|activate|rollback``, ``diagnose``."""
from __future__ import annotations

import os
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Optional

import typer


def default_registry() -> Path:
    """Registry used when --registry is not given: $ROTORDIAG_REGISTRY, else the shipped default."""
    from .registry import shipped_registry_dir

    env = os.environ.get("ROTORDIAG_REGISTRY")
    return Path(env) if env else shipped_registry_dir()


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
            table = load_feature_tables(data, cache=cache, augment=cfg.augment)
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

    @app.command()
    def retrain(
        registry: Path = typer.Option(..., "--registry", help="Registry to add the model to (created if missing); "
                                      "its active model is the one the new one must beat (empty: the shipped one)."),
        preset: Optional[str] = typer.Option(None, "--preset", help="A rated-machine preset by name (gen50_2pole, "
                                             "gen200_2pole, gen600_2pole, gen600_4pole)."),
        shaftline: Optional[Path] = typer.Option(None, "--shaftline", help="The plant's shaft-line TOML "
                                                 "(rotordiag plant from-shaftline; may hold rated_speed_rpm)."),
        rated_speed_rpm: Optional[list[float]] = typer.Option(None, "--rated-speed-rpm", help="Rated speed(s), r/min "
                                                              "(a preset gives its own); the sweep runs 0.8–1.05 × it."),
        n_samples: int = typer.Option(0, "--n-samples", min=0, max=20000, help="Simulated samples of the plant's "
                                      "dataset (0: the default, docs/models.md's learning curve)."),
        report_cases: int = typer.Option(0, "--report-cases", min=0, max=200, help="Held-out recordings per class "
                                         "(each coupling of a train, or the 4 lumped mechanisms, + aligned) of the quality report (0: the default)."),
        seed: int = typer.Option(0, "--seed", min=0, help="Seed of the dataset's design and of the report's held-out set."),
        work_dir: Optional[Path] = typer.Option(None, "--work-dir", help="Folder for the dataset and its features "
                                                "(default: ./retrain-<plant>; a rerun resumes it)."),
        workers: Optional[int] = typer.Option(None, "--workers", min=0, max=256, help="Simulation worker processes "
                                              "(default: the CPUs; 0: in this process)."),
        activate: bool = typer.Option(True, "--activate/--no-activate", help="Activate the new model if its report "
                                      "says it is better than the active one."),
        force: bool = typer.Option(False, "--force", help="Activate it even if it is not better (recorded: "
                                   "activated_by = forced)."),
        threads: int = typer.Option(1, min=1, max=256, help="OpenMP threads of the boosted trees."),
    ) -> None:
        """Retrain for one plant: its dataset, a model, and a quality report on held-out recordings of that plant
        beside the active model's; activated only if better (docs/models.md, "Retraining for one plant")."""
        from threadpoolctl import threadpool_limits
        from tqdm import tqdm

        from rotordiag.simulator.dataset.generate import generate
        from rotordiag.simulator.dataset.spec import SpecError, parse_spec
        from rotordiag.simulator.dataset.store import StoreError

        from .dataset import load_feature_table
        from .plant_retrain import (
            DEFAULT_N_SAMPLES,
            DEFAULT_REPORT_CASES,
            StagedProgress,
            describe_plant,
            drop_unmeasured,
            format_report,
            pending_card,
            plant_dataset_spec,
            plant_train_config,
            report_and_activate,
            retrain_units,
            stage_seconds,
        )
        from .predict import load_bundle
        from .registry import Registry, RegistryError, shipped_registry_dir
        from .train import train_and_register

        try:
            if (preset is None) == (shaftline is None):
                raise ValueError("give the plant as exactly one of --preset NAME or --shaftline FILE")
            plant = describe_plant(preset=preset, shaftline=shaftline, rated_speed_rpm=rated_speed_rpm or None)
            n = n_samples or DEFAULT_N_SAMPLES
            k = report_cases or DEFAULT_REPORT_CASES
            spec = plant_dataset_spec(plant, n_samples=n, seed=seed)
            reg = Registry(registry)
            own = reg.active_version() is not None
            compare_with = load_bundle(registry if own else shipped_registry_dir())
            label = f"{compare_with.version} ({'active in ' + str(registry) if own else 'the shipped model'})"
        except (ValueError, RegistryError) as exc:
            _fail(str(exc))
        import tomli_w

        folder = work_dir or Path(f"retrain-{plant.name.split(':')[-1].removesuffix('.toml')}")
        folder.mkdir(parents=True, exist_ok=True)
        spec_path = folder / "dataset.toml"
        spec_path.write_text(tomli_w.dumps(spec), encoding="utf-8")
        cfg = plant_train_config({"seed": seed})
        staged = StagedProgress(retrain_units(plant, n, k, cfg.augment.copies if cfg.augment is not None else 0),
                                seconds=stage_seconds(plant))
        bar = tqdm(total=1000, bar_format="{desc} {percentage:3.0f}%|{bar}| {elapsed}", dynamic_ncols=True)

        def cb(stage: str):
            def on(done: int, total: int) -> None:
                f, eta = staged.update(stage, done, total)
                bar.set_description_str(f"{stage} {done}/{total}, ETA "
                                        + ("?" if eta is None else f"{eta / 60:.1f} min"), refresh=False)
                bar.update(max(0, round(1000 * f) - bar.n))
            return on

        try:
            resolved = parse_spec(spec_path.read_text(encoding="utf-8"))
            generate(resolved, folder / "dataset.h5", n_workers=workers, progress=False, on_progress=cb("simulating"))
            table = load_feature_table(folder / "dataset.h5", progress=cb("features"), augment=cfg.augment)
            table, dropped = drop_unmeasured(table)
            cb("training")(0, 1)
            with threadpool_limits(threads):
                version, _ = train_and_register(table, cfg, reg, activate=False, card_extra={
                    **pending_card(plant), "features_never_measured": dropped})
            cb("training")(1, 1)
            report, by = report_and_activate(
                reg, version, plant, compare_with, seed=seed, n_per_class=k, activate=activate, force=force,
                progress=lambda stage, d, t: cb(stage)(d, t), cache=folder,
                compare_label=label)
        except (ValueError, SpecError, RegistryError) as exc:
            bar.close()
            _fail(str(exc))
        except StoreError as exc:   # the work folder's dataset.h5 is not this plant's and size's to resume
            bar.close()
            _fail(f"{exc}. rotordiag retrain keeps its dataset in {folder} (a rerun with the same plant, "
                  f"--n-samples and --seed resumes it): give another --work-dir, or remove {folder / 'dataset.h5'} "
                  "to start again")
        except KeyboardInterrupt:
            bar.close()
            _fail("interrupted; the dataset is kept and a rerun resumes it", 130)
        bar.close()
        typer.echo(format_report(report))
        state = ("activated (forced)" if by == "forced" else "activated: better on its report" if by
                 else "registered, NOT activated" + ("" if not activate else
                                                     " (not better on its report; --force to activate it anyway)"))
        typer.echo(f"{version} in {registry}: {state}")

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
        force: bool = typer.Option(False, "--force", help="Activate a plant-retrained version whose quality report "
                                   "says it is not better (recorded in its card: activated_by = forced)."),
    ) -> None:
        """Make VERSION the active model (a plant-retrained one only if its report says it is better, or --force)."""
        from .registry import Registry, RegistryError

        try:
            Registry(registry or default_registry()).activate(version, force=force)
        except RegistryError as exc:
            _fail(str(exc))
        typer.echo(f"active: {version}")

    @models_app.command("show")
    def show_model(
        version: Optional[str] = typer.Argument(None, help="Version name (default: the active one)."),
        registry: Optional[Path] = typer.Option(None, "--registry", help=_REGISTRY_HELP),
        as_json: bool = typer.Option(False, "--json", help="Print the card (and the plant report) as JSON."),
    ) -> None:
        """A version's card: training data, held-out metrics and, for a plant-retrained one, its quality report."""
        import json

        from .plant_retrain import REPORT_FILE, format_report
        from .registry import Registry, RegistryError

        reg = Registry(registry or default_registry())
        try:
            name = version or reg.active_version()
            if name is None:
                raise RegistryError(f"registry {reg.root}: no active model; name a version")
            card = reg.card(name)
        except RegistryError as exc:
            _fail(str(exc))
        assert name is not None   # _fail exits otherwise
        path = reg.root / name / REPORT_FILE
        report = json.loads(path.read_text(encoding="utf-8")) if path.is_file() else None
        if as_json:
            typer.echo(json.dumps({"card": card, "plant_report": report}, indent=2))
            return
        td = card.get("training_data", {})
        typer.echo(f"{name}{' (active)' if reg.active_version() == name else ''}  created {card.get('created', '?')}  "
                   f"code {card.get('code_version', '?')}")
        typer.echo(f"  trained on {td.get('n_rows_used', '?')} rows of {td.get('n_plants', '?')} plants, speeds "
                   f"{td.get('speed_rpm_range')} r/min; plant: {(card.get('plant') or {}).get('name', card.get('plant_family'))}")
        if "activated_by" in card:
            typer.echo(f"  activated_by: {card.get('activated_by')}")
        if report is not None:
            typer.echo(format_report(report))
        elif isinstance(card.get("plant_report"), dict) and card["plant_report"].get("pending"):
            typer.echo("  plant quality report: pending (the retraining did not finish)")

    @models_app.command("rollback")
    def rollback_model(registry: Optional[Path] = typer.Option(None, "--registry", help=_REGISTRY_HELP)) -> None:
        """Re-activate the model that was active before the current one."""
        from .registry import Registry, RegistryError

        try:
            v = Registry(registry or default_registry()).rollback()
        except RegistryError as exc:
            _fail(str(exc))
        typer.echo(f"active: {v}")

    @models_app.command("migrate")
    def migrate_models(registry: Optional[Path] = typer.Option(None, "--registry", help=_REGISTRY_HELP)) -> None:
        """Rewrite model files saved before the rotordiag.* rename (type names models.*) to the current names.

        Each rewritten file is checked to predict exactly as the old one before it replaces it; the old
        file is kept as model.skops.pre-rename. Loading works without migrating too (the names are mapped
        in memory); migrating makes the files readable by other tools that use the trusted-types list.
        """
        from .registry import RegistryError, migrate_registry

        root = registry or default_registry()
        if not root.is_dir():
            _fail(f"registry {root} does not exist")
        try:
            done = migrate_registry(root)
        except (RegistryError, ValueError, OSError) as exc:
            _fail(str(exc))
        typer.echo(f"migrated: {', '.join(done)}" if done else "nothing to migrate: every model file uses the current names")

    @app.command()
    def examples(
        names: Optional[list[str]] = typer.Argument(None, help="Examples to copy (default: all of them)."),
        copy_to: Optional[Path] = typer.Option(None, "--copy-to", help="Copy the examples (and their sidecars) "
                                               "into this folder, to try `rotordiag diagnose FOLDER` or upload them."),
    ) -> None:
        """List the example recordings shipped with rotordiag (where they are, what each is), or copy them."""
        from rotordiag.features.examples import (
            copy_examples,
            describe_example,
            example_options,
            example_path,
            list_examples,
        )

        if copy_to is None:
            if names:
                _fail("give --copy-to FOLDER to copy examples; without it every example is listed")
            typer.echo(f"example recordings in {example_path(list_examples()[0]).parent}:")
            for name in list_examples():
                opts = example_options(name)
                typer.echo(f"  {name:<26s} {describe_example(name)}"
                           + (f" (sidecar: {', '.join(f'{k}={v}' for k, v in opts.items())})" if opts else ""))
            typer.echo("try: rotordiag diagnose <folder above>/moderate.csv, or rotordiag examples --copy-to DIR")
            return
        try:
            written = copy_examples(copy_to, names)
        except ValueError as exc:
            _fail(str(exc))
        for path in written:
            typer.echo(str(path))

    @app.command()
    def diagnose(
        files: list[Path] = typer.Argument(..., help="Recordings (.csv, .npy, .h5/.hdf5, .json) or folders of them; "
                                           "'rotordiag examples' lists the shipped ones."),
        registry: Optional[Path] = typer.Option(None, "--registry", help=_REGISTRY_HELP),
        version: Optional[str] = typer.Option(None, "--version", help="Model version (default: the active one)."),
        sidecar: Optional[Path] = typer.Option(None, "--sidecar", help="JSON with the options below by name (default: FILE with .json next to a .csv/.npy/.h5)."),
        sample_rate_hz: Optional[float] = typer.Option(None, "--sample-rate-hz", help="Sample rate, Hz (or a time_s column in the CSV)."),
        units: Optional[str] = typer.Option(None, "--units", help="um | mm | m | mil | V | mV (default: the file's, from its column names, unit row or header; else um). V and mV need --sensitivity."),
        sensitivity: Optional[str] = typer.Option(None, "--sensitivity", help="Probe sensitivity for --units V/mV as the datasheet states it: '7.87 V/mm', '200 mV/mil', '7.87 mV/um' (a bare number is V/mm)."),
        sensitivity_v_per_mm: Optional[float] = typer.Option(None, "--sensitivity-v-per-mm", help="Probe scale factor for --units V/mV, V/mm (7.87 = 200 mV/mil); or --sensitivity."),
        gap_voltage_v: Optional[float] = typer.Option(None, "--gap-voltage-v", help="DC gap voltage for --units V/mV, in V (default: each channel's mean)."),
        channels: Optional[str] = typer.Option(None, "--channels", help="Probe layout in file order, BEARING@ANGLE: '1@45,1@135,2@45,2@135'; or for a CSV/UFF by column name 'GEN DE X=b2@45;GEN DE Y=b2@135' (other columns besides time and keyphasor are not read; a note names them)."),
        keyphasor_channel: Optional[str] = typer.Option(None, "--keyphasor-channel", help="Raw keyphasor pulse channel: CSV column name, or index in file order (default: a CSV column named kp/keyphasor); with --acquisitions, one per acquisition separated by semicolons (kp_a;kp_b)."),
        keyphasor_edge: str = typer.Option("falling", "--keyphasor-edge", help="falling (a notch) | rising (a projection, TTL)."),
        keyphasor_threshold: Optional[float] = typer.Option(None, "--keyphasor-threshold", help="Pulse threshold in the channel's units (default: halfway between its 1st and 99th percentile)."),
        rotation: str = typer.Option("ccw", "--rotation", help="Shaft rotation seen from the driver end: ccw | cw."),
        viewed_from: str = typer.Option("driver", "--viewed-from", help="End the probe angles are measured from: driver | non-driver."),
        speed_rpm: Optional[float] = typer.Option(None, "--speed-rpm", help="Running speed, r/min (estimated from the signal if omitted)."),
        clearance_um: Optional[float] = typer.Option(None, "--clearance-um", help="Radial bearing clearance, µm (gives the offset in µm)."),
        plant_model: Optional[str] = typer.Option(None, "--plant-model", help="The machine's plant model: default (MODEL.md's plant) or a preset (gen50_2pole, gen200_2pole, gen600_2pole, gen600_4pole; train:NAME for its finite-element train). A family the model was not trained on is never given a confident verdict (family_untrained)."),
        speed_range_rpm: Optional[str] = typer.Option(None, "--speed-range-rpm", help="MIN,MAX r/min: the running speed's range when it is not known exactly (the machine's nominal speed, e.g. 2900,3100): the speed estimate is sought only there."),
        sample: Optional[int] = typer.Option(None, "--sample", help="Row of a rotordiag dataset HDF5 file."),
        dc_removed: bool = typer.Option(False, "--dc-removed", help="The channels' DC part is no shaft position (AC-coupled acquisition): the shaft centreline is not read (zero-mean channels and --units V without --gap-voltage-v are read so anyway)."),
        acquisitions: Optional[str] = typer.Option(None, "--acquisitions", help="Groups of bearings sampled together when the channels come from separate acquisitions (takes), e.g. '1,2;3,4': the phase differences between takes are not measured, and with bearings 2 and 3 in different takes the verdict is never confident."),
        takes: bool = typer.Option(False, "--takes", help="The files are the takes of one recording (a portable analyser's, bearing pair by bearing pair, each with its keyphasor or tachometer): merged into one recording with each file's bearings as one acquisition and its keyphasor as that take's, so the phase across the coupling is measured (features.take_files). Each file is read with the options above and its own sidecar."),
        as_json: bool = typer.Option(False, "--json", help="Print the verdict(s) as JSON."),
        out: Optional[Path] = typer.Option(None, "--out", help="Write one table of verdicts, one row per file: .csv or .json."),
        output_units: str = typer.Option("um", "--output-units", help="Units of the offset and amplitudes in the output: um | mil."),
        slow_roll: Optional[Path] = typer.Option(None, "--slow-roll", help="A recording of the same probes at slow roll (<= 20 % of the running speed; keyphasor in both files): its 1X/2X runout vectors are subtracted from every recording's. Read with the options above (not --speed-rpm/--sample) and its own sidecar."),
        slow_roll_sample_rate_hz: Optional[float] = typer.Option(None, "--slow-roll-sample-rate-hz", help="Sample rate of the --slow-roll file, Hz (default: --sample-rate-hz, its sidecar or its time column)."),
        baseline: Optional[Path] = typer.Option(None, "--baseline", help="An asset baseline as JSON (`rotordiag baseline "
                                                "show ASSET --json` or GET /assets/{id}/baseline): also say what "
                                                "changed since it."),
    ) -> None:
        """Diagnose coupling misalignment from one or many recordings (the model is loaded once)."""
        import json

        from rotordiag.core.units import um_to
        from rotordiag.features import parse_speed_range

        from .change import compare, format_change, load_baseline_file
        from .diagnose_files import (
            collect_files,
            diagnose_one,
            diagnose_takes,
            load_options,
            slow_roll_from_file,
            verdict_json,
            verdict_row,
            write_table,
        )
        from .predict import format_verdict, load_bundle
        from .registry import RegistryError

        try:
            um_to(None, output_units)
            if sensitivity is not None and sensitivity_v_per_mm is not None:
                raise ValueError("--sensitivity and --sensitivity-v-per-mm: give the probe sensitivity once")
            paths = collect_files(files)
            if plant_model is not None:
                from .families import machine_family

                machine_family(plant_model)           # refused here, before any file is read
            given = {
                "sample_rate_hz": sample_rate_hz, "units": units,
                "sensitivity_v_per_mm": sensitivity if sensitivity is not None else sensitivity_v_per_mm,
                "gap_voltage_v": gap_voltage_v, "channels": channels, "keyphasor_channel": keyphasor_channel,
                "keyphasor_edge": keyphasor_edge, "keyphasor_threshold_v": keyphasor_threshold,
                "rotation": rotation, "viewed_from": viewed_from, "speed_rpm": speed_rpm,
                "clearance_um": clearance_um, "sample_index": sample, "dc_removed": dc_removed or None,
                "acquisitions": acquisitions,
                "speed_range_rpm": None if speed_range_rpm is None else parse_speed_range(speed_range_rpm,
                                                                                          "--speed-range-rpm"),
            }
            base, rule = load_baseline_file(baseline) if baseline is not None else (None, None)
            runout = None
            if slow_roll is not None:
                slow_given = {**given, "speed_rpm": None, "sample_index": None, "speed_range_rpm": None, "acquisitions": None,
                              "sample_rate_hz": slow_roll_sample_rate_hz or sample_rate_hz}
                runout = slow_roll_from_file(slow_roll, load_options(slow_roll, None, slow_given))
        except ValueError as exc:
            _fail(str(exc))
        loaded: list = []

        def bundle():  # loaded once, after the first file has been read
            if not loaded:
                loaded.append(load_bundle(registry or default_registry(), version))
            return loaded[0]

        rows: list[dict] = []
        full: list[dict] = []
        n_bad = 0
        def one(p: Path) -> tuple:
            return diagnose_one(bundle, p, load_options(p, sidecar, given), runout, plant_model)

        jobs: list[tuple[Path, Callable[[], tuple]]] = (
            [(Path("+".join(str(p) for p in paths)), partial(diagnose_takes, bundle, paths, sidecar, given, runout,
                                                                    plant_model))]
            if takes else [(p, partial(one, p)) for p in paths])
        for path, run in jobs:
            try:
                verdict, res, sig = run()
            except RegistryError as exc:
                _fail(str(exc))
            except ValueError as exc:
                if len(jobs) == 1:
                    _fail(f"{path}: {exc}")
                n_bad += 1
                typer.secho(f"error: {path}: {exc}", fg=typer.colors.RED, err=True)
                rows.append({"file": str(path), "error": str(exc)})
                full.append({"file": str(path), "error": str(exc)})
                continue
            section = compare(sig, base, rule) if rule is not None else None
            rows.append(verdict_row(path, verdict, res, output_units, baseline=section))
            full.append(verdict_json(path, verdict, res, output_units, baseline=section))
            if section is not None:
                rows[-1].update({"baseline_compared": section["compared"], "baseline_changed": section["changed"],
                                 "baseline_exceeded": " ".join(section["exceeded"])})
            if out is None and not as_json:
                if len(jobs) > 1:
                    typer.echo(f"== {path}")
                typer.echo(format_verdict(verdict, output_units, baseline=section))
                if section is not None:
                    typer.echo(format_change(section))
                for note in res.notes:
                    typer.echo(f"note: {note}")
                if res.truth:
                    typer.echo(f"(dataset truth: Δ = {res.truth['misalignment']:.3f})")
        if out is not None:
            try:
                write_table(out, rows)
            except ValueError as exc:
                _fail(str(exc))
            typer.echo(f"wrote {out}: {len(rows)} file(s), {n_bad} could not be read", err=True)
        elif as_json:
            typer.echo(json.dumps(full[0] if len(full) == 1 else full, indent=2))
        if n_bad:
            raise typer.Exit(1)


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
