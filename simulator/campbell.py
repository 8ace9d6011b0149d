"""Campbell diagram and damped critical speeds of the linearised rotor (issue 46).

:func:`campbell` runs :func:`rotordiag.simulator.modal` over a speed grid; :func:`critical_speeds` finds where
a mode's damped natural frequency meets an excitation order's line (n·running speed) and keeps those with an
amplification factor AF = 1/(2ζ) of at least ``MIN_AMPLIFICATION_FACTOR`` (API 684's 2.5: a more damped mode is
no critical a run-up shows). Each critical carries its half-power width, Δn ≈ 2ζ·n_c (the band where a single
mode's response is above 1/√2 of its peak).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .modal import modal
from .params import SPEED_RANGE_RPM, Plant, check_range

__all__ = ["CampbellData", "CriticalSpeed", "campbell", "critical_speeds", "MIN_AMPLIFICATION_FACTOR"]

#: API 684: a response peak with an amplification factor below 2.5 is critically damped (no critical speed).
MIN_AMPLIFICATION_FACTOR = 2.5


@dataclass(frozen=True)
class CampbellData:
    """Damped natural frequencies against running speed.

    Attributes
    ----------
    speeds_rpm : ndarray, shape (n_speeds,)
    frequencies_hz : ndarray, shape (n_speeds, n_modes)
        Sorted ascending at each speed (a branch is the k-th lowest mode, not one mode shape).
    damping_ratios : ndarray, shape (n_speeds, n_modes)
    """

    speeds_rpm: np.ndarray
    frequencies_hz: np.ndarray
    damping_ratios: np.ndarray


@dataclass(frozen=True)
class CriticalSpeed:
    """A mode meeting an excitation line: at ``speed_rpm`` the mode's damped frequency is ``order`` × running speed."""

    speed_rpm: float
    frequency_hz: float
    damping_ratio: float
    order: int

    @property
    def half_power_width_rpm(self) -> float:
        """2ζ·n_c: the full width of the response peak at 1/√2 of its height (single-mode estimate)."""
        return 2.0 * self.damping_ratio * self.speed_rpm

    @property
    def amplification_factor(self) -> float:
        return 1.0 / (2.0 * self.damping_ratio)


def campbell(plant: Plant, speeds_rpm: np.ndarray | list[float]) -> CampbellData:
    """Modes of the linearised rotor (:func:`modal`) at each speed (r/min, inside ``SPEED_RANGE_RPM``)."""
    sp = np.asarray(speeds_rpm, dtype=float)
    if sp.ndim != 1 or sp.size < 2 or sp.size > 400:
        raise ValueError(f"speeds_rpm: give 2 to 400 speeds, got shape {sp.shape}")
    for s in sp:
        check_range("speeds_rpm", float(s), *SPEED_RANGE_RPM)
    res = [modal(plant, float(s)) for s in sp]
    n_modes = min(r.frequencies_hz.size for r in res)
    f = np.array([r.frequencies_hz[:n_modes] for r in res])
    z = np.array([r.damping_ratios[:n_modes] for r in res])
    return CampbellData(sp, f, z)


def critical_speeds(data: CampbellData, orders: tuple[int, ...] = (1,)) -> list[CriticalSpeed]:
    """Where a branch of ``data`` crosses ``order`` × running speed (linear interpolation between the grid
    speeds), with AF ≥ :data:`MIN_AMPLIFICATION_FACTOR`; sorted by speed. A branch is the k-th lowest frequency,
    so where two modes cross near the line its damping may be either's: a critical there can come out twice, a
    few r/min apart (the linearised model does not track mode shapes)."""
    out: list[CriticalSpeed] = []
    sp = data.speeds_rpm
    for order in orders:
        line_hz = order * sp / 60.0
        for m in range(data.frequencies_hz.shape[1]):
            g = data.frequencies_hz[:, m] - line_hz
            for i in np.flatnonzero(np.sign(g[:-1]) * np.sign(g[1:]) < 0):
                w = g[i] / (g[i] - g[i + 1])
                s = sp[i] + w * (sp[i + 1] - sp[i])
                zeta = float(data.damping_ratios[i, m] + w * (data.damping_ratios[i + 1, m] - data.damping_ratios[i, m]))
                if 0 < zeta <= 1.0 / (2.0 * MIN_AMPLIFICATION_FACTOR):
                    out.append(CriticalSpeed(float(s), float(order * s / 60.0), zeta, int(order)))
    return sorted(out, key=lambda c: (c.speed_rpm, c.order))
