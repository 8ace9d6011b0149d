"""What the jobs do: validate requests up front (422 at POST time), then run on Dask.

* ``dataset``: the dataset package's generator writes ``<data_dir>/datasets/<name>.h5``
  (resumable: a resumed job completes only the missing samples).
* ``retrain``: a dataset for the user's plant (plant parameters or a shaft-line
  description, + small perturbations, sweep options), optionally field-labelled recordings, then the
  models package's training entry point, which evaluates and registers a new
  version in the service's registry (activated when asked).
"""
from __future__ import annotations

import math
from typing import Any

from .core.config import Settings
from .errors import InputError

#: Bounds on what one job may ask for, checked at POST time (422) so that an absurd job is never queued
#: (docs/service.md, "Job bounds"): simulated samples, stored points (samples x points per channel, about
#: 8 GiB of float64 over 8 probes), integration steps (samples x (transient revolutions x steps per revolution
#: + points)), and the integers of the training options (iterations, trees, leaves).
MAX_JOB_SAMPLES = 20_000
MAX_JOB_POINTS = 2**27
MAX_JOB_STEPS = 2**34
MAX_TRAINING_INT = 100_000
#: largest magnitude of a number in the training options
MAX_TRAINING_NUMBER = 1e6


def check_job_size(resolved: Any) -> None:
    """Refuse a resolved dataset spec whose work is beyond the job bounds (:data:`MAX_JOB_SAMPLES`, ...).

    Raises
    ------
    InputError
        Naming the quantity, its value and the bound.
    """
    from rotordiag.simulator.dataset.design import build_design
    from rotordiag.simulator.dataset.spec import SpecError

    spec = resolved.spec
    if spec.design.method == "grid":
        try:
            n = build_design(resolved).n_samples
        except SpecError as exc:
            raise InputError(str(exc)) from None
    else:
        n = int(spec.design.n_samples)
    if n > MAX_JOB_SAMPLES:
        raise InputError(f"design: {n} samples; a job may simulate at most {MAX_JOB_SAMPLES} (lower n_samples or the "
                         "grid's levels, or generate larger datasets with the `rotordiag dataset` command)")
    points = spec.n_points
    if n * points > MAX_JOB_POINTS:
        raise InputError(f"measurement: {n} samples x {points} points per channel = {n * points} points; a job may "
                         f"store at most {MAX_JOB_POINTS} (shorten duration_s/duration_revs, lower the sample rate "
                         "or n_samples)")
    # a run-up's settling revolutions stand where a steady sample's transient does
    pre, name = ((spec.transient.settle_revs, "transient.settle_revs") if spec.transient is not None
                 else (spec.simulation.transient_revs, "transient_revs"))
    steps = n * (pre * spec.simulation.samples_per_rev + points)
    if steps > MAX_JOB_STEPS:
        raise InputError(f"simulation: about {steps:.3g} integration steps (samples x ({name} x "
                         f"samples_per_rev + points)); a job may take at most {MAX_JOB_STEPS:.3g} (lower "
                         f"{name}, samples_per_rev or n_samples)")


def _check_training_numbers(value: Any, where: str = "training") -> None:
    """Every number of the training options finite and of a sane size (``max_iter`` = 10^12 is no request)."""
    if isinstance(value, dict):
        for k, v in value.items():
            _check_training_numbers(v, f"{where}.{k}")
    elif isinstance(value, list):
        for i, v in enumerate(value):
            _check_training_numbers(v, f"{where}[{i}]")
    elif isinstance(value, bool) or value is None or isinstance(value, str):
        return
    elif isinstance(value, int):
        if abs(value) > MAX_TRAINING_INT and not where.endswith("seed"):
            raise InputError(f"{where} = {value}: integers of the training options may be at most "
                             f"{MAX_TRAINING_INT} (seeds excepted)")
    elif isinstance(value, float) and not (math.isfinite(value) and abs(value) <= MAX_TRAINING_NUMBER):
        raise InputError(f"{where} = {value!r}: numbers of the training options must be finite and at most "
                         f"{MAX_TRAINING_NUMBER:g} in size")


def _check_plant_types(values: dict[str, Any], base: Any) -> None:
    """Plant values of the type of the plant's own fields: a number for a number (``true`` is not a mass)."""
    defaults = base.to_dict()
    for name, v in values.items():
        d = defaults.get(name)
        if isinstance(d, str):
            if not isinstance(v, str):
                raise InputError(f"plant.{name}: expected a string, got {v!r}")
            continue
        items = v if isinstance(v, list) else [v]
        for x in items:
            if isinstance(x, list):
                items.extend(x)
            elif isinstance(x, bool) or not isinstance(x, (int, float)):
                raise InputError(f"plant.{name}: expected a number (SI units, as the name says), got {x!r}")


#: What a retraining request may set under ``sweep.plant`` (the plant itself comes from ``plant``/``shaftline``).
RETRAIN_SWEEP_PLANT_KEYS = frozenset({"perturb", "scale"})


def _spec_toml_from_dict(spec: dict[str, Any]) -> str:
    import tomli_w

    try:
        return tomli_w.dumps(spec)
    except RecursionError:
        raise InputError("spec: nested too deeply; a spec has a few levels of tables") from None
    except (TypeError, ValueError) as exc:
        raise InputError(f"spec: cannot be written as TOML ({exc}); use objects, numbers, strings and lists") from None


def _validate_spec_text(text: str) -> Any:
    import tomllib

    from rotordiag.simulator.dataset.spec import SpecError, parse_spec

    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"the spec is not valid TOML: {exc}") from None
    except RecursionError:
        raise InputError("the spec is nested too deeply; a spec has a few levels of tables") from None
    plant = raw.get("plant")
    if isinstance(plant, dict):   # checked before anything reads a file
        if "file" in plant:
            raise InputError("plant.file: a spec sent over HTTP cannot name a file on the server; "
                             "give the plant values in plant.set instead")
        if isinstance(plant.get("shaftline"), str) or "shaftlines" in plant:
            key = "plant.shaftlines" if "shaftlines" in plant else "plant.shaftline"
            raise InputError(f"{key}: a spec sent over HTTP cannot name a file on the server; give the "
                             "shaft-line tables themselves in plant.shaftline (or use plant.presets)")
    try:
        resolved = parse_spec(text)
    except SpecError as exc:
        raise InputError(str(exc)) from None
    except (OverflowError, RecursionError):
        raise InputError("the spec holds a number too large to use (e.g. inf or 1e308 where a finite size is "
                         "needed); check the units and sizes") from None
    check_job_size(resolved)
    return resolved


def prepare_dataset_job(body: Any, settings: Settings) -> dict[str, Any]:
    """Validate a POST /datasets body; return the job parameters stored in the database."""
    if (body.spec_toml is None) == (body.spec is None):
        raise InputError("give exactly one of spec_toml (the TOML text) or spec (the same tables as JSON)")
    text = body.spec_toml if body.spec_toml is not None else _spec_toml_from_dict(body.spec)
    resolved = _validate_spec_text(text)
    return {"spec_toml": text, "spec_hash": resolved.spec_hash, "name": body.name}


def _retrain_plant(body: Any) -> Any:
    """The plant of a retrain request (``models.plant_retrain.describe_plant``: its preset or shaft line, rated
    speeds, ``plant`` values checked for type first)."""
    from dataclasses import replace

    from rotordiag.models.plant_retrain import describe_plant

    line = body.shaftline
    if body.shaftline_toml is not None:
        import tomllib

        if body.shaftline is not None:
            raise InputError("shaftline and shaftline_toml: give the shaft line once, as tables or as the file's text")
        try:
            line = tomllib.loads(body.shaftline_toml)
        except tomllib.TOMLDecodeError as exc:
            raise InputError(f"shaftline_toml is not valid TOML: {exc}") from None
        except RecursionError:
            raise InputError("shaftline_toml is nested too deeply; a shaft line has a few levels of tables") from None
    try:
        plain = describe_plant(preset=body.preset, shaftline=line, rated_speed_rpm=body.rated_speed_rpm)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    _check_plant_types(body.plant, plain.base_plant())
    plant = replace(plain, plant_set=dict(body.plant))
    try:
        plant.base_plant()
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(f"plant: {exc}") from None
    return plant


def prepare_retrain_job(body: Any, settings: Settings) -> dict[str, Any]:
    """Validate a POST /models/retrain body (plant, sweep, training options, field data); the dataset spec is
    ``models.plant_retrain.plant_dataset_spec``'s (the plant's tolerances, speeds and probe layout)."""
    from rotordiag.models.plant_retrain import plant_dataset_spec, plant_train_config

    plant = _retrain_plant(body)
    sweep = dict(body.sweep)
    if "plant" in sweep:
        extra = set(sweep["plant"]) - RETRAIN_SWEEP_PLANT_KEYS if isinstance(sweep["plant"], dict) else {"plant"}
        if extra:
            raise InputError(f"sweep.plant: only {' and '.join(sorted(RETRAIN_SWEEP_PLANT_KEYS))} may be given "
                             "here; put plant values in `plant` and a shaft-line description in `shaftline`")
    try:
        spec = plant_dataset_spec(plant, sweep=sweep)
    except (TypeError, ValueError, AttributeError) as exc:
        raise InputError(f"sweep: {exc}") from None
    text = _spec_toml_from_dict(spec)
    resolved = _validate_spec_text(text)
    _check_training_numbers(body.training)
    try:
        train_cfg = plant_train_config(body.training)
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(f"training: {exc}") from None
    field = [r.model_dump(mode="json") for r in body.field_data]
    if field:
        from .parsing import recording_from_model

        for i, rec in enumerate(body.field_data):
            try:
                recording_from_model(rec.recording)
            except ValueError as exc:
                raise InputError(f"field_data[{i}].recording: {exc}") from None
    return {"plant": body.plant, "shaftline": plant.shaftline is not None, "preset": body.preset,
            "plant_description": plant.to_dict(), "spec_toml": text, "spec_hash": resolved.spec_hash,
            "training": train_cfg.to_dict(), "field_data": field, "activate": body.activate, "force": body.force,
            "report_cases": body.report_cases}


# --- execution (inside the job thread) ---------------------------------------------------------

def _progress_cb(ctx, lo: float, hi: float, stage: str):
    def cb(done: int, total: int) -> None:
        frac = done / total if total else 1.0
        ctx.progress(lo + (hi - lo) * frac, stage, f"{stage}: {done}/{total}")
    return cb


def run_dataset(params: dict[str, Any], ctx) -> dict[str, Any]:
    """Generate (or complete) the dataset file of a dataset job (a resumed job computes only missing samples)."""
    out = ctx.settings.datasets_dir / f"{params.get('name') or ctx.job_id}.h5"
    return _generate(params["spec_toml"], out, ctx, 0.0, 1.0)


def _generate(spec_toml: str, out, ctx, lo: float, hi: float) -> dict[str, Any]:
    """Run the dataset package's ``generate`` on the job manager's Dask cluster (resumable)."""
    import dataclasses

    from rotordiag.simulator.dataset.generate import generate
    from rotordiag.simulator.dataset.spec import parse_spec

    resolved = parse_spec(spec_toml)
    n = resolved.spec.design.n_samples
    ctx.progress(lo, "simulating", f"starting {n or 'the grid of'} simulations on Dask")
    out.parent.mkdir(parents=True, exist_ok=True)
    kwargs: dict[str, Any] = {"client": ctx.client(), "progress": False,
                              "on_progress": _progress_cb(ctx, lo, hi, "simulating")}
    summary = generate(resolved, out, **kwargs)
    ctx.progress(hi, "simulating", "dataset complete")
    result = {k: (str(v) if k == "path" else v) for k, v in dataclasses.asdict(summary).items()}
    result["path"] = str(out.resolve())
    result["spec_hash"] = resolved.spec_hash
    result["complete"] = summary.complete
    if summary.complete:
        from rotordiag.simulator.dataset.info import summarize

        result["summary"] = summarize(out)
    if not summary.complete:
        raise RuntimeError(f"dataset {out} is incomplete ({summary.n_done_before + summary.n_computed} of "
                           f"{summary.n_samples} samples); resume the job to finish it")
    return {k: v for k, v in result.items() if _jsonable(v)}


def _jsonable(v: Any) -> bool:
    if isinstance(v, float):
        return math.isfinite(v)
    if isinstance(v, (int, str, bool, type(None))):
        return True
    if isinstance(v, (list, tuple)):
        return all(_jsonable(x) for x in v)
    if isinstance(v, dict):
        return all(isinstance(k, str) and _jsonable(x) for k, x in v.items())
    return False


def run_retrain(params: dict[str, Any], ctx) -> dict[str, Any]:
    """Dataset for the plant (resumable), features, train and register a version (not active, its report
    pending), then the plant's quality report against the active model, and activation only if it is better
    (or forced): ``models.plant_retrain``. Progress is one fraction over the stages weighted by their
    expected time (``models.plant_retrain.StagedProgress``), so that the job's ``eta_s`` is sane.
    """
    from dataclasses import replace

    from rotordiag.models.config import TrainConfig
    from rotordiag.models.dataset import load_feature_table
    from rotordiag.models.plant_retrain import (
        DEFAULT_REPORT_CASES,
        StagedProgress,
        describe_plant,
        pending_card,
        report_and_activate,
        retrain_units,
        stage_seconds,
    )
    from rotordiag.simulator.dataset.spec import parse_spec

    desc = params.get("plant_description") or {}
    plant = replace(describe_plant(shaftline=desc.get("shaftline"), rated_speed_rpm=desc.get("rated_speed_rpm") or None,
                                   plant_set=desc.get("plant_set") or params.get("plant") or {}),
                    name=desc.get("name", "plant"))
    k = int(params.get("report_cases") or DEFAULT_REPORT_CASES)
    n = parse_spec(params["spec_toml"]).spec.design.n_samples or 1
    config = TrainConfig.from_dict(params["training"])
    staged = StagedProgress(retrain_units(plant, n, k, config.augment.copies if config.augment is not None else 0),
                            seconds=stage_seconds(plant))

    def span(stage: str) -> tuple[float, float]:
        return staged.start[stage], staged.start[stage] + staged.share[stage]

    out = ctx.settings.datasets_dir / f"retrain-{ctx.job_id}.h5"
    dataset = _generate(params["spec_toml"], out, ctx, *span("simulating"))
    ctx.progress(span("features")[0], "features", "extracting features")
    table = load_feature_table(out, progress=_progress_cb(ctx, *span("features"), "features"), augment=config.augment)
    field = params.get("field_data") or []
    if field:
        table = _with_field_rows(table, field)
    table, dropped = _drop_unmeasured(table)
    ctx.progress(span("training")[0], "training", f"training on {len(table)} rows (held-out-plant evaluation, then final fit)")
    version = _registered_by(ctx.models.registry, ctx.job_id)
    if version is None:
        # in a child process, so that a cancel or a shutdown stops a fit that has no progress to check
        version = run_in_child(ctx, _train_step, table, params["training"], str(ctx.models.root), False,
                               {"retrain_job": ctx.job_id, "plant_overrides": params.get("plant") or {},
                                "field_records": len(field), "features_never_measured": dropped,
                                **pending_card(plant)})
    else:   # an earlier attempt registered it, then died before recording success: do not train it twice
        ctx.progress(span("training")[1], "training", f"{version} was registered by an earlier attempt of this job")
    compare_with, label = _model_to_beat(ctx)
    report, by = report_and_activate(
        ctx.models.registry, version, plant, compare_with, seed=int(config.seed), n_per_class=k,
        activate=bool(params.get("activate", True)), force=bool(params.get("force")),
        progress=lambda stage, d, t: _progress_cb(ctx, *span(stage), stage)(d, t),
        cache=ctx.settings.datasets_dir, compare_label=label)
    card = ctx.models.registry.card(version)
    return {"version": version, "activated": by is not None, "activated_by": by,
            "better": report["decision"]["better"], "decision": report["decision"],
            "plant_report": {"pooled": report["pooled"], "paired_bootstrap": report["paired_bootstrap"],
                             "file": str((ctx.models.root / version / "plant_report.json").resolve())},
            "metrics": card.get("metrics"),
            "n_rows": len(table), "field_records": len(field), "features_never_measured": dropped,
            "report": str((ctx.models.root / version / "report.json").resolve()), "dataset": dataset}


def _model_to_beat(ctx) -> tuple[Any, str]:
    """The active model (``ModelBundle``) and its label; with none active, the shipped registry's."""
    from rotordiag.models.predict import load_bundle

    from .inference import ModelUnavailable

    try:
        bundle = ctx.models.load(None)
        return bundle, f"{bundle.version} (active)"
    except ModelUnavailable:
        bundle = load_bundle(ctx.settings.shipped_registry_dir)
        return bundle, f"{bundle.version} (the shipped model)"


def _registered_by(registry, job_id: str) -> str | None:
    """The version an earlier attempt of retraining job ``job_id`` registered (a job taken over after its
    holder died between registering and recording success), or None."""
    from rotordiag.models.registry import RegistryError

    for version in reversed(registry.versions()):
        try:
            if registry.card(version).get("retrain_job") == job_id:
                return version
        except RegistryError:
            continue
    return None


def _train_step(table: Any, training: dict[str, Any], registry_root: str, activate: bool,
                card_extra: dict[str, Any]) -> str:
    """Evaluate, fit and register (``models.train.train_and_register``); runs in a child process. The
    registry writes a version into a temporary directory and renames it, so a killed child leaves none."""
    from pathlib import Path

    from rotordiag.models.config import TrainConfig
    from rotordiag.models.registry import Registry
    from rotordiag.models.train import train_and_register

    version, _report = train_and_register(table, TrainConfig.from_dict(training), Registry(Path(registry_root)),
                                          activate=activate, card_extra=card_extra)
    return version


def _child_main(conn: Any, fn: Any, args: tuple) -> None:
    """Body of :func:`run_in_child`'s process: ``("ok", fn(*args))`` or ``("error", message, traceback)``."""
    import traceback

    try:
        answer: tuple = ("ok", fn(*args))
    except BaseException as exc:  # noqa: BLE001 - everything goes back to the job
        answer = ("error", f"{type(exc).__name__}: {exc}", traceback.format_exc())
    conn.send(answer)
    conn.close()


def run_in_child(ctx: Any, fn: Any, *args: Any, poll_s: float = 0.2) -> Any:
    """``fn(*args)`` in a spawned child process that is killed within ``poll_s`` when the job is cancelled or
    the server stops (``ctx.check()`` then raises). ``fn`` and ``args`` must be picklable; an exception in
    the child is raised here as ``RuntimeError`` with its type and message."""
    import multiprocessing

    mp = multiprocessing.get_context("spawn")
    receiver, sender = mp.Pipe(duplex=False)
    proc = mp.Process(target=_child_main, args=(sender, fn, args), name=f"rotordiag-job-{ctx.job_id[:8]}")
    proc.start()
    sender.close()
    remove = ctx.on_stop(lambda: _kill(proc))
    answer: tuple | None = None
    try:
        while answer is None:
            if receiver.poll(poll_s):
                try:
                    answer = receiver.recv()
                except EOFError:       # the child died without answering
                    break
            elif not proc.is_alive() and not receiver.poll(0):
                break
            ctx.check()
    finally:
        remove()
        if answer is None:
            _kill(proc)
        proc.join(10)
        receiver.close()
    ctx.check()
    if answer is None:
        raise RuntimeError(f"the job's child process ended without an answer (exit code {proc.exitcode})")
    if answer[0] == "error":
        import logging

        logging.getLogger("rotordiag.service.jobs").error("job %s: child process failed:\n%s", ctx.job_id, answer[2])
        raise RuntimeError(answer[1])
    return answer[1]


def _kill(proc: Any) -> None:
    """Stop a child process now (SIGTERM, then SIGKILL after 2 s)."""
    if proc.is_alive():
        proc.terminate()
        proc.join(2)
    if proc.is_alive():
        proc.kill()


def _drop_unmeasured(table) -> tuple[Any, list[str]]:
    """``models.plant_retrain.drop_unmeasured`` (columns NaN in every row dropped)."""
    from rotordiag.models.plant_retrain import drop_unmeasured

    return drop_unmeasured(table)


def _with_field_rows(table, field: list[dict[str, Any]]):
    """Append field-labelled recordings (features by name, one extra plant group) to a feature table."""
    import numpy as np

    from rotordiag.features import extract_features
    from rotordiag.models.table import FeatureTable

    from .parsing import recording_from_model
    from .schemas import RecordingIn

    rows, deltas, mechs, speeds = [], [], [], []
    for rec in field:
        fr = extract_features(recording_from_model(RecordingIn.model_validate(rec["recording"])))
        got = fr.as_dict()
        rows.append([got.get(n, np.nan) for n in table.feature_names])
        deltas.append(rec["misalignment"])
        mechs.append(rec.get("mechanism", "rigid"))
        speeds.append(fr.speed_rpm)
    pid = table.plant_id
    field_id = (pid.max() + 1) if np.issubdtype(pid.dtype, np.number) else "field"
    return FeatureTable(
        np.vstack([table.X, np.array(rows, dtype=float)]), table.feature_names,
        np.concatenate([table.misalignment, deltas]),
        np.concatenate([pid, np.full(len(rows), field_id, dtype=pid.dtype)]),
        np.concatenate([table.mechanism, np.array(mechs, dtype=object)]),
        np.concatenate([table.speed_rpm, speeds]),
        np.concatenate([table.sample_index, np.full(len(rows), -1)]),
        {**table.meta, "field_records": len(rows)},
    )


def register_all(manager) -> None:
    """Declare the job kinds on ``manager``."""
    manager.register("dataset", run_dataset)
    manager.register("retrain", run_retrain)
