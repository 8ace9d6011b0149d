"""The nonlinear analyses of a shaft train: largest Lyapunov exponent and amplitude–speed curves.

Both run the reduced train of :mod:`rotordiag.simulator.train.dynamics` (the time response the simulator
uses: ETDRK4 near the static state, Dormand–Prince where the train whirls) and so see what a simulated
recording would show.

- :func:`train_lyapunov`: Benettin's method (:func:`.lyapunov.largest_lyapunov`) on the once-per-revolution
  map of the reduced state, positions weighted by 1 and velocities by 1/Ω so both count alike.
- :func:`train_speed_sweep`: at each speed the steady response after a transient; per bearing the 1X and 2X
  amplitudes (pk-pk, the larger of the x and y probes', from the record's Fourier bins at the running
  frequency and twice it over whole revolutions) and the once-per-revolution (Poincaré) points.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..train.dynamics import build_kernel, simulate_train
from ..train.fe import Assembly, assemble
from ..train.model import Train, TrainError
from ..train.transient import unbalanced
from .lyapunov import FlowMapError, LyapunovResult, largest_lyapunov
from .lyapunov import _batch_stderr as batch_stderr

__all__ = ["with_unbalance", "train_lyapunov", "TrainSweep", "train_speed_sweep", "MAX_SWEEP_POINTS"]

#: at most this many speeds in one sweep
MAX_SWEEP_POINTS = 200


def with_unbalance(train: Train, amount_kg_m: float, angle_deg: float = 0.0, rotor: int = 0, *,
                   replace_own: bool = False) -> Train:
    """``train`` with an unbalance ``amount_kg_m`` (kg·m) at ``angle_deg`` added to rotor ``rotor``, at the
    station of its heaviest disk or body mass (its mid station when it has none); ``replace_own``: in place of
    the train's own (a preset's residual unbalance; ``simulator.train.transient.unbalanced``)."""
    if amount_kg_m == 0 and not replace_own and 0 <= rotor < len(train.rotors):
        return train
    r = train.rotors[rotor] if 0 <= rotor < len(train.rotors) else None
    station = max(r.disks, key=lambda d: d.mass_kg).station if r is not None and r.disks else None
    return unbalanced(train, amount_kg_m, rotor=rotor, station=station, angle_rad=math.radians(angle_deg),
                      replace_own=replace_own)


def train_lyapunov(train: Train | Assembly, speed_rpm: float, *, n_revs: int = 150, transient_revs: int = 300,
                   align_revs: int = 20, separation: float = 1e-7, seed: int = 0, n_modes: int = 12,
                   progress: Callable[[int], None] | None = None) -> tuple[LyapunovResult, np.ndarray]:
    """Largest Lyapunov exponent (per revolution and per second) of the train at ``speed_rpm`` after
    ``transient_revs`` from the static state; also the state it ends on. ``separation`` is relative to the
    size of the reduced state at the start of the measurement (≫ the integrator's error, ≪ the orbit).
    The first ``align_revs`` revolutions of the perturbation are not averaged: its random start direction
    needs them to turn into the most unstable one (their growth would bias a short average)."""
    if n_revs < 10:
        raise TrainError("n_revs must be ≥ 10")
    asm = train if isinstance(train, Assembly) else assemble(train)
    kern = build_kernel(asm, speed_rpm, n_modes)
    run = simulate_train(kern, speed_rpm, transient_revs=max(transient_revs, 0), record_revs=1, samples_per_rev=8)
    if not run.ok:
        raise TrainError(f"the transient did not reach a steady state at {speed_rpm:g} r/min: {run.status} "
                         f"{run.message}")
    x0 = run.final_state
    n = kern.red.n
    w = kern.speed_rad_s
    weights = np.concatenate([np.ones(n), np.full(n, 1.0 / w)])
    size = float(np.linalg.norm(weights * x0))

    def one_rev(x: np.ndarray) -> np.ndarray:
        r = simulate_train(kern, speed_rpm, transient_revs=0, record_revs=1, samples_per_rev=64, initial=x)
        if not r.ok:
            raise FlowMapError(f"one revolution from the state failed: {r.status}")
        return r.final_state

    if align_revs < 0:
        raise TrainError("align_revs must be ≥ 0")
    res = largest_lyapunov(one_rev, x0, n_intervals=n_revs + align_revs, interval_s=60.0 / speed_rpm,
                           separation=separation * max(size, 1e-12), norm_weights=weights, seed=seed,
                           progress=progress)
    g = res.log_growth[align_revs:]
    lle = float(np.mean(g))
    hist = np.cumsum(g) / np.arange(1, g.size + 1)
    res = replace(res, lle_per_interval=lle, lle_per_s=lle / res.interval_s, history_per_interval=hist, log_growth=g,
                  stderr_per_interval=batch_stderr(g))
    return res, x0


@dataclass(frozen=True)
class TrainSweep:
    """Steady responses of a train over speed.

    Attributes
    ----------
    speeds_rpm : ndarray (n_speeds,)
    bearing_names : list of str
    amp_1x_um_pp, amp_2x_um_pp : ndarray (n_speeds, n_bearings)
        1X and 2X amplitude, µm pk-pk (the larger of the x and y directions).
    poincare_um : ndarray (n_speeds, record_revs, n_bearings, 2)
        Journal position relative to its bearing, once per revolution (t ≡ 0 mod T), µm.
    centre_um : ndarray (n_speeds, n_bearings, 2)
        Mean journal position relative to its bearing over the record (the shaft centreline), µm.
    clearance_um : ndarray (n_bearings,)
        Each bearing's radial clearance, µm.
    status : list of str
        The integrator's status at each speed (``ok`` or why not; NaN rows where not).
    """

    speeds_rpm: np.ndarray
    bearing_names: list
    amp_1x_um_pp: np.ndarray
    amp_2x_um_pp: np.ndarray
    poincare_um: np.ndarray
    centre_um: np.ndarray
    clearance_um: np.ndarray
    status: list


def order_amplitude_pp(signal: np.ndarray, samples_per_rev: int, order: int) -> np.ndarray:
    """Pk-pk amplitude of the ``order``-X component of ``signal`` (samples along axis 0, whole revolutions
    at ``samples_per_rev``): twice the modulus of its Fourier coefficient at ``order`` × running frequency."""
    n = signal.shape[0]
    revs = n // samples_per_rev
    if revs < 1 or revs * samples_per_rev != n:
        raise ValueError("the record must be whole revolutions")
    spec = np.fft.rfft(signal, axis=0)
    return 2 * 2 * np.abs(spec[order * revs]) / n


def train_speed_sweep(train: Train | Assembly, speeds_rpm: Sequence[float] | np.ndarray, *, transient_revs: int = 320,
                      record_revs: int = 32, samples_per_rev: int = 64, n_modes: int = 12,
                      progress: Callable[[int], None] | None = None) -> TrainSweep:
    """The train's steady response at each of ``speeds_rpm`` (each from its static state)."""
    sp = np.asarray(speeds_rpm, dtype=float)
    if sp.ndim != 1 or not 1 <= sp.size <= MAX_SWEEP_POINTS:
        raise TrainError(f"give 1 to {MAX_SWEEP_POINTS} speeds")
    if not np.all(np.isfinite(sp)) or np.any(sp <= 0):
        raise TrainError("speeds must be positive r/min")
    if record_revs < 2 or samples_per_rev < 8:
        raise TrainError("record_revs ≥ 2 and samples_per_rev ≥ 8 are needed")
    asm = train if isinstance(train, Assembly) else assemble(train)
    nb = len(asm.support_nodes)
    a1 = np.full((sp.size, nb), np.nan)
    a2 = np.full((sp.size, nb), np.nan)
    pc = np.full((sp.size, record_revs, nb, 2), np.nan)
    cen = np.full((sp.size, nb, 2), np.nan)
    clear = np.full(nb, np.nan)
    status: list[str] = []
    names: list = []
    for i, s in enumerate(sp):
        run = simulate_train(asm, float(s), transient_revs=transient_revs, record_revs=record_revs,
                             samples_per_rev=samples_per_rev, n_modes=n_modes)
        names = list(run.bearing_names)
        status.append(run.status if run.ok else f"{run.status}: {run.message}")
        if run.ok:
            j = run.journal_m * 1e6  # (n, nb, 2) µm
            a1[i] = order_amplitude_pp(j, samples_per_rev, 1).max(axis=-1)
            a2[i] = order_amplitude_pp(j, samples_per_rev, 2).max(axis=-1)
            pc[i] = j[::samples_per_rev]
            cen[i] = j.mean(axis=0)
        clear = np.asarray(run.clearance_m, dtype=float) * 1e6
        if progress is not None:
            progress(1)
    return TrainSweep(sp, names, a1, a2, pc, cen, clear, status)


def half_power_band(speeds_rpm: np.ndarray, amp: np.ndarray) -> tuple[float, float, float]:
    """(peak speed, lower, upper half-power speed) of an amplitude–speed curve: where it is above
    peak/√2 around its largest value (linear interpolation between grid speeds)."""
    k = int(np.nanargmax(amp))
    level = amp[k] / math.sqrt(2)
    lo = speeds_rpm[0]
    for j in range(k, 0, -1):
        if amp[j - 1] < level:
            lo = speeds_rpm[j - 1] + (level - amp[j - 1]) / (amp[j] - amp[j - 1]) * (speeds_rpm[j] - speeds_rpm[j - 1])
            break
    hi = speeds_rpm[-1]
    for j in range(k, len(amp) - 1):
        if amp[j + 1] < level:
            hi = speeds_rpm[j] + (amp[j] - level) / (amp[j] - amp[j + 1]) * (speeds_rpm[j + 1] - speeds_rpm[j])
            break
    return float(speeds_rpm[k]), float(lo), float(hi)
