"""Physical bounds on the numbers that describe a recording, shared by every door (reader, API schemas, query).

A number can be finite and positive and still make no sense for a machine: ``5e-324`` Hz passes ``> 0`` and
then divides to infinity. Every door refuses values outside these ranges with a message that names the
quantity, its unit and the range, so the user can check the units instead of meeting an overflow.
"""
from __future__ import annotations

import math

#: sample rate of a recording, Hz (a shaft-vibration acquisition samples at tens of Hz to hundreds of kHz)
SAMPLE_RATE_RANGE_HZ: tuple[float, float] = (1.0, 1e6)
#: running speed, r/min (turning gear is a few r/min; the fastest turbomachines about 100,000 r/min)
SPEED_RANGE_RPM: tuple[float, float] = (1.0, 1e5)
#: radial bearing clearance, µm (1 µm to 100 mm)
CLEARANCE_RANGE_UM: tuple[float, float] = (1.0, 1e5)
#: probe scale factor of a voltage recording, V/mm (7.87 V/mm = 200 mV/mil)
SENSITIVITY_RANGE_V_PER_MM: tuple[float, float] = (1e-3, 1e3)
#: largest displacement sample, µm (10 m: far beyond any probe's range, small enough that squares stay finite)
MAX_DISPLACEMENT_UM: float = 1e7
#: keyphasor pulse times, s from the first sample (the magnitude) and the shortest interval between two pulses
KEYPHASOR_MAX_TIME_S: float = 1e7
KEYPHASOR_MIN_INTERVAL_S: float = 1e-6


def check_range(value: object, name: str, bounds: tuple[float, float], unit: str, hint: str = "") -> float:
    """``value`` as a float inside ``bounds`` (inclusive).

    Raises
    ------
    ValueError
        Not a number, not finite, or outside ``bounds``; the message names ``name``, the range in ``unit``
        and says to check the units (``hint`` is appended).
    """
    lo, hi = bounds
    tail = f"; {hint}" if hint else ""
    if isinstance(value, bool):
        raise ValueError(f"{name} must be a number of {unit}, got {value!r}{tail}")
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a number of {unit}, got {value!r}{tail}") from None
    if not (math.isfinite(v) and lo <= v <= hi):
        raise ValueError(f"{name} must be between {lo:g} and {hi:g} {unit}, got {v:g}: check the units{tail}")
    return v
