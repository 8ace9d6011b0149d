"""Campbell diagram, critical speeds and stability margin of a shaft train.

At each speed the train is linearised about its static state (bearing coefficients as :mod:`.stability`
takes them: reduced where a bearing has them, the film's derivatives otherwise) and its damped modes up
to ``max_frequency_hz`` are kept, lowest first. The result is a ``simulator.campbell.CampbellData`` (the
damping ratio ζ = δ / √(4π² + δ²) of each mode's log decrement δ) with the log decrements beside it, so
the paper model's critical-speed rule (1X/2X crossings with amplification factor ≥ 2.5, half-power width
2ζ·n_c) serves both models unchanged. The stability margin is the log decrement of the least-damped mode
(API 684's measure; :func:`.stability.stability`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..campbell import CampbellData, CriticalSpeed, critical_speeds
from .fe import Assembly, assemble
from .linear import modes
from .model import Train, TrainError
from .stability import Stability, reduced_coefficients, stability
from .static import static_state

__all__ = ["TrainCampbell", "train_campbell", "damping_ratio_of_log_decrement", "MAX_SPEEDS"]

#: at most this many speeds in one diagram (a static solution and an eigenproblem each, ≈ 1 s on one core)
MAX_SPEEDS = 200


def damping_ratio_of_log_decrement(log_decrement: np.ndarray | float) -> np.ndarray:
    """ζ of a mode with log decrement δ = 2πζ/√(1 − ζ²): ζ = δ/√(4π² + δ²)."""
    d = np.asarray(log_decrement, dtype=float)
    return d / np.sqrt(4 * math.pi**2 + d**2)


@dataclass(frozen=True)
class TrainCampbell:
    """A train's damped modes against speed.

    Attributes
    ----------
    data : CampbellData
        Speeds (r/min), damped natural frequencies (Hz) and damping ratios, shape (n_speeds, n_modes), the
        k-th lowest mode at each speed (NaN where fewer modes lie below the frequency limit).
    log_decrements : ndarray, shape (n_speeds, n_modes)
    forward : ndarray of bool, shape (n_speeds, n_modes)
        Forward whirl (the mode's circular component turns with the shaft).
    margin : list of Stability
        The least-damped mode at each speed (its log decrement is the stability margin there).
    """

    data: CampbellData
    log_decrements: np.ndarray
    forward: np.ndarray
    margin: list[Stability]

    def critical_speeds(self, orders: tuple[int, ...] = (1, 2)) -> list[CriticalSpeed]:
        """Where a mode meets ``order`` × running speed with AF ≥ 2.5 (``simulator.campbell.critical_speeds``)."""
        return critical_speeds(self.data, orders)

    def threshold_rpm(self) -> float:
        """The first grid speed whose least-damped mode has δ ≤ 0 (``math.inf`` if none): where whirl starts
        on this grid (:func:`.stability.threshold_speed_rpm` brackets it finely)."""
        for m in self.margin:
            if not m.stable:
                return m.speed_rpm
        return math.inf


def train_campbell(train: Train | Assembly, speeds_rpm, n_modes: int = 8, *,
                   max_frequency_hz: float | None = None, max_damping_ratio: float = 0.5) -> TrainCampbell:
    """Modes of ``train`` linearised at its static state at each of ``speeds_rpm`` (r/min, > 0, at most
    :data:`MAX_SPEEDS`): the ``n_modes`` lowest below ``max_frequency_hz`` (default 2.5 × the top speed's
    running frequency, so the 2X line is covered and a fine mesh's stiff local modes are not) with damping
    ratio below ``max_damping_ratio`` (the films' overdamped roots, nearly real eigenvalues with a
    spurious small imaginary part, show no response peak and would crowd out the shaft modes)."""
    sp = np.asarray(speeds_rpm, dtype=float)
    if sp.ndim != 1 or not 2 <= sp.size <= MAX_SPEEDS:
        raise TrainError(f"speeds_rpm: give 2 to {MAX_SPEEDS} speeds, got shape {sp.shape}")
    if not np.all(np.isfinite(sp)) or np.any(sp <= 0) or np.any(np.diff(sp) <= 0):
        raise TrainError("speeds_rpm must be positive and increasing")
    if not 1 <= n_modes <= 40:
        raise TrainError(f"n_modes must be 1..40 (got {n_modes})")
    asm = train if isinstance(train, Assembly) else assemble(train)
    top = 2.5 * sp[-1] / 60.0 if max_frequency_hz is None else float(max_frequency_hz)
    f = np.full((sp.size, n_modes), np.nan)
    d = np.full((sp.size, n_modes), np.nan)
    fw = np.zeros((sp.size, n_modes), dtype=bool)
    margin = []
    for i, s in enumerate(sp):
        st = static_state(asm, float(s))
        m = modes(asm, float(s), st, coefficients=reduced_coefficients)
        zeta = damping_ratio_of_log_decrement(m.log_decrement)
        keep = np.flatnonzero((m.frequency_hz <= top) & (zeta < max_damping_ratio))[:n_modes]
        f[i, :keep.size] = m.frequency_hz[keep]
        d[i, :keep.size] = m.log_decrement[keep]
        fw[i, :keep.size] = m.forward[keep]
        margin.append(stability(asm, float(s), static=st, max_frequency_hz=max(top, 4 * s / 60.0)))
    data = CampbellData(sp, f, damping_ratio_of_log_decrement(d))
    return TrainCampbell(data, d, fw, margin)
