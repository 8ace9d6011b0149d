"""Static journal position in a plain (fixed-geometry) oil-film bearing.

The shaft centreline sits at eccentricity ε = e/c from the bearing centre and, under a
vertical (gravity) load, off the load line in the direction of rotation by the attitude
angle φ. Conventions of :mod:`rotordiag.core.conventions` and ``features.evidence``: x
horizontal, y up, the load line is −y, φ is measured from −y toward +x (the rotation
direction).
"""
from __future__ import annotations

import numpy as np

__all__ = ["ATTITUDE_MIN_ECC", "attitude_angle_deg", "short_bearing_attitude_deg"]

#: Below this eccentricity ratio the journal sits practically at the bearing centre and its attitude
#: angle is not defined by the load (a DC error of a few µm turns it anywhere): not read. Training plants
#: with ε ≤ 0.003 at an outboard bearing (light journal, high speed, thick film) gave angles of −160° to
#: −75°, which widened the envelope until a linear-bearing machine at ε = 0.26 and 0° passed as in-family.
ATTITUDE_MIN_ECC = 0.05


def attitude_angle_deg(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Attitude angle φ in degrees, in (−180, 180]: from the load line (−y) to the line of centres, with rotation.

    Parameters
    ----------
    x, y : ndarray
        Mean journal position relative to the bearing centre (any common unit, e.g. per clearance).
    """
    return np.degrees(np.arctan2(np.asarray(x, dtype=float), -np.asarray(y, dtype=float)))


def short_bearing_attitude_deg(ecc: np.ndarray) -> np.ndarray:
    """Attitude angle of a plain short (Ocvirk) journal bearing at eccentricity ratio ``ecc``, degrees.

    ``tan φ = π √(1 − ε²) / (4 ε)``: 90° for a centred journal, falling to 0° as the journal
    reaches the wall (ε → 1); 0° beyond it (ε ≥ 1 is not a position inside the bearing).
    """
    e = np.asarray(ecc, dtype=float)
    with np.errstate(invalid="ignore"):
        return np.degrees(np.arctan2(np.pi * np.sqrt(np.clip(1.0 - e * e, 0.0, None)), 4.0 * np.abs(e)))


def attitude_offset_deg(x: np.ndarray, y: np.ndarray, ecc: np.ndarray | None = None) -> np.ndarray:
    """The centreline's attitude angle minus a plain short bearing's at its eccentricity, degrees in [−180, 180).

    How far a journal sits from where a plain oil-film bearing would hold it under the same load: about 0° for a
    plain cylindrical bearing, −30° to −60° for a linear or tilting-pad one (the journal on the load line), every
    bearing shifted alike when the probe frame is turned. Not masked: below :data:`ATTITUDE_MIN_ECC` the value is
    noise (the caller leaves it out).

    Parameters
    ----------
    x, y : ndarray
        Mean journal position per clearance.
    ecc : ndarray, optional
        Eccentricity ratio (default ``hypot(x, y)``).
    """
    e = np.hypot(x, y) if ecc is None else np.asarray(ecc, dtype=float)
    return (attitude_angle_deg(x, y) - short_bearing_attitude_deg(e) + 180.0) % 360.0 - 180.0
