"""Shaft trains as they are built: finite-element rotors on their own bearings, joined by couplings.

Public API
----------
Train, Rotor, ShaftElement, Disk, Support, Unbalance, Coupling, Material, TrainError
    The description (``model``); ``misaligned`` and ``bearing_moved`` move bearings.
assemble, Assembly
    Global Timoshenko finite-element matrices (``fe``).
static_state, StaticState, aligned_offsets, with_moves
    Newton solution on the nonlinear bearings; the aligned (catenary) bearing positions (``static``).
modes, campbell, critical_speeds, unbalance_response
    The linearised train (``linear``).
"""
from __future__ import annotations

from .fe import Assembly, assemble
from .linear import Modes, campbell, critical_speeds, modes, reduced_critical_speeds, unbalance_response
from .model import (
    STEEL,
    Coupling,
    Disk,
    Material,
    Rotor,
    ShaftElement,
    Support,
    Train,
    TrainError,
    Unbalance,
    bearing_moved,
    misaligned,
    uniform_elements,
)
from .static import StaticState, aligned_offsets, static_state, with_moves

__all__ = [
    "Assembly", "assemble", "Modes", "campbell", "critical_speeds", "reduced_critical_speeds", "modes", "unbalance_response", "STEEL",
    "Coupling", "Disk", "Material", "Rotor", "ShaftElement", "Support", "Train", "TrainError", "Unbalance",
    "bearing_moved", "misaligned", "uniform_elements", "StaticState", "aligned_offsets", "static_state",
    "with_moves",
]
