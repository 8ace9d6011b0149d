"""``generate``: run a dataset spec through the simulator on Dask into one HDF5 file."""
from __future__ import annotations

import datetime as _dt
import json
import math
import time
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .design import Design, SampleParams, build_design
from .measurement import MeasurementSettings
from .spec import ResolvedSpec, load_spec
from .store import (
    FORMAT,
    FORMAT_VERSION,
    MECHANISM_CODES,
    PLANT_SOURCE_LEN,
    SIMULATED_MECHANISM_CODES,
    DatasetWriter,
    layout,
)
from .worker import STATUS_CODES, SampleOutput, SampleTask, SimulationSettings, run_sample_encoded

__all__ = ["GenerateSummary", "generate", "severity_bands"]


def severity_bands():
    """The severity bands of the labels (the models package's definition, one source of truth)."""
    from rotordiag.core.bands import SeverityBands

    return SeverityBands()


@dataclass
class GenerateSummary:
    """What a :func:`generate` call did."""

    path: Path
    n_samples: int
    n_done_before: int
    n_computed: int
    status_counts: dict[str, int] = field(default_factory=dict)
    resumed: bool = False
    repaired: bool = False
    elapsed_s: float = 0.0            # whole call: file, cluster start-up, samples
    first_sample_s: float = math.nan  # from the call's start to the first sample written
    startup_s: float = math.nan       # from the call's start to the first task submitted (spec, file, cluster)

    @property
    def steady_rate_per_s(self) -> float:
        """Samples per second after the first one (excludes cluster start-up and warm-up)."""
        if self.n_computed < 2 or not math.isfinite(self.first_sample_s):
            return math.nan
        return (self.n_computed - 1) / max(self.elapsed_s - self.first_sample_s, 1e-9)

    @property
    def generation_rate_per_s(self) -> float:
        """Samples per second from the first task submitted to the last sample written (no start-up)."""
        if self.n_computed < 1 or not math.isfinite(self.startup_s):
            return math.nan
        return self.n_computed / max(self.elapsed_s - self.startup_s, 1e-9)

    @property
    def complete(self) -> bool:
        return self.n_done_before + self.n_computed == self.n_samples


def _file_attrs(resolved: ResolvedSpec, design: Design, meas: MeasurementSettings) -> dict[str, Any]:
    from rotordiag.core.version import code_version

    bands = severity_bands()
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "spec_toml": resolved.text,
        "spec_json": json.dumps(resolved.spec.model_dump(mode="json")),
        "spec_hash": resolved.spec_hash,
        "code_version": code_version(),
        "created_utc": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "n_samples": design.n_samples,
        "n_channels": len(meas.channels),
        "n_points": meas.n_points,
        "sample_rate_hz": meas.sample_rate_hz,
        "waveform_units": "um",
        "design_method": design.method,
        "master_seed": design.master_seed,
        "base_plant_json": json.dumps(resolved.base_plant.to_dict()),
        "plant_sources_json": json.dumps({k: {"weight": resolved.source_weights[k], "plant": p.to_dict()}
                                          for k, p in resolved.sources.items()}),
        "severity_bands_json": json.dumps(bands.to_dict()),
        "merged": False,
        "sample_kind": "transient" if resolved.spec.is_transient else "steady",
    }


def _dataset_attrs() -> dict[str, dict[str, Any]]:
    bands = severity_bands()
    return {
        "waveforms": {"units": "um", "description": "probe displacement toward the probe, (sample, channel, point)"},
        "done": {"description": "1 when the sample is completely written"},
        "parameters/mechanism": {"codes_json": json.dumps(MECHANISM_CODES)},
        "parameters/simulated_mechanism": {"codes_json": json.dumps(SIMULATED_MECHANISM_CODES)},
        "labels/severity": {"names_json": json.dumps(list(bands.names)), "edges_json": json.dumps(list(bands.edges))},
        "labels/status": {"codes_json": json.dumps(STATUS_CODES)},
        "diagnostics/wall_time_s": {"description": "simulator wall time (not reproducible between runs)"},
        "diagnostics/steady_start": {"description": "how the record started: shooting (on the period-1 orbit) "
                                                    "or integrate (after the transient)"},
        "diagnostics/steady_start_note": {"description": "why integrate when shooting was asked for"},
        "transient/profile_times_s": {"units": "s", "description": "the run's speed profile: times of its points"},
        "transient/profile_speeds_rpm": {"units": "r/min", "description": "the run's speed profile: its speeds "
                                                                          "(straight lines between the points)"},
        "transient/keyphasor_times_s": {"units": "s", "description": "once-per-revolution marks from the record's "
                                                                     "start (shaft angle 0: the generator unbalance "
                                                                     "along +x); NaN past a run that stopped early"},
    }


def _rows(p: SampleParams, out: SampleOutput,
          profile: tuple[tuple[float, ...], tuple[float, ...]] | None = None, n_marks: int = 0) -> dict[str, Any]:
    from rotordiag.simulator import Plant
    from rotordiag.simulator.train.plant import TrainPlant, is_train_plant

    bands = severity_bands()
    rows: dict[str, Any] = {"waveforms": out.waveforms_um}
    for name in ("speed_rpm", "misalignment", "unbalance", "unbalance_phase_rad", "exciter_unbalance",
                 "exciter_unbalance_phase_rad", "offset_angle_rad", "coupling_phase_rad",
                 "angular_misalignment_mrad"):
        rows[f"parameters/{name}"] = getattr(p, name)
    rows["parameters/mechanism"] = MECHANISM_CODES[p.mechanism]
    rows["parameters/simulated_mechanism"] = SIMULATED_MECHANISM_CODES[out.simulated_mechanism]
    rows["parameters/sample_seed"] = np.uint64(p.sample_seed)
    train = is_train_plant(p.plant)
    plant_id = (TrainPlant.from_dict(p.plant) if train else Plant.from_dict(p.plant)).plant_id()
    rows["parameters/plant_id"] = plant_id.encode()
    rows["parameters/plant_source"] = p.plant_source.encode("utf-8", "replace")[:PLANT_SOURCE_LEN]
    rows["parameters/record_revs"] = out.record_revs
    for name, v in p.plant.items():
        if not isinstance(v, dict):  # a train's base shaft line is in the file's plant_sources_json
            rows[f"parameters/plant/{name}"] = v.encode() if isinstance(v, str) else np.asarray(v, dtype=float)
    d = out.draws
    rows["measurement/snr_db"] = d.snr_db
    rows["measurement/start_angle_rad"] = d.start_angle_rad
    rows["measurement/speed_fluctuation_phase_rad"] = d.speed_fluctuation_phase_rad
    rows["measurement/runout_1x_um"] = d.runout_1x_um
    rows["measurement/runout_1x_phase_rad"] = d.runout_1x_phase_rad
    rows["measurement/runout_2x_um"] = d.runout_2x_um
    rows["measurement/runout_2x_phase_rad"] = d.runout_2x_phase_rad
    rows["labels/misalignment"] = p.misalignment
    rows["labels/severity"] = int(bands.index([p.misalignment])[0])
    rows["labels/status"] = STATUS_CODES[out.status]
    rows["labels/motion_kind"] = out.motion_kind.encode()[:16]
    rows["labels/motion_period"] = out.motion_period
    rows["diagnostics/nfev"] = out.nfev
    rows["diagnostics/wall_time_s"] = out.wall_time_s
    rows["diagnostics/message"] = out.message.encode("utf-8", "replace")[:256]
    rows["diagnostics/steady_start"] = out.steady_start.encode()[:16]
    rows["diagnostics/steady_start_note"] = out.steady_note.encode("utf-8", "replace")[:96]
    if train:  # the lumped model's unbalance inputs do not apply: the train's is labels/unbalance_kg_m
        rows["parameters/unbalance"] = rows["parameters/exciter_unbalance"] = math.nan
        rows["labels/offset_um"] = out.offset_um
        rows["labels/unbalance_kg_m"] = out.unbalance_kg_m
        rows["diagnostics/log_decrement"] = out.log_decrement
    if profile is not None:  # a run-up: its profile and keyphasor; the steady angle draws are not used
        rows["measurement/start_angle_rad"] = rows["measurement/speed_fluctuation_phase_rad"] = math.nan
        rows["transient/profile_times_s"] = np.asarray(profile[0], dtype=float)
        rows["transient/profile_speeds_rpm"] = np.asarray(profile[1], dtype=float)
        kp = np.full(n_marks, np.nan)
        got = np.asarray(out.keyphasor_times_s if out.keyphasor_times_s is not None else [], dtype=float)[:n_marks]
        kp[:got.size] = got
        rows["transient/keyphasor_times_s"] = kp
    return rows


def transient_marks(times_s: tuple[float, ...], speeds_rpm: tuple[float, ...], n_points: int,
                    sample_rate_hz: float) -> int:
    """Keyphasor marks in a complete transient record of ``n_points`` (what ``simulate_transient`` keeps)."""
    from rotordiag.simulator.transient import SpeedProfile

    rev_t = SpeedProfile(tuple(times_s), tuple(speeds_rpm)).revolution_times_s()
    return int(np.count_nonzero(rev_t <= (n_points - 1) / sample_rate_hz))


#: Samples are submitted in consecutive blocks of this many (in index order), the slowest of a block first.
ORDER_BLOCK = 64


def submission_order(design: Design, todo: np.ndarray, block: int = ORDER_BLOCK) -> np.ndarray:
    """The unfinished samples ``todo`` in the order they are submitted: expected slowest first, per block.

    A sample's cost rises steeply with speed (above about twice the first critical
    speed the oil film whirls and the integrator takes many more steps: at 2600-3000
    r/min a sample costs up to tens of times a 1500 r/min one), so within each block
    of ``block`` consecutive samples the fastest-running shaft is submitted first. A
    slow sample then starts while plenty of work is left for the other workers,
    instead of being the last one running on a single worker at the end. Blocks keep
    a partly finished file (Ctrl-C) close to a prefix of the design rather than all
    high-speed samples. Values never depend on the order.
    """
    todo = np.asarray(todo, dtype=np.int64)
    if len(todo) == 0:
        return todo
    speed = np.array([design[int(i)].speed_rpm for i in todo])
    key = np.arange(len(todo)) // block
    return todo[np.lexsort((-speed, key))]  # lexsort: last key is the primary one


def generate(
    spec: str | Path | ResolvedSpec,
    out: str | Path,
    *,
    n_workers: int | None = None,
    scheduler_address: str | None = None,
    client: Any = None,
    progress: bool = True,
    connect_timeout_s: float = 30.0,
    on_progress: Callable[[int, int], None] | None = None,
) -> GenerateSummary:
    """Generate (or resume) the dataset of ``spec`` into the HDF5 file ``out``.

    Parameters
    ----------
    spec : path or ResolvedSpec
        The TOML spec (see :mod:`simulator.dataset.spec`).
    out : path
        Output HDF5 file. If it exists and was made from the same spec, only
        the missing samples are computed; a different spec is refused.
    n_workers : int, optional
        Worker processes of the local Dask cluster (default: the CPUs
        available). ``0`` runs the samples serially in this process, without
        Dask (debugging; same values).
    scheduler_address : str, optional
        Use an existing Dask scheduler, e.g. ``"tcp://scheduler:8786"``.
    client : distributed.Client, optional
        Use a client the caller holds (e.g. the service's); it is not closed.
    progress : bool
        Show the progress bar.
    connect_timeout_s : float
        How long to wait for ``scheduler_address`` to answer.
    on_progress : callable, optional
        Called as ``on_progress(n_done, n_samples)`` after each sample is
        written (and once at the start), in this process.

    Returns
    -------
    GenerateSummary

    Raises
    ------
    SpecError, StoreError
        Invalid spec; unusable output file (other spec, locked, not a dataset).
    simulator.runner.TaskError
        A sample's computation raised something other than the simulator's
        input errors; the samples finished so far are kept, rerun to resume.
    """
    given = [k for k, v in (("n_workers", n_workers), ("scheduler_address", scheduler_address),
                            ("client", client)) if v is not None]
    if len(given) > 1:
        raise ValueError(f"give at most one of n_workers, scheduler_address, client (got {', '.join(given)})")
    if n_workers is not None and n_workers < 0:
        raise ValueError(f"n_workers must be >= 0 (0 = serial), got {n_workers}")
    t_start = time.perf_counter()
    resolved = spec if isinstance(spec, ResolvedSpec) else load_spec(spec)
    design = build_design(resolved)
    meas = MeasurementSettings.from_spec(resolved.spec)
    sim = SimulationSettings.from_spec(resolved.spec)
    from rotordiag.core.version import code_version

    angular = resolved.spec.operating.angular_misalignment_mrad != 0.0  # a constant 0 or a range/levels
    shape = None
    if sim.profile is not None:
        shape = (len(sim.profile[0]), transient_marks(*sim.profile, meas.n_points, meas.sample_rate_hz))
    L = layout(len(meas.channels), meas.n_points, len(meas.bearings), resolved.base_plant.to_dict(), angular=angular,
               transient=shape)
    own_client = None
    if scheduler_address is not None:  # connect first: an unreachable scheduler leaves no file behind
        from distributed import Client

        own_client = client = Client(scheduler_address, timeout=connect_timeout_s, set_as_default=False)
        scheduler_address = None
    try:
        return _run(resolved, design, meas, sim, L, out, n_workers, client, progress, on_progress,
                    t_start, code_version())
    finally:
        if own_client is not None:
            own_client.close()


def _run(resolved, design, meas, sim, L, out, n_workers, client, progress, on_progress, t_start,
         version) -> GenerateSummary:
    from rotordiag.simulator.runner import run_tasks

    t_first = math.nan
    t_ready = [math.nan]
    writer = DatasetWriter.open(
        out, n_samples=design.n_samples, spec_hash=resolved.spec_hash, L=L, channels=meas.channels,
        attrs=_file_attrs(resolved, design, meas), dataset_attrs=_dataset_attrs(), code_version=version,
    )
    n_before = int(writer.done.sum())
    todo = np.flatnonzero(~writer.done)
    counts: Counter[str] = Counter()
    try:
        if on_progress is not None:
            on_progress(n_before, design.n_samples)

        def ready() -> None:
            t_ready[0] = time.perf_counter() - t_start

        if len(todo) == 0:
            results: Iterator[tuple[int, SampleOutput]] = iter(())  # nothing to do: start no cluster
        elif n_workers == 0:  # one process: nothing to balance, index order
            ready()
            tasks = (SampleTask(design[int(i)], sim, meas) for i in todo)
            results = ((k, run_sample_encoded(t)) for k, t in enumerate(tasks))
            if progress:
                from tqdm.auto import tqdm

                results = tqdm(results, total=len(todo), desc="samples", unit="sample")
        else:
            tasks = (SampleTask(design[int(i)], sim, meas) for i in submission_order(design, todo))
            results = run_tasks(run_sample_encoded, tasks, n_workers=n_workers, client=client,
                                total=len(todo), progress=progress, desc="samples", unit="sample",
                                on_ready=ready)
        for _, output in results:
            params = design[output.index]
            rows = _rows(params, output, sim.profile, L.get("transient/keyphasor_times_s", ((0,), ""))[0][0])
            writer.write_sample(output.index, {k: v for k, v in rows.items() if k in L})
            counts[output.status] += 1
            if not math.isfinite(t_first):
                t_first = time.perf_counter() - t_start
            if on_progress is not None:
                on_progress(n_before + sum(counts.values()), design.n_samples)
    finally:
        writer.close()
    return GenerateSummary(Path(out), design.n_samples, n_before, int(sum(counts.values())), dict(counts),
                           writer.resumed, writer.repaired, time.perf_counter() - t_start, t_first, t_ready[0])
