"""Stability of a train at a speed: the least-damped mode of the train linearised at its static state.

Bearing coefficients are, by default (``coefficients="reduced"``), the *reduced* ones where a bearing has them (a
tilting-pad bearing's ``reduced_coefficients``, Lund's pad assembly at synchronous whirl, the coefficients tilting-pad
tables quote) and the film's own derivatives otherwise; ``coefficients="film"`` takes the nonlinear film's own
derivatives at the static state for every bearing (the force the time integration uses, so the margin the
simulation has; for tilting pads it is the smaller one). The margin is the logarithmic decrement
δ = −2π Re λ / Im λ of the least-damped mode (API 684's measure); δ ≤ 0 is an unstable train (oil whip
or whirl). :func:`threshold_speed_rpm` brackets the speed where δ crosses zero.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .fe import Assembly, assemble
from .linear import bearing_coefficients, modes
from .model import Train, TrainError
from .static import StaticState, static_state


def reduced_coefficients(brg, x_m: float, y_m: float, speed_rad_s: float) -> tuple[np.ndarray, np.ndarray]:
    """(K, C) of a bearing for the stability check: reduced (synchronous) where the bearing has them."""
    red = getattr(brg, "reduced_coefficients", None)
    if red is not None:
        return red(x_m, y_m, speed_rad_s)
    return bearing_coefficients(brg, x_m, y_m, speed_rad_s)


#: the bearing coefficients :func:`stability` can linearise with: ``reduced`` (synchronous reduced where a bearing has
#: them) or ``film`` (the nonlinear film's own derivatives)
COEFFICIENTS = {"reduced": reduced_coefficients, "film": bearing_coefficients}


def _coefficients(which: str):
    if which not in COEFFICIENTS:
        raise TrainError(f"coefficients must be one of {sorted(COEFFICIENTS)} (got {which!r})")
    return COEFFICIENTS[which]


@dataclass(frozen=True)
class Stability:
    """The least-damped mode at ``speed_rpm``: its log decrement, damped frequency and direction."""

    speed_rpm: float
    log_decrement: float
    frequency_hz: float
    forward: bool

    @property
    def stable(self) -> bool:
        return self.log_decrement > 0.0


def stability(train: Train | Assembly, speed_rpm: float, *, max_frequency_hz: float | None = None,
              static: StaticState | None = None, coefficients: str = "reduced") -> Stability:
    """The least-damped mode of the train at ``speed_rpm`` (modes up to ``max_frequency_hz``, default
    4× running speed: the shaft modes a film can drive, not the stiff local modes of a fine mesh), linearised
    about ``static`` (solved here unless given) with the bearings' ``coefficients`` (``reduced`` or ``film``,
    module docstring)."""
    coef = _coefficients(coefficients)
    asm = train if isinstance(train, Assembly) else assemble(train)
    st = static if static is not None else static_state(asm, speed_rpm)
    m = modes(asm, speed_rpm, st, coefficients=coef)
    top = 4 * speed_rpm / 60.0 if max_frequency_hz is None else max_frequency_hz
    keep = m.frequency_hz <= top
    if not np.any(keep):
        raise TrainError(f"no mode below {top:g} Hz at {speed_rpm:g} r/min")
    i = int(np.flatnonzero(keep)[np.argmin(m.log_decrement[keep])])
    return Stability(float(speed_rpm), float(m.log_decrement[i]), float(m.frequency_hz[i]), bool(m.forward[i]))


def threshold_speed_rpm(train: Train | Assembly, max_rpm: float, *, min_rpm: float = 300.0, n_grid: int = 12,
                        tol_rpm: float = 5.0, coefficients: str = "reduced") -> float:
    """The lowest speed in [``min_rpm``, ``max_rpm``] where the least-damped mode's log decrement
    reaches zero (onset of oil whirl/whip), by a grid and bisection; ``math.inf`` if stable throughout.
    The static state is solved again at every speed (a film's load capacity grows with speed, so the journals
    rise and, under an offset, the load shares change); ``coefficients`` as :func:`stability`."""
    _coefficients(coefficients)
    asm = train if isinstance(train, Assembly) else assemble(train)
    grid = np.linspace(min_rpm, max_rpm, n_grid)
    prev = None

    def log_dec(speed_rpm: float) -> float:
        return stability(asm, speed_rpm, coefficients=coefficients).log_decrement

    for s in grid:
        d = log_dec(float(s))
        if d <= 0:
            if prev is None:
                return float(s)
            lo, hi = prev, float(s)
            while hi - lo > tol_rpm:
                mid = 0.5 * (lo + hi)
                if log_dec(mid) <= 0:
                    hi = mid
                else:
                    lo = mid
            return hi
        prev = float(s)
    return math.inf


def speed_warning(train: Train | Assembly, speed_rpm: float) -> str | None:
    """A warning when ``speed_rpm`` is beyond the train's stability threshold (None when stable there)."""
    s = stability(train, speed_rpm)
    if s.stable:
        return None
    return (f"{speed_rpm:g} r/min is beyond this train's stability threshold: its least-damped mode "
            f"({s.frequency_hz:.1f} Hz, {'forward' if s.forward else 'backward'}) has log decrement "
            f"{s.log_decrement:.3f} ≤ 0, so the response will be oil whirl/whip, not the steady 1X/2X of "
            f"a healthy or misaligned train; lower the speed or change the bearings")
