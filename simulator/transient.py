"""Run-ups and coast-downs: the rotor through a speed profile (issue 46).

The kernels are written in τ = Ωt at one constant Ω (``simulator._kernels``). A variable-speed run is
integrated **revolution by revolution**: revolution k spans the times t_k → t_{k+1} at which the profile's
shaft angle θ(t) = ∫Ω dt reaches 2πk and 2π(k+1), and is integrated at the constant speed
Ω_k = 2π / (t_{k+1} − t_k) (the revolution's mean speed). Between revolutions the parameters are re-packed at
the new speed and the non-dimensional velocities rescaled by Ω_k / Ω_{k+1}, so the dimensional state (positions
and velocities, m and m/s) is continuous; τ runs on, so the shaft angle at every revolution boundary is the
profile's exactly and the once-per-revolution mark (the keyphasor, τ ≡ 0 mod 2π: the generator unbalance points
along +x) falls at t_k. What this leaves out is the tangential unbalance force of the angular acceleration,
m·a·dΩ/dt against the centripetal m·a·Ω²: (dΩ/dt)/Ω² is 0.047 at 100 r/min and below 0.005 from 300 r/min up on a
0 → 3000 r/min in 60 s run-up.

The run starts settled: ``settle_revs`` revolutions at the profile's first speed (the steady simulator's
transient) before the profile's t = 0.

A shaft-train model plugs in through :class:`VariableSpeedModel`: anything that gives a flow map in τ at a
speed (``at_speed``), the indices of its velocity coordinates, and the probe-plane displacements of a state.
:class:`PlantModel` is the paper's 11-DOF rotor behind that interface; :func:`simulate_transient` uses nothing
else of it.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from rotordiag.core.conventions import project_on_probe
from rotordiag.core.numerics import DEFAULT_ATOL, DEFAULT_RTOL

from . import _kernels as K
from .params import SPEED_RANGE_RPM, Plant
from .system import TWO_PI, RotorSystem, pack_parameters

__all__ = ["SpeedProfile", "VariableSpeedModel", "PlantModel", "TransientResult", "simulate_transient",
           "MAX_PROFILE_DURATION_S", "MAX_PROFILE_REVS", "DEFAULT_CHANNELS"]

#: Longest profile simulated (s) and most revolutions: a bound on the work one call may ask for.
MAX_PROFILE_DURATION_S = 600.0
MAX_PROFILE_REVS = 50_000
#: The dataset's probe layout: bearings 1–4 at 45° and 135°.
DEFAULT_CHANNELS: tuple[tuple[int, float], ...] = tuple((b, a) for b in (1, 2, 3, 4) for a in (45.0, 135.0))


@dataclass(frozen=True)
class SpeedProfile:
    """Running speed against time: straight lines between the points of a table.

    Build with :meth:`linear` (two points) or :meth:`table`; :meth:`parse` reads the CLI / spec text. The speed
    must stay inside the model's range (``SPEED_RANGE_RPM``: the short-bearing model is not defined at rest, so a
    start-up starts at a slow roll, e.g. 100 r/min) and must not reverse (a run-up only rises or holds, a
    coast-down only falls or holds).
    """

    times_s: tuple[float, ...]
    speeds_rpm: tuple[float, ...]

    def __post_init__(self) -> None:
        t = np.asarray(self.times_s, dtype=float)
        n = np.asarray(self.speeds_rpm, dtype=float)
        if t.ndim != 1 or t.shape != n.shape or t.size < 2:
            raise ValueError("speed profile: give at least two (time_s, speed_rpm) points, as many times as speeds")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(n))):
            raise ValueError("speed profile: times and speeds must be finite numbers")
        if t[0] != 0.0:
            raise ValueError(f"speed profile: the first time must be 0 s, got {t[0]:g} s")
        dt = np.diff(t)
        if np.any(dt <= 0):
            i = int(np.argmax(dt <= 0))
            raise ValueError(f"speed profile: times must increase; {t[i + 1]:g} s follows {t[i]:g} s")
        lo, hi = SPEED_RANGE_RPM
        bad = np.flatnonzero((n < lo) | (n > hi))
        if bad.size:
            raise ValueError(f"speed profile: {n[bad[0]]:g} r/min at t = {t[bad[0]]:g} s is outside the model's "
                             f"range {lo:g}–{hi:g} r/min (the bearing model is not defined at rest: start a start-up "
                             f"at a slow roll of at least {lo:g} r/min)")
        dn = np.diff(n)
        if np.all(dn == 0):
            raise ValueError("speed profile: the speed never changes; use `simulate` for a steady run")
        rising = dn[dn != 0][0] > 0
        wrong = np.flatnonzero(dn < 0) if rising else np.flatnonzero(dn > 0)
        if wrong.size:
            i = int(wrong[0])
            raise ValueError(f"speed profile reverses at t = {t[i]:g} s: a {'run-up' if rising else 'coast-down'} "
                             f"goes {'down' if rising else 'up'} from {n[i]:g} to {n[i + 1]:g} r/min; split it into a "
                             "run-up and a coast-down")
        if t[-1] > MAX_PROFILE_DURATION_S:
            raise ValueError(f"speed profile: {t[-1]:g} s is longer than the {MAX_PROFILE_DURATION_S:g} s simulated")
        revs = self.angle_rad(np.array([t[-1]]))[0] / TWO_PI
        if revs > MAX_PROFILE_REVS:
            raise ValueError(f"speed profile: {revs:.0f} revolutions, more than the {MAX_PROFILE_REVS} simulated")
        if revs < 2:
            raise ValueError(f"speed profile: {revs:.2f} revolutions; it must last at least two")

    # ---------------------------------------------------------------- constructors
    @classmethod
    def linear(cls, start_rpm: float, end_rpm: float, duration_s: float) -> SpeedProfile:
        """A constant-rate ramp from ``start_rpm`` to ``end_rpm`` in ``duration_s``."""
        return cls((0.0, float(duration_s)), (float(start_rpm), float(end_rpm)))

    @classmethod
    def table(cls, times_s: Any, speeds_rpm: Any) -> SpeedProfile:
        """Straight lines between the points (``times_s`` from 0, increasing)."""
        try:
            t = tuple(float(v) for v in times_s)
            n = tuple(float(v) for v in speeds_rpm)
        except (TypeError, ValueError):
            raise ValueError("speed profile: times_s and speeds_rpm must be sequences of numbers") from None
        return cls(t, n)

    @classmethod
    def parse(cls, text: str) -> SpeedProfile:
        """``"100:3000:60"`` (start r/min : end r/min : duration s, a linear ramp) or a table
        ``"0@100,20@1500,60@3000"`` (time_s@speed_rpm points)."""
        s = str(text).strip()
        try:
            if "@" in s:
                pts = [p.split("@") for p in s.split(",") if p.strip()]
                if any(len(p) != 2 for p in pts):
                    raise ValueError
                return cls.table([p[0] for p in pts], [p[1] for p in pts])
            parts = s.split(":")
            if len(parts) != 3:
                raise ValueError
            return cls.linear(float(parts[0]), float(parts[1]), float(parts[2]))
        except ValueError as exc:
            if str(exc).startswith("speed profile"):
                raise
            raise ValueError(f"speed profile {text!r}: write START:END:DURATION (r/min, r/min, s), e.g. "
                             "'100:3000:60', or time@speed points, e.g. '0@100,20@1500,60@3000'") from None

    # ---------------------------------------------------------------- evaluation
    @property
    def duration_s(self) -> float:
        return float(self.times_s[-1])

    @property
    def kind(self) -> str:
        """``"run-up"`` or ``"coast-down"``."""
        return "run-up" if self.speeds_rpm[-1] > self.speeds_rpm[0] else "coast-down"

    def speed_rpm(self, time_s: np.ndarray) -> np.ndarray:
        """Speed at the given times (r/min)."""
        return np.interp(np.asarray(time_s, dtype=float), self.times_s, self.speeds_rpm)

    def angle_rad(self, time_s: np.ndarray) -> np.ndarray:
        """Shaft angle ∫Ω dt from t = 0 (rad): exact for the straight lines."""
        t = np.clip(np.asarray(time_s, dtype=float), 0.0, self.duration_s)
        tt = np.asarray(self.times_s)
        nn = np.asarray(self.speeds_rpm) * (TWO_PI / 60.0)  # rad/s
        seg_angle = np.concatenate([[0.0], np.cumsum(0.5 * (nn[1:] + nn[:-1]) * np.diff(tt))])
        i = np.clip(np.searchsorted(tt, t, side="right") - 1, 0, tt.size - 2)
        s = t - tt[i]
        a = (nn[i + 1] - nn[i]) / (tt[i + 1] - tt[i])
        return seg_angle[i] + nn[i] * s + 0.5 * a * s * s

    def revolution_times_s(self) -> np.ndarray:
        """Times at which θ(t) = 2πk, k = 0, 1, …, up to the profile's end (exact roots of the quadratics)."""
        tt = np.asarray(self.times_s)
        nn = np.asarray(self.speeds_rpm) * (TWO_PI / 60.0)
        seg_angle = np.concatenate([[0.0], np.cumsum(0.5 * (nn[1:] + nn[:-1]) * np.diff(tt))])
        k = np.arange(int(math.floor(seg_angle[-1] / TWO_PI + 1e-12)) + 1)
        target = TWO_PI * k
        i = np.clip(np.searchsorted(seg_angle, target, side="right") - 1, 0, tt.size - 2)
        d = target - seg_angle[i]
        a = (nn[i + 1] - nn[i]) / (tt[i + 1] - tt[i])
        w = nn[i]
        # 0.5·a·s² + w·s − d = 0 with w > 0: the stable root 2d / (w + √(w² + 2ad))
        s = 2.0 * d / (w + np.sqrt(np.maximum(w * w + 2.0 * a * d, 0.0)))
        return tt[i] + s


class VariableSpeedModel(Protocol):
    """What :func:`simulate_transient` needs of a rotor model (the paper's plant: :class:`PlantModel`; a shaft
    train supplies its own): a flow map in τ at one speed, its velocity coordinates, and what the probes see."""

    n_state: int
    clearance_m: float

    def at_speed(self, speed_rpm: float) -> RotorSystem: ...

    def velocity_indices(self) -> np.ndarray: ...

    def journal_displacements_m(self, system: RotorSystem, tau: np.ndarray, states: np.ndarray) -> np.ndarray: ...


class PlantModel:
    """The paper's 11-DOF generator–exciter rotor (MODEL.md) as a :class:`VariableSpeedModel`.

    The keyword arguments are :class:`RotorSystem`'s (misalignment, unbalance, mechanism, phases, tolerances);
    one system is built and its parameter vector re-packed at each new speed.
    """

    def __init__(self, plant: Plant, misalignment: float, unbalance: float, **kwargs: Any) -> None:
        self.plant = plant
        self._kwargs = dict(kwargs)
        self._pack = {k: v for k, v in kwargs.items() if k not in ("rtol", "atol", "stiff_solver")}
        self.misalignment = float(misalignment)
        self.unbalance = float(unbalance)
        self._system: RotorSystem | None = None
        self.clearance_m = plant.clearance_m
        self.n_state = K.N_STATE

    def at_speed(self, speed_rpm: float) -> RotorSystem:
        if self._system is None:
            self._system = RotorSystem(self.plant, speed_rpm, self.misalignment, self.unbalance, **self._kwargs)
            self.n_state = self._system.n_state
            return self._system
        s = self._system
        s.params = pack_parameters(self.plant, speed_rpm, self.misalignment, self.unbalance, **self._pack)
        s.speed_rpm = float(speed_rpm)
        s.speed_rad_s = math.pi * float(speed_rpm) / 30.0
        return s

    def velocity_indices(self) -> np.ndarray:
        s = self._system
        idx = list(range(11, 21))
        if s is not None and s.mechanism_code == K.MECH_PIN:
            idx.append(21)  # φ' of the pin coupling is a dynamic variable; rigid's φ' ≡ 1 follows τ
        if s is not None and s.mechanism_code == K.MECH_FLEXIBLE:
            idx += [24, 25]
        return np.asarray(idx)

    def journal_displacements_m(self, system: RotorSystem, tau: np.ndarray, states: np.ndarray) -> np.ndarray:
        from .params import JOURNAL_NODES

        pos = system.node_positions(tau, states)
        return pos[:, [n - 1 for n in JOURNAL_NODES], :] - system.bearing_centres_m[None]


@dataclass
class TransientResult:
    """Output of :func:`simulate_transient`.

    Attributes
    ----------
    time_s : ndarray, shape (n,)
        Sample times from the profile's start (uniform at ``sample_rate_hz``).
    speed_rpm : ndarray, shape (n,)
        The profile's speed at the samples.
    journal_displacements_m : ndarray, shape (n, n_bearings, 2)
        Journals of bearings 1..4 (a train: all its bearings) relative to their bearing centres (x horizontal, y vertical up): what a DC-coupled
        probe pair sees, static position included.
    keyphasor_times_s : ndarray
        Once-per-revolution mark (τ ≡ 0 mod 2π: the generator unbalance along +x) inside the record.
    status, message : str
        As :class:`SimulationResult`; after contact or divergence the arrays end there.
    """

    time_s: np.ndarray
    speed_rpm: np.ndarray
    journal_displacements_m: np.ndarray
    keyphasor_times_s: np.ndarray
    sample_rate_hz: float
    status: str
    message: str
    clearance_m: float
    profile: SpeedProfile
    wall_time_s: float
    inputs: dict[str, Any] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def probe_waveforms_um(self, channels: tuple[tuple[int, float], ...] = DEFAULT_CHANNELS, *,
                           snr_db: float = math.inf, seed: int = 0) -> np.ndarray:
        """Probe signals (µm, shape (n_channels, n)): each probe at (bearing, angle_deg) reads x cos α + y sin α
        (``rotordiag.core.conventions.project_on_probe``), DC kept; white noise at ``snr_db`` of each channel's
        AC power over the whole run, drawn from ``seed``."""
        d = self.journal_displacements_m * 1e6
        out = np.empty((len(channels), d.shape[0]))
        for c, (b, angle) in enumerate(channels):
            if not 1 <= int(b) <= d.shape[1]:
                raise ValueError(f"channels: bearing must be 1–{d.shape[1]}, got {b!r}")
            out[c] = project_on_probe(d[:, int(b) - 1, 0], d[:, int(b) - 1, 1], float(angle))
        if math.isfinite(snr_db):
            rng = np.random.default_rng(seed)
            sigma = np.sqrt(out.var(axis=1) / 10.0 ** (snr_db / 10.0))
            out += rng.standard_normal(out.shape) * sigma[:, None]
        return out

    def keyphasor_signal(self, notch_fraction: float = 0.1) -> np.ndarray:
        """A keyphasor probe's signal (0 with a −1 notch at each mark lasting ``notch_fraction`` of a revolution),
        its falling edges ramped over two samples so that a halfway-threshold crossing interpolates to the mark's
        exact time (what ``features.reader.keyphasor_times_from_pulses`` reads)."""
        return keyphasor_pulse_signal(self.time_s, self.sample_rate_hz, self.keyphasor_times_s, notch_fraction)


def keyphasor_pulse_signal(time_s: np.ndarray, sample_rate_hz: float, keyphasor_times_s: np.ndarray,
                           notch_fraction: float = 0.1) -> np.ndarray:
    """A keyphasor probe's signal at the sample times ``time_s``: 0 with a −1 notch at each mark of
    ``keyphasor_times_s`` lasting ``notch_fraction`` of a revolution, its falling edges ramped over two samples so
    that a halfway-threshold crossing interpolates to the mark's exact time (what
    ``features.reader.keyphasor_times_from_pulses`` reads)."""
    t = np.asarray(time_s, dtype=float)
    fs = float(sample_rate_hz)
    kp = np.asarray(keyphasor_times_s, dtype=float)
    if kp.size == 0:
        return np.zeros(t.size)
    periods = np.diff(kp, append=kp[-1] + (kp[-1] - kp[-2] if kp.size > 1 else 1.0))
    k = np.searchsorted(kp, t + 1.0 / fs, side="right") - 1  # the mark at or just after each sample
    valid = k >= 0
    k = np.clip(k, 0, kp.size - 1)
    since = t - kp[k]
    edge = np.clip(0.5 * since * fs + 0.5, 0.0, 1.0)  # linear over the two samples around the mark
    return -np.where(valid & (since < notch_fraction * periods[k]), edge, 0.0)


def simulate_transient(
    plant: Plant | VariableSpeedModel,
    profile: SpeedProfile,
    misalignment: float = 0.0,
    unbalance: float = 0.05,
    *,
    sample_rate_hz: float = 2560.0,
    settle_revs: int = 200,
    rtol: float = DEFAULT_RTOL,
    atol: float = DEFAULT_ATOL,
    **kwargs: Any,
) -> TransientResult:
    """Simulate a run-up or coast-down along ``profile`` and record the journals at ``sample_rate_hz``.

    Parameters
    ----------
    plant : Plant or VariableSpeedModel
        The paper's plant (with ``misalignment``, ``unbalance`` and ``kwargs`` as for
        :func:`rotordiag.simulator.simulate`: ``mechanism``, ``unbalance_phase_rad``, ``exciter_unbalance``, …),
        or a model already built behind :class:`VariableSpeedModel` (then those are ignored).
    profile : SpeedProfile
    sample_rate_hz : float
        Uniform acquisition rate, at least 8 samples per revolution at the top speed.
    settle_revs : int
        Revolutions at the first speed before t = 0 (the start is settled).

    Returns
    -------
    TransientResult

    Raises
    ------
    ValueError
        Inputs outside their ranges, with the parameter named.
    """
    start = time.perf_counter()
    if not isinstance(profile, SpeedProfile):
        raise ValueError(f"profile must be a SpeedProfile, got {type(profile).__name__}")
    fs = float(sample_rate_hz)
    top_hz = max(profile.speeds_rpm) / 60.0
    if not (math.isfinite(fs) and 8.0 * top_hz <= fs <= 1.0e6):
        raise ValueError(f"sample_rate_hz must be in [{8 * top_hz:.1f}, 1e6] Hz (8 samples per revolution at "
                         f"{max(profile.speeds_rpm):g} r/min), got {sample_rate_hz!r}")
    settle_revs = int(settle_revs)
    if not 0 <= settle_revs <= 5000:
        raise ValueError(f"settle_revs must be in [0, 5000], got {settle_revs!r}")
    if isinstance(plant, Plant):
        model: VariableSpeedModel = PlantModel(plant, misalignment, unbalance, rtol=rtol, atol=atol, **kwargs)
    else:
        model = plant
    rev_t = profile.revolution_times_s()
    n_total = int(math.floor(rev_t[-1] * fs)) + 1  # samples up to the last whole revolution
    if n_total * 8 * 8 > 2**31:
        raise ValueError(f"{n_total} samples: lower sample_rate_hz or shorten the profile")

    system = model.at_speed(profile.speeds_rpm[0])
    vel = model.velocity_indices()
    y = system.initial_state()
    tau = 0.0
    status = "ok"
    if settle_revs:
        y, _, _, st, _, _ = system.integrate(y, 0.0, TWO_PI * settle_revs)
        tau, status = TWO_PI * settle_revs, st.status
    tau_zero = tau
    states = np.full((n_total, model.n_state), np.nan)
    taus = np.full(n_total, np.nan)
    n_done = 0
    w_prev = system.speed_rad_s
    stop_t = math.nan
    for k in range(rev_t.size - 1 if status == "ok" else 0):
        t0, t1 = rev_t[k], rev_t[k + 1]
        w = TWO_PI / (t1 - t0)
        system = model.at_speed(w * 30.0 / math.pi)
        y = y.copy()
        y[vel] *= w_prev / w
        w_prev = w
        j0 = n_done
        j1 = min(n_total, int(math.ceil(t1 * fs - 1e-9)))
        g_t0 = tau + w * (j0 / fs - t0)
        y, grid, _, st, ng, _ = system.integrate(y, tau, tau + TWO_PI, grid_t0=g_t0, grid_dt=w / fs,
                                                 n_grid=j1 - j0)
        states[j0:j0 + ng] = grid[:ng]
        taus[j0:j0 + ng] = g_t0 + (w / fs) * np.arange(ng)
        n_done = j0 + ng
        if st.status != "ok":
            status = st.status
            stop_t = t0 + (st.tau - tau) / w
            break
        tau += TWO_PI
    n = n_done
    t = np.arange(n) / fs
    disp = model.journal_displacements_m(system, taus[:n], states[:n]) if n else np.zeros((0, 4, 2))
    kp = rev_t[rev_t <= (t[-1] if n else -1.0)]
    if status == "ok":
        message = "completed"
    else:
        what = "a journal reached its bushing" if status == "contact" else "the integration diverged"
        message = (f"{what} at t = {stop_t:.3f} s ({float(profile.speed_rpm(np.array([stop_t]))[0]):.0f} r/min); "
                   "samples up to that point are kept")
    own = isinstance(plant, Plant)  # a model built behind VariableSpeedModel describes itself (or not at all)
    inputs = dict(profile={"times_s": list(profile.times_s), "speeds_rpm": list(profile.speeds_rpm)},
                  misalignment=float(misalignment) if own else None, unbalance=float(unbalance) if own else None,
                  model=None if own or not hasattr(model, "describe") else model.describe(), sample_rate_hz=fs,
                  settle_revs=settle_revs, rtol=rtol, atol=atol, tau_at_t0=tau_zero,
                  plant=plant.to_dict() if isinstance(plant, Plant) else None,
                  **{k: (float(v) if isinstance(v, (int, float)) else v) for k, v in kwargs.items()})
    return TransientResult(time_s=t, speed_rpm=profile.speed_rpm(t), journal_displacements_m=disp,
                           keyphasor_times_s=kp, sample_rate_hz=fs, status=status, message=message,
                           clearance_m=model.clearance_m, profile=profile,
                           wall_time_s=time.perf_counter() - start, inputs=inputs)
