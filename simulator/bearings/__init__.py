"""Nonlinear oil-film bearings for shaft trains (SI units).

Journal position (x horizontal, y vertical up) and velocity relative to the bearing centre;
Ω > 0 turns from +x towards +y, as the paper model's film (MODEL.md section 4).

Public API
----------
PlainBearing, EllipticalBearing, TiltingPadBearing, LinearBearing
    Frozen, validated parameter sets with ``force_n``, ``coefficients``, ``equilibrium``,
    ``kernel`` and ``to_dict``/``from_dict``.
bearing_from_dict
    The bearing a TOML/JSON table names (``{type = "tilting_pad", pads = 5, ...}``).
bearing_force
    numba-compiled ``bearing_force(code, params, x, y, vx, vy, omega) -> (fx, fy)`` for the
    ``(code, params)`` that ``kernel()`` returns; callable inside other compiled code.
tilting_pad_force_states
    numba ``tilting_pad_force_states(params, x, y, vx, vy, omega, u, du_dt) -> (fx, fy)`` for a
    tilting-pad bearing whose pad tilts ``u`` are states of the train (massless pads in moment
    equilibrium with their own squeeze films; writes the tilt rates). ``bearing_force`` instead
    holds each pad at rest in tilt (quasi-static); see docs/bearings.md.
BEARING_PLAIN, BEARING_ELLIPTICAL, BEARING_TILTING_PAD, BEARING_LINEAR
    The type codes.
"""
from __future__ import annotations

from ._film import LINEAR as BEARING_LINEAR
from ._film import LOBED as BEARING_ELLIPTICAL
from ._film import PLAIN as BEARING_PLAIN
from ._film import TILTING_PAD as BEARING_TILTING_PAD
from ._film import bearing_force, tilting_pad_force_states
from ._types import (
    BEARING_TYPES,
    Bearing,
    EllipticalBearing,
    LinearBearing,
    PlainBearing,
    TiltingPadBearing,
    bearing_from_dict,
)

__all__ = [
    "PlainBearing", "EllipticalBearing", "TiltingPadBearing", "LinearBearing", "Bearing", "BEARING_TYPES",
    "bearing_from_dict", "bearing_force", "BEARING_PLAIN", "BEARING_ELLIPTICAL", "BEARING_TILTING_PAD",
    "BEARING_LINEAR", "tilting_pad_force_states",
]
