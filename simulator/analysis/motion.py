"""The motion-type classifier, kept in ``rotordiag.simulator.motion`` (NumPy only, no sweeps loaded); re-exported
here as part of the analysis API."""
from __future__ import annotations

from ..motion import (
    DIVERGENCE_THRESHOLD,
    KINDS,
    LLE_NOISE_PER_INTERVAL,
    MAX_PERIOD,
    MIN_REPEATS,
    PERIOD_RTOL,
    MotionType,
    classify_motion,
    detect_period,
    poincare_divergence_rate,
)

__all__ = ["MotionType", "classify_motion", "detect_period", "poincare_divergence_rate", "PERIOD_RTOL", "MAX_PERIOD",
           "LLE_NOISE_PER_INTERVAL", "DIVERGENCE_THRESHOLD", "MIN_REPEATS", "KINDS"]
