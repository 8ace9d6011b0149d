"""Generator–exciter rotor with parallel coupling misalignment (MODEL.md).

Public API
----------
Plant
    Validated, immutable plant parameters (``Plant.default()``; TOML/JSON files).
simulate
    Steady-state response at one operating point → :class:`SimulationResult`.
build_system, RotorSystem
    The rotor at one operating point as a flow map in τ = Ωt (for continuation,
    Lyapunov exponents, sweeps).
modal, ModalResult, bearing_coefficients, static_equilibrium
    Linearised analysis about the static equilibrium.
"""
from .modal import ModalResult, bearing_coefficients, modal, static_equilibrium
from .params import JOURNAL_NODES, MECHANISMS, Plant
from .simulate import SimulationResult, simulate
from .system import RotorSystem, build_system

__all__ = [
    "Plant", "simulate", "SimulationResult", "build_system", "RotorSystem", "modal",
    "ModalResult", "bearing_coefficients", "static_equilibrium", "JOURNAL_NODES", "MECHANISMS",
]
