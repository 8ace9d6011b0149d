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
import sys
import types
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


class _Package(types.ModuleType):
    """This package's module type: the functions ``simulate`` and ``modal`` share their names with
    the submodules that define them, and importing such a submodule (``import
    rotordiag.simulator.simulate``) makes the import system set the package attribute to the
    *module* — after which ``rotordiag.simulator.simulate(...)`` would fail with "'module' object is
    not callable". A lazily exported name is therefore always set to the object it names. The modules
    stay reachable as ``from rotordiag.simulator.simulate import …`` and through ``sys.modules``
    (``import rotordiag.simulator.simulate as m`` gives the function, as the attribute does)."""

    def __setattr__(self, name: str, value: Any) -> None:
        if isinstance(value, types.ModuleType) and _LAZY.get(name) == "." + name and hasattr(value, name):
            value = getattr(value, name)
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
