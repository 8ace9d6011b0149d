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
from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .modal import ModalResult, bearing_coefficients, modal, static_equilibrium
    from .params import JOURNAL_NODES, MECHANISMS, Plant
    from .simulate import SimulationResult, simulate
    from .system import RotorSystem, build_system

# Loaded on first use (PEP 562): ``rotordiag diagnose`` and the service import command and
# dataset modules of this package without needing the numba kernels, scipy.optimize and
# the modal analysis (0.7 s of every CLI call before).
_LAZY = {
    "ModalResult": ".modal", "bearing_coefficients": ".modal", "modal": ".modal",
    "static_equilibrium": ".modal", "JOURNAL_NODES": ".params", "MECHANISMS": ".params", "Plant": ".params",
    "SimulationResult": ".simulate", "simulate": ".simulate", "RotorSystem": ".system",
    "build_system": ".system",
}

__all__ = [
    "Plant", "simulate", "SimulationResult", "build_system", "RotorSystem", "modal",
    "ModalResult", "bearing_coefficients", "static_equilibrium", "JOURNAL_NODES", "MECHANISMS",
]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
