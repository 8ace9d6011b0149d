"""Periodic steady states directly: shooting with Floquet stability (issue 16).

Public API
----------
steady_state(plant, speed_rpm, misalignment, unbalance, ...) -> PeriodicOrbit
    Period-n (n ≤ 16) steady state by Newton shooting on the once-per-revolution
    map, with the monodromy matrix from the variational equations; Floquet
    multipliers and a stability verdict.
RotorMap
    The rotor's Poincaré map Pⁿ and ∂Pⁿ/∂x on the dynamic state components.
find_fixed_point(map, x0, n, method="newton"|"chord") -> FixedPoint
    The Newton / chord solver, for any :class:`PeriodicMap`.
steady_start(system, transient_revs) -> SteadyStart
    Where a dataset sample's or sweep point's record starts: on the shot period-1
    orbit where that is safe, else after the (rest of the) transient.
"""
from .maps import MapEval, PeriodicMap, RotorMap
from .shooting import FixedPoint, PeriodicOrbit, find_fixed_point, stability_verdict, steady_state
from .start import SteadyStart, steady_start

__all__ = [
    "MapEval", "PeriodicMap", "RotorMap", "FixedPoint", "PeriodicOrbit", "find_fixed_point",
    "stability_verdict", "steady_state", "SteadyStart", "steady_start",
]
