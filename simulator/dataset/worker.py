"""The per-sample task run on the Dask workers: simulate, then measure.

:func:`run_sample` takes a :class:`SampleTask` (plain, picklable data) and
returns a :class:`SampleOutput`. It runs in a worker process and never touches
the output file; the parent writes. :func:`run_sample_encoded` (what
``generate`` runs) also puts the waveforms through the file's compression
filters, so the parent only copies the compressed chunk into the file and the
result sent back is smaller.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from rotordiag.simulator.train.plant import TrainPlant, is_train_plant

if TYPE_CHECKING:
    from rotordiag.simulator.train.model import Train
from .design import SampleParams
from .measurement import (
    MeasurementDraws,
    MeasurementSettings,
    draw_measurement,
    probe_waveforms_um,
    required_record_revs,
    transient_probe_waveforms_um,
)
from .store import EncodedChunk, encode_waveform_chunk

__all__ = ["SimulationSettings", "SampleTask", "SampleOutput", "run_sample", "run_sample_encoded", "STATUS_CODES"]

#: Sample status codes stored in ``labels/status``: the simulator's three, plus
#: ``error`` for a sample whose simulation raised ValueError (message in diagnostics/message).
STATUS_CODES: dict[str, int] = {"ok": 0, "contact": 1, "diverged": 2, "error": 3}


@dataclass(frozen=True)
class SimulationSettings:
    transient_revs: int
    samples_per_rev: int
    rtol: float
    atol: float
    record_revs_min: int
    classify_motion: bool
    steady_start: str = "shooting"  # as the spec's default
    transient_stop: str = "fixed"  # likewise
    integrator: str = "auto"  # likewise
    #: a transient spec's speed profile, (times_s, speeds_rpm), and its settling revolutions; None: steady samples
    profile: tuple[tuple[float, ...], tuple[float, ...]] | None = None
    settle_revs: int = 0

    @classmethod
    def from_spec(cls, spec) -> SimulationSettings:
        s = spec.simulation
        tr = spec.transient
        profile = None if tr is None else (tuple(tr.profile.times_s), tuple(tr.profile.speeds_rpm))
        return cls(s.transient_revs, s.samples_per_rev, s.rtol, s.atol, s.record_revs_min, s.classify_motion,
                   s.steady_start, s.transient_stop, s.integrator, profile, 0 if tr is None else tr.settle_revs)


@dataclass(frozen=True)
class SampleTask:
    params: SampleParams
    simulation: SimulationSettings
    measurement: MeasurementSettings


@dataclass
class SampleOutput:
    index: int
    waveforms_um: np.ndarray | EncodedChunk  # (n_channels, n_points) float32, or its file chunk (run_sample_encoded)
    draws: MeasurementDraws
    status: str
    simulated_mechanism: str          # what simulate() ran ("aligned" for Δ = 0)
    record_revs: int
    nfev: int = 0
    wall_time_s: float = 0.0
    motion_kind: str = ""
    motion_period: int = 0
    message: str = ""             # simulator message when status != ok
    steady_start: str = ""        # how the record started: "shooting" or "integrate" ("" for an error sample)
    steady_note: str = ""         # why "integrate" when shooting was asked for
    offset_um: float = math.nan   # a train's offset at the coupling, Δ·c (µm)
    unbalance_kg_m: float = math.nan  # a train's generator unbalance from its balance grade
    log_decrement: float = math.nan   # a train's least-damped mode about its static state at the sample's speed
    keyphasor_times_s: np.ndarray | None = None  # a transient sample's once-per-revolution marks in its record


def _motion(poincare_m: np.ndarray) -> tuple[str, int]:
    """Motion label from the analysis package's classifier (optional hook)."""
    try:
        from rotordiag.simulator.motion import classify_motion
    except ImportError:  # analysis package absent: no motion label
        return "", 0
    pts = poincare_m[np.all(np.isfinite(poincare_m.reshape(len(poincare_m), -1)), axis=1)]
    try:
        mt = classify_motion(pts)
    except ValueError:  # too few Poincaré points for the classifier's tests: say so, don't guess
        return "unresolved", 0
    return mt.kind, int(mt.period or 0)


def run_sample(task: SampleTask) -> SampleOutput:
    """Simulate one sample and apply the measurement model (runs on a worker)."""
    import time

    from rotordiag.simulator import Plant, build_system, simulate
    from rotordiag.simulator.steady.attractor import record_start

    p, sim, meas = task.params, task.simulation, task.measurement
    rng = np.random.default_rng(p.sample_seed)
    draws = draw_measurement(meas, rng)
    if sim.profile is not None:
        return _run_transient_sample(task, draws, rng)
    revs = max(required_record_revs(p.speed_rpm, meas, draws), sim.record_revs_min)
    if is_train_plant(p.plant):
        return _run_train_sample(task, draws, revs, rng)
    try:
        t0 = time.perf_counter()
        plant = Plant.from_dict(p.plant)
        kw = dict(mechanism=p.mechanism, rtol=sim.rtol, atol=sim.atol, unbalance_phase_rad=p.unbalance_phase_rad,
                  exciter_unbalance=p.exciter_unbalance, exciter_unbalance_phase_rad=p.exciter_unbalance_phase_rad,
                  offset_angle_rad=p.offset_angle_rad, coupling_phase_rad=p.coupling_phase_rad,
                  angular_misalignment_mrad=p.angular_misalignment_mrad if p.mechanism in ("offset", "flexible")
                  else 0.0, stiff_solver=sim.integrator == "auto")
        start = record_start(build_system(plant, p.speed_rpm, p.misalignment, p.unbalance, **kw),
                             sim.transient_revs, sim.steady_start, sim.transient_stop)
        res = simulate(plant, p.speed_rpm, p.misalignment, p.unbalance, transient_revs=start.transient_revs,
                       record_revs=revs, samples_per_rev=sim.samples_per_rev,
                       initial_state=None if start.path == "integrate" and start.warmup_revs == 0 else start.state,
                       **kw)  # type: ignore[arg-type]
        wall_s = time.perf_counter() - t0
    except ValueError as exc:  # simulate's documented input error: kept as a labelled sample, not dropped
        msg = f"{type(exc).__name__}: {exc}"
        return SampleOutput(p.index, np.full((len(meas.channels), meas.n_points), np.nan, np.float32), draws,
                            "error", p.mechanism if p.misalignment > 0 else "aligned", revs,
                            message=msg)
    waveforms = probe_waveforms_um(res.journal_displacements_m, sim.samples_per_rev, p.speed_rpm, meas, draws, rng)
    kind, period = ("", 0)
    if sim.classify_motion and res.status == "ok":
        kind, period = _motion(res.poincare_m)
    return SampleOutput(p.index, waveforms, draws, res.status, res.inputs["mechanism"], revs,
                        nfev=int(res.nfev) + start.nfev, wall_time_s=wall_s,
                        motion_kind=kind, motion_period=period,
                        message="" if res.status == "ok" else res.message,
                        steady_start=start.path, steady_note=_stiff_note(start.note, res.inputs.get("stiff_from_rev")))


def sample_train(plant: TrainPlant, p: SampleParams) -> Train:
    """The finite-element train of a train sample: ``plant``'s line with the sample's coupling, the exciter's
    bearings moved by Δ·c and α along ``offset_angle_rad`` (a flexible coupling given the offset's kinematic 2X
    forcing, as ``simulate --train`` does), the generator unbalanced to its balance grade."""
    from rotordiag.simulator.train.model import misaligned
    from rotordiag.simulator.train.recording import with_kinematic_offset
    from rotordiag.simulator.train.shaftline import train_from_shaftline
    from rotordiag.simulator.train.transient import unbalanced

    train = train_from_shaftline(plant.line(coupling=p.mechanism))
    offset_um = p.misalignment * plant.clearance_m * 1e6
    if p.misalignment or p.angular_misalignment_mrad:
        train = misaligned(train, offset_m=offset_um * 1e-6, angle_rad=p.angular_misalignment_mrad * 1e-3,
                           direction_rad=p.offset_angle_rad)
        train = with_kinematic_offset(train, offset_um, math.degrees(p.offset_angle_rad))
    return unbalanced(train, plant.unbalance_kg_m(p.speed_rpm), angle_rad=p.unbalance_phase_rad, replace_own=True)


def _run_train_sample(task: SampleTask, draws: MeasurementDraws, revs: int,
                      rng: np.random.Generator) -> SampleOutput:
    """A shaft train's sample: the plant's line with the sample's coupling, the exciter's bearings moved by
    Δ·c along ``offset_angle_rad`` with the angular offset, the generator unbalanced to its balance grade,
    integrated from its static state (simulator.train); probes and measurement as for the lumped model."""
    import time

    from rotordiag.simulator.train.dynamics import simulate_train
    from rotordiag.simulator.train.stability import stability

    p, sim, meas = task.params, task.simulation, task.measurement
    aligned = p.misalignment == 0 and p.angular_misalignment_mrad == 0
    label = "aligned" if aligned else p.mechanism
    offset_um = math.nan
    try:
        t0 = time.perf_counter()
        plant = TrainPlant.from_dict(p.plant)
        offset_um = p.misalignment * plant.clearance_m * 1e6
        unb = plant.unbalance_kg_m(p.speed_rpm)
        train = sample_train(plant, p)
        log_dec = stability(train, p.speed_rpm).log_decrement  # its static state refuses a journal outside c
        run = simulate_train(train, p.speed_rpm, transient_revs=sim.transient_revs, record_revs=revs,
                             samples_per_rev=sim.samples_per_rev, rtol=sim.rtol)
        wall_s = time.perf_counter() - t0
    except ValueError as exc:  # TrainError and the plant's own checks: a labelled error sample, as for the lumped
        return SampleOutput(p.index, np.full((len(meas.channels), meas.n_points), np.nan, np.float32), draws,
                            "error", label, revs, message=f"{type(exc).__name__}: {exc}", offset_um=offset_um)
    waveforms = probe_waveforms_um(run.journal_m, sim.samples_per_rev, p.speed_rpm, meas, draws, rng)
    kind, period = ("", 0)
    if sim.classify_motion and run.status == "ok":
        poincare = run.journal_m[::sim.samples_per_rev].reshape(-1, 2 * run.journal_m.shape[1])
        kind, period = _motion(poincare)
    message = run.message if run.status != "ok" else ""
    if log_dec <= 0:  # whirl/whip: the record is the self-excited orbit; said with every sample beyond the threshold
        message = "; ".join(filter(None, [f"beyond the stability threshold (log decrement {log_dec:.3f})", message]))
    return SampleOutput(p.index, waveforms, draws, run.status, label, revs, nfev=run.nfev, wall_time_s=wall_s,
                        motion_kind=kind, motion_period=period, message=message, steady_start="integrate",
                        steady_note="shaft train: from its static state", offset_um=offset_um,
                        unbalance_kg_m=unb, log_decrement=log_dec)


def _run_transient_sample(task: SampleTask, draws: MeasurementDraws, rng: np.random.Generator) -> SampleOutput:
    """A run-up or coast-down sample: the paper's model (:class:`~rotordiag.simulator.transient.PlantModel`) or
    the sample's shaft train (:func:`sample_train`, its balance grade taken at the profile's top speed,
    ``p.speed_rpm``) through the spec's profile with :func:`~rotordiag.simulator.transient.simulate_transient`,
    recorded at the acquisition rate; the probes see it with the sample's runout and noise
    (:func:`transient_probe_waveforms_um`), the shaft angle the profile's (0 at each keyphasor mark)."""
    import time

    from rotordiag.simulator import Plant
    from rotordiag.simulator.system import MECHANISM_NAMES, resolve_mechanism
    from rotordiag.simulator.transient import SpeedProfile, simulate_transient

    p, sim, meas = task.params, task.simulation, task.measurement
    assert sim.profile is not None
    profile = SpeedProfile(*sim.profile)
    train = is_train_plant(p.plant)
    angular = p.angular_misalignment_mrad if p.mechanism in ("offset", "flexible") or train else 0.0
    label = "aligned" if p.misalignment == 0 and angular == 0 else p.mechanism
    offset_um = unb = log_dec = math.nan
    try:
        t0 = time.perf_counter()
        if train:
            from rotordiag.simulator.train.stability import stability
            from rotordiag.simulator.train.transient import TrainTransientModel

            tplant = TrainPlant.from_dict(p.plant)
            offset_um = p.misalignment * tplant.clearance_m * 1e6
            unb = tplant.unbalance_kg_m(p.speed_rpm)
            tr = sample_train(tplant, p)
            log_dec = stability(tr, p.speed_rpm).log_decrement  # its static state refuses a journal outside c
            model: Any = TrainTransientModel(tr, rtol=sim.rtol)  # a VariableSpeedModel (structurally)
            res = simulate_transient(model, profile, sample_rate_hz=meas.sample_rate_hz, settle_revs=sim.settle_revs)
        else:
            label = MECHANISM_NAMES[resolve_mechanism(p.mechanism, p.misalignment, angular)]
            res = simulate_transient(
                Plant.from_dict(p.plant), profile, p.misalignment, p.unbalance, sample_rate_hz=meas.sample_rate_hz,
                settle_revs=sim.settle_revs, rtol=sim.rtol, atol=sim.atol, mechanism=p.mechanism,
                unbalance_phase_rad=p.unbalance_phase_rad, exciter_unbalance=p.exciter_unbalance,
                exciter_unbalance_phase_rad=p.exciter_unbalance_phase_rad, offset_angle_rad=p.offset_angle_rad,
                coupling_phase_rad=p.coupling_phase_rad, angular_misalignment_mrad=angular)
        wall_s = time.perf_counter() - t0
    except ValueError as exc:  # the simulators' input errors: a labelled error sample, as for steady ones
        return SampleOutput(p.index, np.full((len(meas.channels), meas.n_points), np.nan, np.float32), draws,
                            "error", label, 0, message=f"{type(exc).__name__}: {exc}", steady_start="transient",
                            offset_um=offset_um, unbalance_kg_m=unb, keyphasor_times_s=np.zeros(0))
    theta = profile.angle_rad(meas.time_s)
    waveforms = transient_probe_waveforms_um(res.journal_displacements_m, theta, meas, draws, rng)
    kp = np.asarray(res.keyphasor_times_s, dtype=float)
    message = res.message if res.status != "ok" else ""
    if train and log_dec <= 0:
        message = "; ".join(filter(None, [f"beyond the stability threshold at the top speed (log decrement "
                                          f"{log_dec:.3f})", message]))
    return SampleOutput(p.index, waveforms, draws, res.status, label, max(int(kp.size) - 1, 0),
                        wall_time_s=wall_s, message=message, steady_start="transient",
                        steady_note=f"settled {sim.settle_revs} revs at {profile.speeds_rpm[0]:g} r/min",
                        offset_um=offset_um, unbalance_kg_m=unb, log_decrement=log_dec, keyphasor_times_s=kp)


def _stiff_note(note: str, stiff_from_rev: float | None) -> str:
    """The steady-start note, with where the run went on with the stiff solver (if it did)."""
    if stiff_from_rev is None:
        return note
    return "; ".join(filter(None, [f"stiff from rev {stiff_from_rev:.0f}", note]))  # first: the column keeps 96 bytes


def run_sample_encoded(task: SampleTask) -> SampleOutput:
    """:func:`run_sample`, with ``waveforms_um`` already encoded as the file's chunk (shuffle + gzip).

    Compressing where the sample is computed spreads that work over the workers
    instead of the one process that writes the file; the values are unchanged
    (``store.decode_waveform_chunk`` gives the float32 array back bit for bit).
    """
    out = run_sample(task)
    assert isinstance(out.waveforms_um, np.ndarray)
    out.waveforms_um = encode_waveform_chunk(out.waveforms_um)
    return out
