"""Nonlinear analysis of the generator–exciter rotor (MODEL.md §8, issue 3).

Public API
----------
largest_lyapunov(flow_map, state0, *, n_intervals, ...) -> LyapunovResult
    Benettin's method on any flow map (renormalised neighbour or variational
    equations); LLE per interval (per revolution) and per second, with history.
classify_motion(poincare_points, lle=None, ...) -> MotionType(kind, period)
    period-n (n <= 16) / quasi-periodic / chaotic (/ unresolved), documented
    thresholds in :mod:`simulator.analysis.motion`.
detect_period, poincare_divergence_rate
    The two tests ``classify_motion`` is built from.
FlowMapError
    Raised by a flow map that cannot advance (contact, divergence).

The rotor-specific sweeps (bifurcation vs speed / misalignment, LLE vs speed,
amplitude–speed curves) live in :mod:`simulator.analysis.sweeps`; the figures in
:mod:`simulator.analysis.figures`; the CLI in :mod:`simulator.analysis.cli`.
"""
from .lyapunov import FlowMapError, LyapunovResult, largest_lyapunov
from .motion import MotionType, classify_motion, detect_period, poincare_divergence_rate

__all__ = [
    "FlowMapError",
    "LyapunovResult",
    "largest_lyapunov",
    "MotionType",
    "classify_motion",
    "detect_period",
    "poincare_divergence_rate",
]
