"""A keyphasor pulse train with missing or extra pulses.

A turbine-generator's inertia keeps its speed from changing by more than a fraction of a per cent from one
revolution to the next (a load rejection's overspeed: about 10 %/s, 0.2 % per revolution at 3000 r/min). A
pulse interval far from its neighbours' is therefore no speed change but a faulty pulse train: a missed pulse
(a worn or dirty notch, the probe gap drifting past the trigger level) gives an interval of about twice the
period, an extra one (a second edge, a scratch, electrical noise) two intervals that add up to one. Order
tracking between such pulses puts a revolution's worth of shaft angle where there were two, or half a revolution
where there was one, and every order's amplitude and phase comes out wrong (measured: docs/features.md,
"Measurements behind the acquisition and keyphasor checks").

:func:`keyphasor_fault` finds such intervals; ``features._speed.shaft_angle`` then does not track orders by the
pulses and ``features._sanity`` says what to check.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["KEYPHASOR_JUMP_MAX", "KeyphasorFault", "keyphasor_fault", "pulses_in_record"]

#: a pulse interval further than this (relative) from the median of its neighbours' is no speed change
KEYPHASOR_JUMP_MAX = 0.05
#: intervals on each side that make a pulse interval's neighbourhood
_HALF_WINDOW = 3


@dataclass(frozen=True)
class KeyphasorFault:
    """Pulse intervals that no running speed explains.

    Attributes
    ----------
    n_off : int
        Intervals further than :data:`KEYPHASOR_JUMP_MAX` from their neighbours' median.
    n_intervals : int
    ratios : tuple of float
        The smallest and the largest interval over its neighbours' median.
    period_s : float or None
        The running period read from the sound intervals (their median) when at least half of the intervals are
        sound, else None (the speed must come from elsewhere).
    """

    n_off: int
    n_intervals: int
    ratios: tuple[float, float]
    period_s: float | None

    def describe(self) -> str:
        """What was found, for a message."""
        lo, hi = self.ratios
        kinds = []
        if hi > 1.0 + KEYPHASOR_JUMP_MAX:
            kinds.append(f"up to {hi:.2f}× (missing pulses)")
        if lo < 1.0 - KEYPHASOR_JUMP_MAX:
            kinds.append(f"down to {lo:.2f}× (extra pulses)")
        return (f"{self.n_off} of {self.n_intervals} keyphasor pulse intervals differ from their neighbours' by more "
                f"than {100 * KEYPHASOR_JUMP_MAX:g} % — {' and '.join(kinds)} — which no rotor's speed does from one "
                "revolution to the next")


def pulses_in_record(pulse_times_s: np.ndarray, n_points: int, sample_rate_hz: float) -> np.ndarray:
    """The pulses inside a record of ``n_points`` samples (first sample at t = 0)."""
    t = np.asarray(pulse_times_s, dtype=float)
    return t[(t >= 0) & (t <= (n_points - 1) / sample_rate_hz)]


def keyphasor_fault(pulse_times_s: np.ndarray) -> KeyphasorFault | None:
    """The faulty intervals of a keyphasor pulse train (times in s, increasing), or None when it is sound.

    Each interval is compared with the median of the :data:`_HALF_WINDOW` intervals on either side of it (itself
    excluded), so that a speed drifting over the record — a run-down, a slow governor swing — is no fault.
    Fewer than 3 intervals are not judged.
    """
    t = np.asarray(pulse_times_s, dtype=float)
    periods = np.diff(t)
    n = periods.size
    if n < 3:
        return None
    pad = np.full(_HALF_WINDOW, np.nan)
    windows = np.lib.stride_tricks.sliding_window_view(np.concatenate([pad, periods, pad]), 2 * _HALF_WINDOW + 1)
    around = np.delete(windows, _HALF_WINDOW, axis=1)            # each interval's neighbours, itself left out
    ratios = periods / np.nanmedian(around, axis=1)
    off = np.abs(ratios - 1.0) > KEYPHASOR_JUMP_MAX
    if not off.any():
        return None
    sound = periods[~off]
    period = float(np.median(sound)) if 2 * sound.size >= n else None
    return KeyphasorFault(int(off.sum()), n, (float(ratios.min()), float(ratios.max())), period)
