"""A shaft train's steady recording as its probes read it: the train misaligned by moving the exciter's bearings,
unbalanced, simulated at one speed (:func:`~rotordiag.simulator.train.dynamics.simulate_train`), its probes with
measurement noise, and a keyphasor — what ``rotordiag simulate --train`` writes, in the layout the features read."""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .dynamics import TrainRun, simulate_train
from .model import Train, TrainError, misaligned
from .probes import TrainProbes, train_probes
from .stability import stability
from .static import ClearanceError, static_state
from .transient import unbalanced

__all__ = ["TrainRecording", "largest_offset_scale", "train_recording", "with_kinematic_offset"]


@dataclass(frozen=True)
class TrainRecording:
    """A train's steady recording: its ``probes`` (:class:`~rotordiag.simulator.train.probes.TrainProbes`, noise
    added; µm, DC included, every bearing's 45°/135° pair, the keyphasor times), the ``run`` they come from,
    ``warnings`` for the user (a speed beyond the stability threshold), and the ``inputs`` that made it (for a file's
    metadata and a dataset's parameters)."""

    probes: TrainProbes
    run: TrainRun
    warnings: list[str] = field(default_factory=list)
    inputs: dict[str, Any] = field(default_factory=dict)

    @property
    def time_s(self) -> np.ndarray:
        return np.arange(self.probes.waveforms_um.shape[1]) / self.probes.sample_rate_hz


def train_recording(train: Train, speed_rpm: float, *, offset_um: float = 0.0, angular_mrad: float = 0.0,
                    direction_deg: float = -90.0, unbalance_kg_m: float | None = None, transient_revs: int = 320,
                    record_revs: int = 48, samples_per_rev: int = 128, snr_db: float = 40.0,
                    seed: int = 0, probes: Sequence[tuple[int, float]] | None = None) -> TrainRecording:
    """The steady recording of ``train`` at ``speed_rpm``.

    Parameters
    ----------
    offset_um, angular_mrad, direction_deg
        Parallel offset (µm) and angular offset (mrad) between the shaft lines at the first coupling, both
        along ``direction_deg`` (from +x toward +y; −90 = the exciter low), set by moving the exciter's bearings
        (:func:`~rotordiag.simulator.train.model.misaligned`); a flexible first coupling also gets the parallel
        offset's kinematic 2X forcing (:func:`with_kinematic_offset`).
    unbalance_kg_m
        Unbalance at the middle of the generator, along the keyphasor mark, in place of the train's own (a preset's
        ISO 21940-11 G2.5 residual unbalance); None keeps the train's own.
    probes
        (bearing number, angle_deg) of every probe, bearings numbered 1… along the train; default a 45°/135° pair at
        every bearing. Checked before anything is simulated.
    snr_db
        White measurement noise per probe: its rms is the probe's AC rms over 10^(snr/20) (``inf``: none); drawn
        with ``seed``.

    Raises
    ------
    TrainError
        Bad input, saying what to fix — among them an offset that puts a journal outside its clearance at rest
        (the static state names the bearing).
    """
    if not (math.isfinite(speed_rpm) and speed_rpm > 0):
        raise TrainError(f"speed_rpm must be a positive number of r/min (got {speed_rpm!r})")
    for name, v in (("offset_um", offset_um), ("angular_mrad", angular_mrad), ("direction_deg", direction_deg)):
        if not math.isfinite(v):
            raise TrainError(f"{name} must be a finite number (got {v!r})")
    if not (snr_db > 0 or snr_db == math.inf):
        raise TrainError(f"snr_db must be positive (inf: no noise), got {snr_db!r}")
    n_bearings = len(train.supports())
    if probes is not None:
        probes = [tuple(p) for p in probes]  # type: ignore[misc]
        bad = [p for p in probes if not (len(p) == 2 and isinstance(p[0], int | np.integer)
                                         and 1 <= int(p[0]) <= n_bearings and math.isfinite(float(p[1])))]
        if bad or not probes:
            raise TrainError(f"probes: each is (bearing 1…{n_bearings}, finite angle_deg), at least one; "
                             f"got {bad[0] if bad else 'none'}")
    def moved(scale: float) -> Train:
        return misaligned(train, offset_m=scale * offset_um * 1e-6, angle_rad=scale * angular_mrad * 1e-3,
                          direction_rad=math.radians(direction_deg)) if (offset_um or angular_mrad) else train

    tr = with_kinematic_offset(moved(1.0), offset_um, direction_deg)
    if unbalance_kg_m is not None:
        tr = unbalanced(tr, unbalance_kg_m, replace_own=True)
    warnings = []
    try:
        log_dec = stability(tr, speed_rpm).log_decrement   # its static state refuses a journal pressed on its metal
    except ClearanceError as exc:
        if not (offset_um or angular_mrad):
            raise
        scale = largest_offset_scale(moved, speed_rpm)
        most = " and ".join(([f"an offset of {scale * offset_um:.0f} µm"] if offset_um else [])
                            + ([f"an angle of {scale * angular_mrad:.3g} mrad"] if angular_mrad else []))
        raise ClearanceError(
            f"{exc}. Along {direction_deg:g}° this train takes at most about {most} at {speed_rpm:g} r/min "
            f"({100 * (1 - scale):.0f} % less than asked)", exc.bearing, exc.film_eccentricity, exc.limit) from None
    if log_dec <= 0:
        warnings.append(f"{speed_rpm:g} r/min is beyond this train's stability threshold (least-damped mode's "
                        f"logarithmic decrement {log_dec:.3f} ≤ 0): expect oil whirl or whip, not a forced response")
    run = simulate_train(tr, speed_rpm, transient_revs=transient_revs, record_revs=record_revs,
                         samples_per_rev=samples_per_rev)
    if run.status != "ok":
        raise TrainError(f"the simulation ended as {run.status!r} ({getattr(run, 'message', '')}); nothing recorded")
    read = train_probes(run, probes)
    wave = read.waveforms_um.copy()
    if snr_db != math.inf:
        rng = np.random.default_rng(seed)
        ac_rms = np.sqrt(np.mean((wave - wave.mean(axis=1, keepdims=True)) ** 2, axis=1, keepdims=True))
        wave = wave + rng.standard_normal(wave.shape) * ac_rms / 10 ** (snr_db / 20)
    inputs = {"speed_rpm": float(speed_rpm), "offset_um": float(offset_um), "angular_mrad": float(angular_mrad),
              "direction_deg": float(direction_deg), "unbalance_kg_m": float(sum(u.amount_kg_m for r in tr.rotors for u in r.unbalances)),
              "transient_revs": int(transient_revs), "record_revs": int(record_revs),
              "samples_per_rev": int(samples_per_rev), "snr_db": float(snr_db), "seed": int(seed),
              "log_decrement": log_dec, "probes": [[int(b), float(a)] for b, a in read.channels]}
    return TrainRecording(probes=replace(read, waveforms_um=wave), run=run, warnings=warnings, inputs=inputs)


def with_kinematic_offset(train: Train, offset_um: float, direction_deg: float) -> Train:
    """The train with a flexible first coupling given the double-engagement kinematic 2X forcing of the parallel
    offset ``offset_um`` along ``direction_deg`` (:class:`~rotordiag.simulator.train.model.Coupling`, as
    benchmarks/train_misalignment.py sets it); a rigid coupling or no offset: the train unchanged."""
    if not train.couplings or train.couplings[0].kind != "flexible" or not offset_um:
        return train
    direction = math.radians(direction_deg) + (math.pi if offset_um < 0 else 0.0)
    first = replace(train.couplings[0], kinematic_offset_m=abs(offset_um) * 1e-6, kinematic_direction_rad=direction)
    return replace(train, couplings=(first, *train.couplings[1:]))


def largest_offset_scale(moved, speed_rpm: float, *, tol: float = 0.01) -> float:
    """The largest fraction s in [0, 1] of a misalignment whose static state ``moved(s)`` keeps every journal off
    its metal (:class:`~rotordiag.simulator.train.static.ClearanceError` beyond it), by bisection to ``tol``;
    what a refusal tells the user to reduce the offset to."""
    lo, hi = 0.0, 1.0
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        try:
            static_state(moved(mid), speed_rpm)
            lo = mid
        except ClearanceError:
            hi = mid
    return lo
