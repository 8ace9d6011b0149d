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

speed_sweep(plant, speeds_rpm, misalignment, unbalance, ...) -> SweepResult
misalignment_sweep(plant, speed_rpm, misalignments, unbalance, ...) -> SweepResult
    Bifurcation data (Poincaré X = x/c of a node, default node 3 horizontal),
    motion type, optional LLE, peak-to-peak and 1X/2X/3X at every point; points
    run in parallel through :func:`simulator.runner.run_tasks`.
amplitude_speed_curves(plant, speeds_rpm, misalignments, unbalance, ...) -> {Δ: SweepResult}
rotor_lyapunov(plant, speed_rpm, misalignment, unbalance, ...) -> LyapunovResult
    LLE of the rotor's once-per-revolution map (per revolution and per second).

Figures (:mod:`simulator.analysis.figures`, ``paper_figures``) and the CLI
(:mod:`simulator.analysis.cli`: ``bifurcate``, ``lyapunov``, ``figures``).
"""
from .lyapunov import FlowMapError, LyapunovResult, largest_lyapunov
from .motion import MotionType, classify_motion, detect_period, poincare_divergence_rate
from .sweeps import SweepResult, amplitude_speed_curves, misalignment_sweep, rotor_lyapunov, speed_sweep

__all__ = [
    "FlowMapError",
    "LyapunovResult",
    "largest_lyapunov",
    "MotionType",
    "classify_motion",
    "detect_period",
    "poincare_divergence_rate",
    "SweepResult",
    "speed_sweep",
    "misalignment_sweep",
    "amplitude_speed_curves",
    "rotor_lyapunov",
]
