"""Measurement model: simulated journal displacements → proximity-probe waveforms in µm.

What a sample's probes record (all draws from the sample's own seed):

1. **Shaft angle with speed fluctuation.** The simulator runs at constant Ω.
   The recorded shaft angle is
   ``θ(t) = θ0 + Ω t + (Ω ε / 2π f_m) [cos φ_m − cos(2π f_m t + φ_m)]``,
   i.e. ``Ω(t) = Ω (1 + ε sin(2π f_m t + φ_m))`` with ``ε = speed_fluctuation``,
   ``f_m = speed_fluctuation_hz``, ``φ_m`` and the start angle ``θ0`` uniform in
   [0, 2π). The simulated response, sampled at τ = Ωt on the simulator's
   uniform grid (``samples_per_rev`` per revolution), is read at τ = θ(t) by
   cubic-spline interpolation: the response follows the shaft angle
   (quasi-static in the slow, small fluctuation) and ``t = k / sample_rate_hz``
   is a fixed-rate acquisition clock. With ε = 0 this is a plain resampling.
2. **Projection onto the probe axis.** A probe at angle α (degrees
   counter-clockwise from +x horizontal; 90 = top) reads
   ``d = x cos α + y sin α``: displacement *toward* the probe is positive
   (API 670). Displacements are relative to the bearing centre, so the static
   journal position (DC) is kept.
3. **Mechanical / electrical runout** at 1X and 2X, fixed to the shaft surface.
   Bearing b's surface profile is ``R_b(ψ) = a1 cos(ψ − p1) + a2 cos(2ψ − p2)``
   (ψ: angle on the shaft); a probe at α sees ``R_b(α − θ(t))``, so both probes
   of a bearing see the same profile, shifted by their angular separation.
   ``a1 ~ U(runout_1x_um)``, ``a2 ~ U(runout_2x_um)``, phases uniform, per bearing.
4. **Additive white Gaussian noise** per channel with
   ``σ² = var(signal) / 10^(SNR/10)`` (signal = steps 2–3, its AC power);
   ``snr_db = inf`` adds none.

The draws are made in this fixed order from ``numpy.random.default_rng(sample_seed)``:
SNR, θ0, φ_m, then for each bearing (a1, p1, a2, p2), then the noise.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from rotordiag.core.conventions import project_on_probe

__all__ = ["MeasurementSettings", "MeasurementDraws", "draw_measurement", "shaft_angle_rad",
           "required_record_revs", "probe_waveforms_um", "transient_probe_waveforms_um", "runout_um"]

TWO_PI = 2.0 * math.pi


def _as_bounds(v: Any) -> tuple[float, float]:
    """A spec value or Range (or (lo, hi) tuple) as (lo, hi)."""
    if hasattr(v, "min") and hasattr(v, "max") and not isinstance(v, (list, tuple)):
        return float(v.min), float(v.max)
    if isinstance(v, (list, tuple)):
        return float(v[0]), float(v[-1])
    return float(v), float(v)


@dataclass(frozen=True)
class MeasurementSettings:
    """The ``[measurement]`` table in plain types (picklable, sent to the workers)."""

    bearings: tuple[int, ...]
    probe_angles_deg: tuple[float, ...]
    sample_rate_hz: float
    n_points: int
    snr_db: tuple[float, float] = (math.inf, math.inf)
    runout_1x_um: tuple[float, float] = (0.0, 0.0)
    runout_2x_um: tuple[float, float] = (0.0, 0.0)
    speed_fluctuation: float = 0.0
    speed_fluctuation_hz: float = 0.5

    @classmethod
    def from_spec(cls, spec: Any) -> MeasurementSettings:
        m = spec.measurement
        return cls(
            bearings=tuple(int(b) for b in m.bearings),
            probe_angles_deg=tuple(float(a) for a in m.probe_angles_deg),
            sample_rate_hz=float(m.sample_rate_hz), n_points=int(spec.n_points),
            snr_db=_as_bounds(m.snr_db), runout_1x_um=_as_bounds(m.runout_1x_um),
            runout_2x_um=_as_bounds(m.runout_2x_um), speed_fluctuation=float(m.speed_fluctuation),
            speed_fluctuation_hz=float(m.speed_fluctuation_hz),
        )

    @property
    def channels(self) -> list[tuple[int, float]]:
        """(bearing, angle_deg) of each channel: bearings in order, both probes per bearing."""
        return [(b, a) for b in self.bearings for a in self.probe_angles_deg]

    @property
    def time_s(self) -> np.ndarray:
        return np.arange(self.n_points) / self.sample_rate_hz


@dataclass(frozen=True)
class MeasurementDraws:
    """The random part of one sample's measurement (stored in the dataset)."""

    snr_db: float
    start_angle_rad: float
    speed_fluctuation_phase_rad: float
    runout_1x_um: np.ndarray        # (n_bearings,)
    runout_1x_phase_rad: np.ndarray
    runout_2x_um: np.ndarray
    runout_2x_phase_rad: np.ndarray


def _uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    lo, hi = bounds
    return float(lo) if hi == lo else float(rng.uniform(lo, hi))


def draw_measurement(settings: MeasurementSettings, rng: np.random.Generator) -> MeasurementDraws:
    """Draw SNR, start angle, fluctuation phase and runout (in the documented order)."""
    snr = _uniform(rng, settings.snr_db)
    theta0 = float(rng.uniform(0.0, TWO_PI))
    phase_m = float(rng.uniform(0.0, TWO_PI))
    r = np.empty((len(settings.bearings), 4))
    for k in range(len(settings.bearings)):
        r[k] = (_uniform(rng, settings.runout_1x_um), rng.uniform(0.0, TWO_PI),
                _uniform(rng, settings.runout_2x_um), rng.uniform(0.0, TWO_PI))
    return MeasurementDraws(snr, theta0, phase_m, r[:, 0].copy(), r[:, 1].copy(), r[:, 2].copy(), r[:, 3].copy())


def shaft_angle_rad(time_s: np.ndarray, speed_rpm: float, settings: MeasurementSettings,
                    draws: MeasurementDraws) -> np.ndarray:
    """θ(t) of the module docstring (radians, from the start of the simulated record)."""
    omega = math.pi * speed_rpm / 30.0
    t = np.asarray(time_s, dtype=float)
    theta = draws.start_angle_rad + omega * t
    eps = settings.speed_fluctuation
    if eps > 0:
        wm = TWO_PI * settings.speed_fluctuation_hz
        phi = draws.speed_fluctuation_phase_rad
        theta = theta + omega * eps / wm * (math.cos(phi) - np.cos(wm * t + phi))
    return theta


def runout_um(theta_rad: np.ndarray, angle_deg: float, draws: MeasurementDraws, k: int) -> np.ndarray:
    """Runout (µm) that a probe at ``angle_deg`` on the ``k``-th measured bearing reads at shaft angle
    ``theta_rad``: step 3 of the module docstring, ``R_b(α − θ)``."""
    r1, r2 = _runout_orders_um(theta_rad, angle_deg, draws, k)
    return r1 + r2


def _runout_orders_um(theta_rad: np.ndarray, angle_deg: float, draws: MeasurementDraws,
                      k: int) -> tuple[np.ndarray, np.ndarray]:
    psi = math.radians(angle_deg) - np.asarray(theta_rad, dtype=float)
    return (draws.runout_1x_um[k] * np.cos(psi - draws.runout_1x_phase_rad[k]),
            draws.runout_2x_um[k] * np.cos(2.0 * psi - draws.runout_2x_phase_rad[k]))


def required_record_revs(speed_rpm: float, settings: MeasurementSettings, draws: MeasurementDraws) -> int:
    """Revolutions the simulator must record so that θ(t) stays inside its record (+1 for the spline)."""
    theta = shaft_angle_rad(settings.time_s, speed_rpm, settings, draws)
    return int(math.floor(float(theta.max()) / TWO_PI)) + 2


def probe_waveforms_um(
    journal_displacements_m: np.ndarray,
    samples_per_rev: int,
    speed_rpm: float,
    settings: MeasurementSettings,
    draws: MeasurementDraws,
    rng: np.random.Generator,
) -> np.ndarray:
    """Probe waveforms of one sample.

    Parameters
    ----------
    journal_displacements_m : ndarray, shape (n, n_bearings, 2)
        Journals of bearings 1..n_bearings (4 for the paper's model; a shaft train's
        own number) relative to their bearing centres, sampled at
        τ = 2πk / samples_per_rev from the start of the record (fewer rows if
        the simulation stopped early).
    samples_per_rev : int
    speed_rpm : float
    settings : MeasurementSettings
    draws : MeasurementDraws
    rng : numpy.random.Generator
        The sample's generator, positioned after :func:`draw_measurement` (noise).

    Returns
    -------
    ndarray, shape (n_channels, n_points), float32
        µm. Points whose shaft angle lies beyond the simulated record (a run
        that ended in contact / divergence) are NaN.
    """
    from scipy.interpolate import CubicSpline

    disp = np.asarray(journal_displacements_m, dtype=float)
    if disp.ndim != 3 or disp.shape[2] != 2 or disp.shape[1] < max(settings.bearings):
        raise ValueError(f"journal_displacements_m must have shape (n, n_bearings ≥ {max(settings.bearings)}, 2), "
                         f"got {disp.shape}")
    n_b = disp.shape[1]
    theta = shaft_angle_rad(settings.time_s, speed_rpm, settings, draws)
    out = np.full((len(settings.channels), settings.n_points), np.nan)
    n = disp.shape[0]
    if n >= 4:
        tau = TWO_PI / samples_per_rev * np.arange(n)
        inside = theta <= tau[-1]
        spline = CubicSpline(tau, disp.reshape(n, 2 * n_b), axis=0)
        xy = spline(theta[inside]).reshape(-1, n_b, 2) * 1e6  # µm
        _probes_and_runout(out, xy, theta, inside, settings, draws)
    return _with_noise(out, draws, rng)


def transient_probe_waveforms_um(
    journal_displacements_m: np.ndarray,
    theta_rad: np.ndarray,
    settings: MeasurementSettings,
    draws: MeasurementDraws,
    rng: np.random.Generator,
) -> np.ndarray:
    """Probe waveforms of a run-up or coast-down sample: steps 2–4 of the module docstring.

    The transient simulator already samples the journals on the acquisition clock, so there is no step 1:
    the shaft angle is the profile's, ``theta_rad`` (0 at each keyphasor mark), and the draws' start angle
    and fluctuation phase are not used.

    Parameters
    ----------
    journal_displacements_m : ndarray, shape (n, n_bearings, 2)
        :attr:`rotordiag.simulator.transient.TransientResult.journal_displacements_m` (n ≤ ``settings.n_points``:
        fewer rows if the run stopped early; those points are NaN).
    theta_rad : ndarray, shape (settings.n_points,)
        The profile's shaft angle at the sample times.

    Returns
    -------
    ndarray, shape (n_channels, n_points), float32
        µm.
    """
    disp = np.asarray(journal_displacements_m, dtype=float)
    if disp.ndim != 3 or disp.shape[2] != 2 or disp.shape[1] < max(settings.bearings):
        raise ValueError(f"journal_displacements_m must have shape (n, n_bearings ≥ {max(settings.bearings)}, 2), "
                         f"got {disp.shape}")
    theta = np.asarray(theta_rad, dtype=float)
    if theta.shape != (settings.n_points,):
        raise ValueError(f"theta_rad must have shape ({settings.n_points},), got {theta.shape}")
    out = np.full((len(settings.channels), settings.n_points), np.nan)
    n = min(disp.shape[0], settings.n_points)
    inside = np.arange(settings.n_points) < n
    _probes_and_runout(out, disp[:n] * 1e6, theta, inside, settings, draws)
    return _with_noise(out, draws, rng)


def _probes_and_runout(out: np.ndarray, xy_um: np.ndarray, theta: np.ndarray, inside: np.ndarray,
                       settings: MeasurementSettings, draws: MeasurementDraws) -> None:
    """Steps 2 and 3: each channel's projection plus its bearing's runout, written into ``out[:, inside]``."""
    for c, (b, angle_deg) in enumerate(settings.channels):
        signal = project_on_probe(xy_um[:, b - 1, 0], xy_um[:, b - 1, 1], angle_deg)
        r1, r2 = _runout_orders_um(theta[inside], angle_deg, draws, settings.bearings.index(b))
        out[c, inside] = signal + r1 + r2       # this order: the stored waveforms stay bit-identical


def _with_noise(out: np.ndarray, draws: MeasurementDraws, rng: np.random.Generator) -> np.ndarray:
    """Step 4 (white noise at the drawn SNR of each channel's finite part), as float32."""
    if math.isfinite(draws.snr_db):
        noise = rng.standard_normal(out.shape)
        with np.errstate(invalid="ignore"):
            power = np.array([np.var(row[np.isfinite(row)]) if np.isfinite(row).any() else 0.0 for row in out])
        out = out + noise * np.sqrt(power / 10.0 ** (draws.snr_db / 10.0))[:, None]
    return out.astype(np.float32)
